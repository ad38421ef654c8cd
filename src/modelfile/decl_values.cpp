#include "src/modelfile/decl_values.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>

#include "src/modelfile/expression.h"
#include "src/modelfile/names.h"

namespace estlab::modelfile {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

SourcePos Offset(SourcePos pos, size_t i) { return {pos.line, pos.column + int(i)}; }

// Splits "head [unit]" into head (returned, trimmed) and *unit; false with a
// diagnostic when the unit is malformed.
bool SplitUnit(const IniEntry& entry, std::string_view* head, std::optional<std::string>* unit,
               std::vector<Diagnostic>* diagnostics) {
  const std::string_view value = entry.value;
  const size_t open = value.find('[');
  *head = Trim(value.substr(0, open));
  if (open == std::string_view::npos) return true;
  const size_t close = value.find(']', open);
  if (close == std::string_view::npos) {
    diagnostics->push_back(
        MakeDiagnostic(Offset(entry.value_pos, open), "unterminated unit (missing ']')"));
    return false;
  }
  if (close + 1 < value.size()) {
    diagnostics->push_back(
        MakeDiagnostic(Offset(entry.value_pos, close + 1), "unexpected text after the unit"));
    return false;
  }
  *unit = std::string(Trim(value.substr(open + 1, close - open - 1)));
  return true;
}

// "> 0" or ">= 0" (any spelling of zero); nullopt otherwise.
std::optional<Constraint> ParseConstraint(std::string_view text) {
  Constraint c = Constraint::kPositive;
  if (text.substr(0, 2) == ">=") {
    c = Constraint::kNonNegative;
    text.remove_prefix(2);
  } else if (text.substr(0, 1) == ">") {
    text.remove_prefix(1);
  } else {
    return std::nullopt;
  }
  const std::string number(Trim(text));
  if (number.empty() || !(std::isdigit(static_cast<unsigned char>(number[0])) || number[0] == '.'))
    return std::nullopt;
  char* end = nullptr;
  const double zero = std::strtod(number.c_str(), &end);
  if (end != number.c_str() + number.size() || zero != 0.0) return std::nullopt;
  return c;
}

// The value of the constant default expression `text`; nullopt (with a
// diagnostic) when it does not parse, uses a name or is not finite.
std::optional<double> EvaluateDefault(std::string_view text, SourcePos pos,
                                      const std::string& param,
                                      std::vector<Diagnostic>* diagnostics) {
  const std::optional<Expr> e = ParseExpression(text, pos, diagnostics);
  if (!e) return std::nullopt;
  bool constant = true;
  ForEachName(*e, [&](const Expr& name) {
    diagnostics->push_back(MakeDiagnostic(
        name.pos, "parameter defaults must be constant (numbers, pi and functions), not " +
                      Quoted(name.text)));
    constant = false;
  });
  if (!constant) return std::nullopt;
  const double value = Evaluate(*e, [](const std::string&) { return 0.0; });
  if (!std::isfinite(value)) {
    diagnostics->push_back(
        MakeDiagnostic(pos, "the default of '" + param + "' is not a finite number"));
    return std::nullopt;
  }
  return value;
}

bool Satisfies(double value, Constraint c) {
  if (c == Constraint::kPositive) return value > 0;
  if (c == Constraint::kNonNegative) return value >= 0;
  return true;
}

}  // namespace

void ReadStateValue(const IniEntry& entry, StateDecl* state, std::vector<Diagnostic>* diagnostics) {
  std::string_view head;
  std::optional<std::string> unit;
  if (!SplitUnit(entry, &head, &unit, diagnostics)) return;
  if (head == "angle") {
    state->angle = true;
  } else if (!head.empty()) {
    diagnostics->push_back(
        MakeDiagnostic(entry.value_pos, "expected 'angle', '[unit]' or nothing after '=', got " +
                                            Quoted(head) + DidYouMean(head, {"angle"})));
  }
  state->unit = unit ? *unit : (state->angle ? "rad" : "");
}

std::string ReadInputValue(const IniEntry& entry, InputDecl* input,
                           std::vector<Diagnostic>* diagnostics) {
  std::string_view head;
  std::optional<std::string> unit;
  if (!SplitUnit(entry, &head, &unit, diagnostics)) return "";
  input->unit = unit.value_or("");
  return std::string(head);
}

void ReadParamValue(const IniEntry& entry, ParamDecl* param, std::vector<Diagnostic>* diagnostics) {
  std::string_view head;
  std::optional<std::string> unit;
  if (!SplitUnit(entry, &head, &unit, diagnostics)) return;
  param->unit = unit.value_or("");
  const size_t split = head.find_first_of("<>=!");
  const std::string_view default_text = Trim(head.substr(0, split));
  bool constraint_ok = true;
  if (split != std::string_view::npos) {
    const std::optional<Constraint> c = ParseConstraint(head.substr(split));
    constraint_ok = c.has_value();
    if (c) {
      param->constraint = *c;
    } else {
      diagnostics->push_back(MakeDiagnostic(
          Offset(entry.value_pos, split),
          "bad constraint " + Quoted(head.substr(split)) + ": expected '> 0', '>= 0' or nothing"));
    }
  }
  if (default_text.empty()) {
    diagnostics->push_back(
        MakeDiagnostic(entry.value_pos, "parameter '" + param->name + "' needs a default value"));
    return;
  }
  const std::optional<double> value =
      EvaluateDefault(default_text, entry.value_pos, param->name, diagnostics);
  if (!value) return;
  param->default_value = *value;
  if (constraint_ok && !Satisfies(*value, param->constraint)) {
    diagnostics->push_back(MakeDiagnostic(
        entry.value_pos, "the default " + FormatNumber(*value) + " of '" + param->name +
                             "' breaks its constraint " + ConstraintText(param->constraint)));
  }
}

}  // namespace estlab::modelfile
