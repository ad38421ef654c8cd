// Named model parameters: each model lists its parameters once, as a table of
// {name, member pointer, unit/description, constraint}, and the registry uses
// that table to apply "--param name=value" overrides and to print defaults.
// Also the other tables a model declares beside them: its measurements'
// sensor groups (OutputGroupSpec).
#ifndef ESTLAB_CORE_PARAMS_H_
#define ESTLAB_CORE_PARAMS_H_

#include <cmath>
#include <string>

#include "src/core/types.h"

namespace estlab {

// One sensor group of a measurement (a model's optional kGroups,
// models/model.h): outputs [first, first + count).
struct OutputGroupSpec {
  const char* name;
  int first;
  int count;
};

enum class Constraint { kPositive, kNonNegative, kAny };

template <class Params>
struct ParamSpec {
  const char* name;
  double Params::*member;
  const char* description;
  Constraint constraint;
};

inline const char* ConstraintText(Constraint c) {
  switch (c) {
    case Constraint::kPositive:
      return "> 0";
    case Constraint::kNonNegative:
      return ">= 0";
    case Constraint::kAny:
      return "any finite";
  }
  return "";
}

// Throws InputError when `value` violates `c`.
inline void CheckConstraint(const std::string& model, const char* name, double value,
                            Constraint c) {
  bool ok = std::isfinite(value);
  if (ok && c == Constraint::kPositive) ok = value > 0;
  if (ok && c == Constraint::kNonNegative) ok = value >= 0;
  if (!ok) {
    throw InputError("parameter '" + std::string(name) + "' of model '" + model + "' must be " +
                     ConstraintText(c) + ", got " + FormatNumber(value));
  }
}

}  // namespace estlab

#endif  // ESTLAB_CORE_PARAMS_H_
