// The member functions of a generated model header (codegen.h), as C++ text
// indented for their place in the struct: Rhs or Step, each measurement's
// Eval, and InvariantsHold + Invariants. Internal to GenerateModelHeader.
//
// Usage:
//   out += DynamicsFunction(model, 2);          // "  template <class T> static ... Rhs(...)"
//   out += EvalFunction(model, model.measurements[0], 4);
#ifndef ESTLAB_MODELFILE_CODEGEN_FUNCTIONS_H_
#define ESTLAB_MODELFILE_CODEGEN_FUNCTIONS_H_

#include <string>

#include "src/modelfile/model_file.h"

namespace estlab::modelfile {

// Rhs(t, x, u, p) for [rhs] models, Step(t, x, dt, u, p) for [step] models.
std::string DynamicsFunction(const ModelFile& m, int indent);
std::string EvalFunction(const ModelFile& m, const MeasurementDecl& meas, int indent);
std::string InvariantFunctions(const ModelFile& m, int indent);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_CODEGEN_FUNCTIONS_H_
