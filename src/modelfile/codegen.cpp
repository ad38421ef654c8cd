#include "src/modelfile/codegen.h"

#include <cctype>
#include <filesystem>
#include <set>
#include <vector>

#include "src/modelfile/codegen_functions.h"
#include "src/modelfile/cpp_names.h"
#include "src/modelfile/names.h"

namespace estlab::modelfile {
namespace {

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// "static constexpr std::array<type, n> name = {...};" with the inner braces
// an array of aggregates needs ({{{0, 1}}}).
std::string ArrayMember(int indent, const std::string& type, const std::string& name,
                        const std::vector<std::string>& items, bool aggregates = false) {
  // Appended, not "{" + Join(...): GCC 12 at -O3 warns falsely (-Wrestrict)
  // on a literal plus a temporary string.
  std::string list = aggregates ? "{{" : "{";
  list += Join(items);
  list += aggregates && !items.empty() ? "}}" : "}";
  if (items.empty()) list = "{}";
  return std::string(size_t(indent), ' ') + "static constexpr std::array<" + type + ", " +
         std::to_string(items.size()) + "> " + name + " = " + list + ";\n";
}

std::string Bool(bool b) { return b ? "true" : "false"; }

// A type name given for the model (model source, tests): an identifier that
// is no keyword, macro-like or reserved spelling, not a name the generated
// struct uses inside, and not a measurement's ("...Measurement").
bool UsableTypeName(const std::string& name) {
  static const std::set<std::string> kGenerated = {"T",
                                                   "P",
                                                   "S",
                                                   "Vec",
                                                   "Params",
                                                   "ParamsT",
                                                   "ParamSpec",
                                                   "OutputGroupSpec",
                                                   "Constraint",
                                                   "Measurements",
                                                   "Rhs",
                                                   "Step",
                                                   "Eval",
                                                   "Invariants",
                                                   "InvariantsHold",
                                                   "Eigen",
                                                   "std",
                                                   "estlab",
                                                   "ceres",
                                                   "model_fn",
                                                   "user_models"};
  const std::string tail = "Measurement";
  const bool measurement =
      name.size() >= tail.size() && name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
  return IsIdentifier(name) && !IsCppKeyword(name) && !LooksLikeMacro(name) &&
         !IsReservedSpelling(name) && kGenerated.count(name) == 0 && !measurement;
}

int StateIndex(const Expr& e) {
  return e.kind == ExprKind::kName && e.ref == NameRef::kState ? e.index : -1;
}
bool IsStepLength(const Expr& e) {
  return e.kind == ExprKind::kName && e.ref == NameRef::kStepLength;
}

// The rate state of state i: its equation is "j" ([rhs]) or "i + dt * j" /
// "i + j * dt" ([step]); -1 when none.
int RateStateOf(const ModelFile& m, int i) {
  const Expr& e = m.rhs[size_t(i)];
  int rate = -1;
  if (!m.discrete) {
    rate = StateIndex(e);
  } else if (e.kind == ExprKind::kAdd && StateIndex(e.args[0]) == i &&
             e.args[1].kind == ExprKind::kMultiply) {
    const Expr& product = e.args[1];
    if (IsStepLength(product.args[0])) rate = StateIndex(product.args[1]);
    if (IsStepLength(product.args[1])) rate = StateIndex(product.args[0]);
  }
  return rate != i ? rate : -1;
}

std::string StateTables(const ModelFile& m) {
  std::vector<std::string> names, units, angles, pairs;
  for (size_t i = 0; i < m.states.size(); ++i) {
    names.push_back(CppStringLiteral(m.states[i].name));
    units.push_back(CppStringLiteral(m.states[i].unit));
    angles.push_back(Bool(m.states[i].angle));
    if (const int rate = RateStateOf(m, int(i)); rate >= 0) {
      std::string pair = "{";
      pair += std::to_string(i);
      pair += ", ";
      pair += std::to_string(rate);
      pair += "}";
      pairs.push_back(pair);
    }
  }
  return ArrayMember(2, "const char*", "kStateNames", names) +
         "  // Unit of each state (\"\" = dimensionless), for axis labels and reports.\n" +
         ArrayMember(2, "const char*", "kStateUnits", units) +
         ArrayMember(2, "bool", "kAngleStates", angles) +
         ArrayMember(2, "std::pair<int, int>", "kPositionRatePairs", pairs, true);
}

std::string ParamTables(const ModelFile& m) {
  std::string members, specs;
  for (const ParamDecl& p : m.params) {
    const std::string member = MemberName(p.name);
    members += "    S " + member + " = S(" + FormatDouble(p.default_value) + ");\n";
    const std::string description = p.unit.empty() ? p.name : p.name + " [" + p.unit + "]";
    const char* constraint = p.constraint == Constraint::kPositive      ? "kPositive"
                             : p.constraint == Constraint::kNonNegative ? "kNonNegative"
                                                                        : "kAny";
    specs += "      {" + CppStringLiteral(p.name) + ", &Params::" + member + ", " +
             CppStringLiteral(description) + ", Constraint::" + constraint + "},\n";
  }
  const std::string table = "  static constexpr std::array<ParamSpec<Params>, " +
                            std::to_string(m.params.size()) + "> kParams = ";
  // Generic over the scalar so that `estlab tune --estimate-param` can
  // differentiate through the parameters (models/model_params.h).
  return "  template <class S = double>\n  struct ParamsT {\n" + members +
         "  };\n  using Params = ParamsT<>;\n" + table +
         (specs.empty() ? "{};\n" : "{{\n" + specs + "  }};\n");
}

// Struct names of the measurements: CamelCase + "Measurement" (numbered
// when two spell alike: "a-b" and "a_b"). No name the generator uses ends
// so, and the model's type ends in "Model": they cannot clash.
std::vector<std::string> MeasurementTypeNames(const ModelFile& m) {
  std::set<std::string> taken;
  std::vector<std::string> names;
  for (const MeasurementDecl& meas : m.measurements) {
    std::string camel = CamelCase(meas.name);  // "_1" -> "1": a letter first
    if (camel.empty() || std::isdigit(static_cast<unsigned char>(camel[0]))) camel = "M" + camel;
    const std::string base = camel + "Measurement";
    std::string name = base;
    for (int k = 2; taken.count(name); ++k) name = base + std::to_string(k);
    taken.insert(name);
    names.push_back(name);
  }
  return names;
}

// kGroups of a measurement with sensor groups, else "".
std::string GroupsMember(const MeasurementDecl& meas) {
  if (meas.groups.empty()) return "";
  std::vector<std::string> groups;
  for (const GroupDecl& g : meas.groups) {
    std::string item = "{";  // appended: see ArrayMember
    item += CppStringLiteral(g.name);
    item += ", " + std::to_string(g.first) + ", " + std::to_string(g.count) + "}";
    groups.push_back(item);
  }
  return ArrayMember(4, "OutputGroupSpec", "kGroups", groups, true);
}

std::string MeasurementStruct(const ModelFile& m, const MeasurementDecl& meas,
                              const std::string& type) {
  std::vector<std::string> outputs, angles;
  for (const OutputDecl& o : meas.outputs) {
    outputs.push_back(CppStringLiteral(o.name));
    angles.push_back(Bool(o.angle));
  }
  return "  struct " + type +
         " {\n    static constexpr const char* kName = " + CppStringLiteral(meas.name) +
         ";\n    static constexpr int kDim = " + std::to_string(meas.outputs.size()) + ";\n" +
         ArrayMember(4, "const char*", "kOutputs", outputs) +
         ArrayMember(4, "bool", "kAngleOutputs", angles) + GroupsMember(meas) +
         EvalFunction(m, meas, 4) + "  };\n";
}

// The file's name without its folder: the header (and so the model cache's
// key) must not depend on how the path was spelled (rt.model from its folder,
// R/rt.model from above).
std::string HeaderTop(const ModelFile& m, const std::string& guard) {
  const std::string file = std::filesystem::path(m.path).filename().string();
  return "// Generated by estlab's model-file front end (src/modelfile/codegen.h) from\n// " +
         CommentText(file.empty() ? "a model file" : file) +
         ". Do not edit: change the model file and regenerate.\n#ifndef " + guard + "\n#define " +
         guard +
         "\n\n#include <array>\n#include <cmath>\n#include <tuple>\n#include <utility>\n\n"
         "#include \"src/core/params.h\"\n#include \"src/core/types.h\"\n"
         "#include \"src/modelfile/model_functions.h\"\n\nnamespace estlab::user_models {\n\n";
}

// kInputNames and kInputUnits (for a model with inputs).
std::string InputNames(const ModelFile& m) {
  if (m.inputs.empty()) return "";
  std::string names, units;
  for (const InputDecl& input : m.inputs) {
    if (!names.empty()) names += ", ", units += ", ";
    names += CppStringLiteral(input.name);
    units += CppStringLiteral(input.unit);
  }
  const std::string array =
      "  static constexpr std::array<const char*, " + std::to_string(m.inputs.size()) + "> ";
  return array + "kInputNames = {" + names + "};\n" + array + "kInputUnits = {" + units + "};\n";
}

std::string ModelConstants(const ModelFile& m) {
  return "  static constexpr const char* kName = " + CppStringLiteral(m.name) +
         ";\n  static constexpr const char* kDescription = " + CppStringLiteral(m.description) +
         ";\n  static constexpr int kStateDim = " + std::to_string(m.states.size()) +
         ";\n  static constexpr int kInputDim = " + std::to_string(m.inputs.size()) + ";\n" +
         InputNames(m) + "  static constexpr bool kStiff = " + Bool(m.stiff) +
         ";\n  // true for a [step] model: Step(t, x, dt, u, p) gives x(t + dt), no Rhs.\n"
         "  static constexpr bool kDiscreteTime = " +
         Bool(m.discrete) + ";\n";
}

}  // namespace

std::string GenerateModelHeader(const ModelFile& m, const std::string& cpp_type_name) {
  if (!UsableTypeName(cpp_type_name))
    throw InputError("model file: '" + cpp_type_name + "' is not a usable C++ type name");
  if (m.rhs.size() != m.states.size() || m.states.empty())
    throw InputError("model file: incomplete model (use ParseModelFile)");
  const std::string guard = "ESTLAB_USER_MODELS_" + UpperSnakeCase(cpp_type_name) + "_H_";
  std::string out = HeaderTop(m, guard) + "struct " + cpp_type_name + " {\n" + ModelConstants(m) +
                    StateTables(m) + "\n" + ParamTables(m) + "\n" + DynamicsFunction(m, 2) + "\n";
  std::vector<std::string> invariant_names;
  for (const InvariantDecl& inv : m.invariants)
    invariant_names.push_back(CppStringLiteral(inv.name));
  out += ArrayMember(2, "const char*", "kInvariantNames", invariant_names) +
         InvariantFunctions(m, 2) + "\n";
  const std::vector<std::string> types = MeasurementTypeNames(m);
  for (size_t i = 0; i < m.measurements.size(); ++i)
    out += MeasurementStruct(m, m.measurements[i], types[i]);
  out += "  using Measurements = std::tuple<" + Join(types) + ">;\n};\n\n";
  return out + "}  // namespace estlab::user_models\n\n#endif  // " + guard + "\n";
}

// CamelCase + "Model": no name the generator uses (Vec, Params, Rhs,
// Measurements, ...) or a header's macro ends so ("rhs" once gave a struct
// Rhs holding a function Rhs).
std::string DefaultTypeName(const ModelFile& m) {
  const std::string name = CamelCase(m.name) + "Model";
  return UsableTypeName(name) ? name : "Model";
}

}  // namespace estlab::modelfile
