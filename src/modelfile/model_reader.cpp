#include "src/modelfile/model_reader.h"

#include <algorithm>
#include <map>
#include <utility>

#include "src/modelfile/decl_values.h"
#include "src/modelfile/names.h"

namespace estlab::modelfile {
namespace {

const std::vector<std::string> kSectionKinds = {"model", "states", "params",      "let",
                                                "rhs",   "step",   "measurement", "invariant"};
const std::vector<std::string> kModelKeys = {"name", "description", "input", "stiff"};
constexpr const char* kZeroWhenKey = "conserved-if-zero";

std::string LineRef(SourcePos pos) { return "line " + std::to_string(pos.line); }

Expr Placeholder(SourcePos pos) {
  Expr e;
  e.pos = pos;
  e.text = "0";
  return e;
}

SourcePos Offset(SourcePos pos, size_t i) { return {pos.line, pos.column + int(i)}; }

// text[begin, end) without surrounding blanks, and the offset where it starts.
std::pair<size_t, std::string> TrimmedPiece(const std::string& text, size_t begin, size_t end) {
  while (begin < end && (text[begin] == ' ' || text[begin] == '\t')) ++begin;
  while (end > begin && (text[end - 1] == ' ' || text[end - 1] == '\t')) --end;
  return {begin, text.substr(begin, end - begin)};
}

class SectionReader {
 public:
  explicit SectionReader(std::vector<Diagnostic>* diagnostics) : diagnostics_(diagnostics) {}

  RawModel Read(const std::vector<IniSection>& sections) {
    for (const IniSection& s : sections) ReadSection(s);
    for (const auto& [group, pos] : group_names_) {
      if (measurement_names_.count(group) || grouped_.count(group))
        Report(pos, "sensor group " + Quoted(group) + " has the name of a measurement");
    }
    return std::move(raw_);
  }

 private:
  void Report(SourcePos pos, std::string message) {
    diagnostics_->push_back(MakeDiagnostic(pos, std::move(message)));
  }

  void ReadSection(const IniSection& s) {
    if (s.kind == "measurement") return ReadMeasurement(s);
    const bool known = s.kind == "invariant" || s.kind == "model" || s.kind == "states" ||
                       s.kind == "params" || s.kind == "let" || s.kind == "rhs" || s.kind == "step";
    if (!known)
      return Report(s.kind_pos,
                    "unknown section " + Quoted(s.kind) + DidYouMean(s.kind, kSectionKinds));
    if (!s.group.empty())
      return Report(s.group_pos, "only a [measurement NAME: GROUP] section takes a group");
    if (s.kind == "invariant") return ReadInvariantGroup(s);
    ReadSingleton(s);
  }

  // A section that appears once; a repeated one is reported and read on.
  void ReadSingleton(const IniSection& s) {
    const auto [first, inserted] = singletons_.insert({s.kind, s.kind_pos});
    if (!inserted) {
      Report(s.kind_pos,
             "duplicate section [" + s.kind + "] (first at " + LineRef(first->second) + ")");
    }
    if (!s.name.empty()) Report(s.name_pos, "[" + s.kind + "] takes no name");
    if (s.kind == "model") {
      if (!raw_.model_section) raw_.model_section = s.kind_pos;
      for (const IniEntry& e : s.entries) ReadModelKey(e);
    } else if (s.kind == "states") {
      if (!raw_.states_section) raw_.states_section = s.kind_pos;
      for (const IniEntry& e : s.entries) ReadState(e);
    } else if (s.kind == "params") {
      for (const IniEntry& e : s.entries) ReadParam(e);
    } else if (s.kind == "let") {
      for (const IniEntry& e : s.entries) ReadLet(e);
    } else {
      const bool step = s.kind == "step";
      std::optional<SourcePos>& section = step ? raw_.step_section : raw_.rhs_section;
      if (!section) section = s.kind_pos;
      for (const IniEntry& e : s.entries)
        (step ? raw_.step_equations : raw_.rhs_equations).push_back(ReadEquation(e));
    }
  }

  // A declared name (state, parameter, let, input, output, invariant).
  bool CheckName(const std::string& name, SourcePos pos) {
    if (!IsIdentifier(name)) {
      Report(pos, Quoted(name) +
                      " is not a valid name (letters, digits and '_', not starting with a digit)");
      return false;
    }
    if (IsReservedSpelling(name)) {
      Report(pos, "names ending in '_' or containing '__' are reserved for the generated C++: " +
                      Quoted(name));
      return false;
    }
    return true;
  }

  void ReadModelKey(const IniEntry& e) {
    const auto [first, inserted] = model_keys_.insert({e.key, e.key_pos});
    if (!inserted) {
      Report(e.key_pos,
             e.key == "input"
                 ? "a second 'input' line: list every input on one line, 'input = a [V], b'"
                 : "duplicate key " + Quoted(e.key) + " (first at " + LineRef(first->second) + ")");
      return;
    }
    if (e.key == "name") {
      ReadModelName(e);
    } else if (e.key == "description") {
      raw_.model.description = e.value;
    } else if (e.key == "input") {
      ReadInput(e);
    } else if (e.key == "stiff") {
      ReadStiff(e);
    } else {
      Report(e.key_pos, "unknown key " + Quoted(e.key) +
                            " in [model] (expected name, description, input or stiff)" +
                            DidYouMean(e.key, kModelKeys));
    }
  }

  void ReadModelName(const IniEntry& e) {
    raw_.has_name = true;
    if (e.value.empty()) {
      Report(e.value_pos, "empty model name");
    } else if (!IsDashedName(e.value)) {
      Report(e.value_pos, Quoted(e.value) +
                              " is not a valid model name (letters, digits, '_' and '-', "
                              "not starting with a digit or '-')");
    } else {
      raw_.model.name = e.value;
    }
  }

  // input = NAME [unit], NAME [unit], ...: each item one name and an
  // optional unit.
  void ReadInput(const IniEntry& e) {
    size_t begin = 0;
    while (begin <= e.value.size()) {
      const size_t comma = std::min(e.value.find(',', begin), e.value.size());
      const auto [offset, item] = TrimmedPiece(e.value, begin, comma);
      const SourcePos pos = Offset(e.value_pos, offset);
      if (item.empty()) {
        Report(pos, e.value.empty() ? "empty input name" : "empty item in the input list");
      } else {
        IniEntry piece = e;
        piece.value = item;
        piece.value_pos = pos;
        InputDecl input{"", "", pos};
        input.name = ReadInputValue(piece, &input, diagnostics_);
        if (input.name.find_first_of(" \t") != std::string::npos) {
          Report(pos, "one name per input, separated by commas: " + Quoted(input.name));
        } else if (!input.name.empty() && CheckName(input.name, pos)) {
          raw_.model.inputs.push_back(input);
        }
      }
      begin = comma + 1;
    }
  }

  void ReadStiff(const IniEntry& e) {
    if (e.value == "true" || e.value == "yes" || e.value == "1") {
      raw_.model.stiff = true;
    } else if (e.value == "false" || e.value == "no" || e.value == "0") {
      raw_.model.stiff = false;
    } else {
      Report(e.value_pos, "stiff must be true or false, got " + Quoted(e.value));
    }
  }

  void ReadState(const IniEntry& e) {
    StateDecl state{e.key, false, "", e.key_pos};
    CheckName(e.key, e.key_pos);
    ReadStateValue(e, &state, diagnostics_);
    raw_.model.states.push_back(std::move(state));
  }

  void ReadParam(const IniEntry& e) {
    ParamDecl param;
    param.name = e.key;
    param.pos = e.key_pos;
    CheckName(e.key, e.key_pos);
    ReadParamValue(e, &param, diagnostics_);
    raw_.model.params.push_back(std::move(param));
  }

  Expr ReadExpression(const std::string& text, SourcePos pos) {
    std::optional<Expr> e = ParseExpression(text, pos, diagnostics_);
    return e ? std::move(*e) : Placeholder(pos);
  }

  void ReadLet(const IniEntry& e) {
    CheckName(e.key, e.key_pos);
    raw_.model.lets.push_back({e.key, ReadExpression(e.value, e.value_pos), e.key_pos});
  }

  RawEquation ReadEquation(const IniEntry& e) {
    return {e.key, e.key_pos, ReadExpression(e.value, e.value_pos)};
  }

  // The name of a [measurement NAME] or [invariant NAME] section; false
  // when missing, malformed or repeated (the section is then skipped).
  bool CheckSectionName(const IniSection& s, std::map<std::string, SourcePos>* seen) {
    if (s.name.empty()) {
      Report(s.kind_pos, "[" + s.kind + "] needs a name, e.g. [" + s.kind +
                             (s.kind == "measurement" ? " angle]" : " energy]"));
      return false;
    }
    if (!IsDashedName(s.name)) {
      Report(s.name_pos,
             Quoted(s.name) + " is not a valid " + s.kind + " name (letters, digits, '_' and '-')");
      return false;
    }
    const auto [first, inserted] = seen->insert({s.name, s.name_pos});
    if (!inserted) {
      Report(s.name_pos, "duplicate " + s.kind + " " + Quoted(s.name) + " (first at " +
                             LineRef(first->second) + ")");
    }
    return inserted;
  }

  void ReadMeasurement(const IniSection& s) {
    raw_.has_measurement_section = true;
    if (!s.group.empty()) return ReadMeasurementGroup(s);
    if (!CheckSectionName(s, &measurement_names_)) return;
    if (grouped_.count(s.name)) {
      Report(s.name_pos, "measurement " + Quoted(s.name) + " has sensor groups ([measurement " +
                             s.name + ": GROUP]); give every section of it a group");
      return;
    }
    MeasurementDecl m{s.name, {}, s.kind_pos, {}};
    ReadOutputs(s, &m);
    raw_.model.measurements.push_back(std::move(m));
  }

  // [measurement NAME: GROUP]: the outputs of one sensor, appended to
  // measurement NAME as its group GROUP.
  void ReadMeasurementGroup(const IniSection& s) {
    if (s.name.empty() || !IsDashedName(s.name) || !IsDashedName(s.group)) {
      Report(s.name.empty() || !IsDashedName(s.name) ? s.name_pos : s.group_pos,
             "expected [measurement NAME: GROUP] with names of letters, digits, '_' and '-'");
      return;
    }
    if (measurement_names_.count(s.name)) {
      Report(s.name_pos, "measurement " + Quoted(s.name) + " is also given without a group (at " +
                             LineRef(measurement_names_.at(s.name)) +
                             "): give every section of it a group");
      return;
    }
    const auto [first, inserted] = group_names_.insert({s.group, s.group_pos});
    if (!inserted) {
      Report(s.group_pos, "duplicate sensor group " + Quoted(s.group) + " (first at " +
                              LineRef(first->second) + ")");
      return;
    }
    auto [it, fresh] = grouped_.insert({s.name, raw_.model.measurements.size()});
    if (fresh) raw_.model.measurements.push_back({s.name, {}, s.kind_pos, {}});
    MeasurementDecl& m = raw_.model.measurements[it->second];
    const int before = int(m.outputs.size());
    ReadOutputs(s, &m);
    m.groups.push_back({s.group, before, int(m.outputs.size()) - before, s.group_pos});
  }

  // The "output = expression" lines of a measurement section, appended to m.
  void ReadOutputs(const IniSection& s, MeasurementDecl* m) {
    for (const IniEntry& e : s.entries) {
      if (!CheckName(e.key, e.key_pos)) continue;
      bool repeated = false;
      for (const OutputDecl& o : m->outputs) {
        if (o.name != e.key) continue;
        Report(e.key_pos, "duplicate output " + Quoted(e.key) + " in measurement " +
                              Quoted(s.name) + " (first at " + LineRef(o.pos) + ")");
        repeated = true;
      }
      if (!repeated) m->outputs.push_back(ReadOutput(e));
    }
    if (s.entries.empty() && s.malformed_lines == 0) {
      Report(s.kind_pos, "measurement " + Quoted(s.name) +
                             (s.group.empty() ? "" : " group " + Quoted(s.group)) +
                             " has no outputs");
    }
  }

  // "name = expression [: angle]"
  OutputDecl ReadOutput(const IniEntry& e) {
    OutputDecl out{e.key, Placeholder(e.value_pos), false, e.key_pos};
    const size_t colon = e.value.find(':');
    if (colon != std::string::npos) {
      const auto [offset, flag] = TrimmedPiece(e.value, colon + 1, e.value.size());
      out.angle = flag == "angle";
      if (!out.angle) {
        Report(Offset(e.value_pos, flag.empty() ? colon : offset),
               "expected 'angle' after ':', got " + Quoted(flag) + DidYouMean(flag, {"angle"}));
      }
    }
    out.expr = ReadExpression(e.value.substr(0, colon), e.value_pos);
    return out;
  }

  void ReadInvariantGroup(const IniSection& s) {
    if (!CheckSectionName(s, &invariant_groups_)) return;
    const size_t first_invariant = raw_.model.invariants.size();
    std::vector<std::string> zero_when;
    bool has_list = false;
    for (const IniEntry& e : s.entries) {
      if (e.key == kZeroWhenKey) {
        if (has_list) Report(e.key_pos, "duplicate key '" + std::string(kZeroWhenKey) + "'");
        if (!has_list) zero_when = ReadZeroWhen(e);
        has_list = true;
      } else {
        ReadInvariant(e, s.name);
      }
    }
    if (raw_.model.invariants.size() == first_invariant && s.malformed_lines == 0 &&
        s.entries.size() == (has_list ? 1u : 0u))
      Report(s.kind_pos, "invariant section " + Quoted(s.name) + " defines no invariant");
    for (size_t i = first_invariant; i < raw_.model.invariants.size(); ++i)
      raw_.model.invariants[i].zero_when = zero_when;
  }

  void ReadInvariant(const IniEntry& e, const std::string& group) {
    if (!CheckName(e.key, e.key_pos)) return;
    const auto [first, inserted] = invariant_names_.insert({e.key, e.key_pos});
    if (!inserted) {
      Report(e.key_pos,
             "duplicate invariant " + Quoted(e.key) + " (first at " + LineRef(first->second) + ")");
      return;
    }
    InvariantDecl inv;
    inv.name = e.key;
    inv.expr = ReadExpression(e.value, e.value_pos);
    inv.group = group;
    inv.pos = e.key_pos;
    raw_.model.invariants.push_back(std::move(inv));
  }

  // "c, u": names checked against params and the input by the checker.
  std::vector<std::string> ReadZeroWhen(const IniEntry& e) {
    std::vector<std::string> names;
    if (e.value.empty()) {
      Report(e.value_pos, "empty conserved-if-zero list");
      return names;
    }
    for (size_t begin = 0;;) {
      const size_t comma = e.value.find(',', begin);
      const size_t end = comma == std::string::npos ? e.value.size() : comma;
      const auto [offset, item] = TrimmedPiece(e.value, begin, end);
      ReadZeroWhenItem(item, Offset(e.value_pos, offset), &names);
      if (comma == std::string::npos) break;
      begin = comma + 1;
    }
    return names;
  }

  void ReadZeroWhenItem(const std::string& item, SourcePos pos, std::vector<std::string>* names) {
    if (item.empty()) return Report(pos, "empty name in the conserved-if-zero list");
    if (!IsIdentifier(item)) return Report(pos, Quoted(item) + " is not a valid name");
    for (const std::string& n : *names) {
      if (n == item) return Report(pos, Quoted(item) + " is listed twice");
    }
    names->push_back(item);
    raw_.zero_when_uses.push_back({item, pos});
  }

  std::vector<Diagnostic>* diagnostics_;
  RawModel raw_;
  std::map<std::string, SourcePos> singletons_, model_keys_, measurement_names_, group_names_,
      invariant_groups_, invariant_names_;
  std::map<std::string, size_t> grouped_;  // a grouped measurement's index in measurements
};

}  // namespace

RawModel ReadModelSections(const std::vector<IniSection>& sections,
                           std::vector<Diagnostic>* diagnostics) {
  return SectionReader(diagnostics).Read(sections);
}

}  // namespace estlab::modelfile
