// The value syntaxes of [states] and [params] lines:
//
//   theta = angle [rad]       state: optional 'angle', optional [unit]
//   w2 = 64 > 0 [1/s^2]       parameter: constant default, optional '> 0' or
//                             '>= 0', optional [unit]
//
// Usage:
//   StateDecl s{"theta"};
//   ReadStateValue(entry, &s, &problems);   // entry: the IniEntry of the line
#ifndef ESTLAB_MODELFILE_DECL_VALUES_H_
#define ESTLAB_MODELFILE_DECL_VALUES_H_

#include <vector>

#include "src/modelfile/diagnostic.h"
#include "src/modelfile/ini_sections.h"
#include "src/modelfile/model_file.h"

namespace estlab::modelfile {

// Sets state->angle and state->unit ("rad" for an angle without [unit]).
void ReadStateValue(const IniEntry& entry, StateDecl* state, std::vector<Diagnostic>* diagnostics);

// Sets param->default_value, constraint and unit. Reports a missing or
// non-constant default, a default that is not finite or breaks the
// constraint, and a constraint other than '> 0' / '>= 0'.
void ReadParamValue(const IniEntry& entry, ParamDecl* param, std::vector<Diagnostic>* diagnostics);

// Sets input->unit from one item "name [unit]" of an input list; returns the
// name part (trimmed; the caller checks it is one valid name).
std::string ReadInputValue(const IniEntry& entry, InputDecl* input,
                           std::vector<Diagnostic>* diagnostics);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_DECL_VALUES_H_
