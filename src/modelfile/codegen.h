// Generates the C++ header of a model file: one struct in
// namespace estlab::user_models of the same form as the built-in models
// (models/pendulum.h; contract in models/model.h), to be compiled into a
// shared library and loaded by estlab.
//
// Usage:
//   const ModelFile m = ParseModelFile(text, "pendulum.model");
//   const std::string header = GenerateModelHeader(m, DefaultTypeName(m));  // "PendulumFileModel"
//   // write it to pendulum_file.h; it includes "src/core/params.h",
//   // "src/core/types.h" and "src/modelfile/model_functions.h".
//
// What is generated (N states, M outputs per measurement):
//   kName, kDescription, kStateDim, kInputDim, kInputNames, kInputUnits, kStiff, kDiscreteTime,
//   kStateNames, kStateUnits, kAngleStates, kPositionRatePairs (state i whose
//   equation is exactly state j gives (i, j); in a [step] model the equation
//   i + dt * j or i + j * dt), Params (defaults printed so that they read
//   back exactly) and kParams ({name, member, "name [unit]", constraint}),
//   template <class T> Rhs(t, x, u, p)  (or Step(t, x, dt, u, p), see below),
//   kInvariantNames, InvariantsHold(p, u), Invariants(x, p) in double,
//   one struct per measurement (CamelCase of its name, made unique) with kName,
//   kDim, kOutputs, kAngleOutputs and template <class T> Eval(x, p), and
//   `using Measurements = std::tuple<...>`.
// Inside the functions each used state is bound as `const T& theta = x(0);`,
// each needed let as `const T name = ...;` (`const double` when it depends on
// parameters and the input only; lets no equation needs are left out),
// parameters are `p.name`, the input `u`, and expressions follow
// expression_cpp.h: same operations in the same order as written, so a model
// file that writes a built-in's formulas as the built-in does gives
// bit-identical results in double. Unused function parameters are commented
// out, so the header compiles with -Wall -Wextra -Werror. User names that
// would clash in C++ get a trailing '_' (cpp_names.h); the name strings in
// the tables stay as written. InvariantsHold is false for a model without
// invariants (as models/van_der_pol.h), true when no conserved-if-zero list
// is given, else the AND of "listed name == 0" over all lists.
//
// [step] (discrete-time) models get kDiscreteTime = true and a
// Step(t, x, dt, u, p) returning x at t + dt instead of Rhs: the
// DiscreteDynamics half of estlab::DynamicModel (models/model.h).
// WARNING: such a model runs with Integrator::kDiscrete only.
#ifndef ESTLAB_MODELFILE_CODEGEN_H_
#define ESTLAB_MODELFILE_CODEGEN_H_

#include <string>

#include "src/modelfile/model_file.h"

namespace estlab::modelfile {

// The header text. `cpp_type_name` is the struct's name; throws InputError
// when it is not a usable C++ identifier, or when `m` has unresolved names
// (it must come from ParseModelFile).
std::string GenerateModelHeader(const ModelFile& m, const std::string& cpp_type_name);

// CamelCase of the model name + "Model" ("pendulum-file" ->
// "PendulumFileModel"); "Model" when that is not a usable identifier.
std::string DefaultTypeName(const ModelFile& m);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_CODEGEN_H_
