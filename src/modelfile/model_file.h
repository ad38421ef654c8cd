// estlab's model-file language: a model written as an INI-shaped text file,
// parsed and checked here, then turned into a C++ model header by codegen.h.
// User reference of the language (sections, functions, every error): docs/model-language.md
//
//   # compound_pendulum.model
//   [model]
//   name = compound-pendulum          # letters, digits, '_' and '-'
//   description = rigid arm with joint friction, theta from upright
//   input = u                         # optional: inputs, 'a [V], b' for several
//   stiff = false                     # optional: true/false (yes/no, 1/0)
//
//   [states]
//   theta = angle [rad]               # 'angle': wrapped; '[unit]' optional
//   omega = [rad/s]                   # angle states default to [rad]
//
//   [params]
//   w2 = 64   > 0    [1/s^2]          # constant default, '> 0' / '>= 0' / none, unit
//   c  = 0.05 >= 0   [1/s]
//
//   [let]                             # optional, evaluated in order
//   restoring = w2 * sin(theta)
//
//   [rhs]                             # continuous time: dx/dt, one line per state
//   theta = omega
//   omega = restoring - c * omega + u
//
//   [measurement angle]               # one or more; output = expression [: angle]
//   theta = theta : angle
//
//   [measurement nav: imu]            # or sensor groups: one section per
//   a = omega^2                       # sensor, joined into the measurement
//   [measurement nav: camera]         # 'nav' (its own R block, tuned R, NIS
//   theta = theta : angle             # and study rate each); --measure nav
//                                     # or --measure imu,camera
//
//   [invariant energy]                # optional; each line is one invariant
//   energy = 0.5 * omega^2 + w2 * cos(theta)
//   conserved-if-zero = c, u          # optional: when these are 0 (default: always)
//
// A discrete-time model has a [step] section instead of [rhs] (x_next per
// state; 'dt' is the step length there and in [let]). Expressions: see
// expression.h. Names available
//   in [let]:               states, parameters, the input, t, earlier lets (+ dt in [step] models)
//   in [rhs] / [step]:      the same and every let
//   in measurements:        states, parameters, the inputs, t, numbers and pi (Eval(x, p),
//                           Eval(x, u, p) with an input, Eval(t, x, u, p) with t; no lets)
//   in invariants:          states, parameters, numbers and pi only (Invariants(x, p))
//   in parameter defaults:  numbers, pi and functions (e.g. 0.15 * 0.17^2 / 12)
// Sections may come in any order. Several [invariant GROUP] sections may be
// given; the model's invariants hold when every name listed in any group's
// conserved-if-zero is 0.
//
// Usage:
//   ModelFile m = ParseModelFile(text, "pendulum.model");  // throws ModelFileError
//   std::string header = GenerateModelHeader(m, "PendulumFile");  // codegen.h
#ifndef ESTLAB_MODELFILE_MODEL_FILE_H_
#define ESTLAB_MODELFILE_MODEL_FILE_H_

#include <optional>
#include <string>
#include <vector>

#include "src/core/params.h"
#include "src/modelfile/diagnostic.h"
#include "src/modelfile/expression.h"

namespace estlab::modelfile {

struct StateDecl {
  std::string name;
  bool angle = false;
  std::string unit;  // "rad" for an angle written without [unit]
  SourcePos pos;
};

struct InputDecl {
  std::string name;
  std::string unit;  // "" = none given
  SourcePos pos;
};

struct ParamDecl {
  std::string name;
  double default_value = 0.0;
  Constraint constraint = Constraint::kAny;
  std::string unit;
  SourcePos pos;
};

struct LetDecl {
  std::string name;
  Expr expr;
  SourcePos pos;
};

struct OutputDecl {
  std::string name;
  Expr expr;
  bool angle = false;
  SourcePos pos;
};

// A sensor group: outputs [first, first + count) of its measurement, from
// one [measurement NAME: GROUP] section.
struct GroupDecl {
  std::string name;
  int first = 0;
  int count = 0;
  SourcePos pos;
};

struct MeasurementDecl {
  std::string name;
  std::vector<OutputDecl> outputs;
  SourcePos pos;
  std::vector<GroupDecl> groups;  // empty: one sensor
};

struct InvariantDecl {
  std::string name;
  Expr expr;
  std::vector<std::string> zero_when;  // params and/or the input; empty = always
  std::string group;                   // the [invariant GROUP] it came from
  SourcePos pos;
};

// The most states a model may have: the filters keep their gains in fixed
// storage of this many rows (src/filters/filter.h, kMaxGainStates; a test
// checks that the two agree). `model check` refuses more.
inline constexpr int kMaxStates = 16;

struct ModelFile {
  std::string path;
  std::string name;
  std::string description;
  std::vector<InputDecl> inputs;  // in declaration order: u(0), u(1), ...
  bool stiff = false;
  bool discrete = false;  // [step] instead of [rhs]
  std::vector<StateDecl> states;
  std::vector<ParamDecl> params;
  std::vector<LetDecl> lets;
  std::vector<Expr> rhs;  // dx/dt ([rhs]) or x_next ([step]), in state order
  std::vector<MeasurementDecl> measurements;
  std::vector<InvariantDecl> invariants;
};

// Parses and checks a whole model file. Every name in the returned
// expressions is resolved (Expr::ref, Expr::index). Throws ModelFileError
// listing every problem found, as "PATH:LINE:COL: message" lines.
ModelFile ParseModelFile(const std::string& text, const std::string& path);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_MODEL_FILE_H_
