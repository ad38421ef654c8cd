// First pass over a model file's sections: reads every section into a
// RawModel (states, params, lets, equations, measurements, invariants) and
// reports what can be seen line by line: unknown or duplicate sections and
// keys, malformed names and values, expression syntax. Cross-references
// (which names exist, which states lack an equation) are the checker's job
// (model_check.h). Internal to ParseModelFile.
//
// Usage:
//   RawModel raw = ReadModelSections(SplitIniSections(text, &problems), &problems);
//   CheckModel(&raw, &problems);
#ifndef ESTLAB_MODELFILE_MODEL_READER_H_
#define ESTLAB_MODELFILE_MODEL_READER_H_

#include <optional>
#include <string>
#include <vector>

#include "src/modelfile/diagnostic.h"
#include "src/modelfile/ini_sections.h"
#include "src/modelfile/model_file.h"

namespace estlab::modelfile {

// "state = expression" in [rhs] or [step].
struct RawEquation {
  std::string state;
  SourcePos pos;
  Expr expr;  // a placeholder 0 when the expression did not parse
};

struct NameUse {
  std::string name;
  SourcePos pos;
};

struct RawModel {
  ModelFile model;                       // all but model.rhs and model.discrete
  bool has_name = false;                 // a 'name' key, valid or not
  bool has_measurement_section = false;  // a [measurement ...] header, valid or not
  std::optional<SourcePos> model_section, states_section, rhs_section, step_section;
  std::vector<RawEquation> rhs_equations, step_equations;
  std::vector<NameUse> zero_when_uses;  // the items of every conserved-if-zero list
};

RawModel ReadModelSections(const std::vector<IniSection>& sections,
                           std::vector<Diagnostic>* diagnostics);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_MODEL_READER_H_
