#include "src/modelfile/codegen_functions.h"

#include <set>
#include <vector>

#include "src/core/types.h"
#include "src/modelfile/cpp_names.h"
#include "src/modelfile/expression_cpp.h"

namespace estlab::modelfile {
namespace {

std::string Spaces(int n) { return std::string(size_t(n), ' '); }

// The lines of one function body and what they use.
class Body {
 public:
  // scalar_t: the function is a template over T (else all values are double).
  Body(const ModelFile& m, bool scalar_t)
      : m_(m), scalar_t_(scalar_t), states_used_(m.states.size()) {
    scope_.spell = [this](const Expr& n) { return Spell(n); };
    if (scalar_t) scope_.is_t = [this](const Expr& n) { return IsT(n); };
  }

  // e as C++, noting the names it uses.
  std::string Code(const Expr& e) {
    ForEachName(e, [this](const Expr& n) { Use(n); });
    return ToCpp(e, scope_, &std_functions_);
  }

  // e assigned to an element of a Vec<T, .>: double values become T(...).
  std::string TCode(const Expr& e) {
    const std::string code = Code(e);
    return scalar_t_ && !IsTValued(e, scope_) ? "T(" + code + ")" : code;
  }

  bool IsTExpr(const Expr& e) const { return IsTValued(e, scope_); }
  void SetLetTypes(std::vector<bool> let_is_t) { let_is_t_ = std::move(let_is_t); }

  void Add(std::string line) { lines_.push_back(std::move(line)); }

  bool uses_p = false, uses_u = false, uses_t = false, uses_dt = false;

  bool uses_x() const {
    for (const bool used : states_used_) {
      if (used) return true;
    }
    return false;
  }

  // "using std::...;", the state bindings, then the added lines.
  std::string Text(int indent) const {
    std::string out;
    for (const std::string& f : std_functions_) out += Spaces(indent) + "using std::" + f + ";\n";
    const char* type = scalar_t_ ? "const T& " : "const double ";
    for (size_t i = 0; i < m_.states.size(); ++i) {
      if (states_used_[i])
        out += Spaces(indent) + type + LocalName(m_.states[i].name) + " = x(" + std::to_string(i) +
               ");\n";
    }
    for (const std::string& line : lines_) out += Spaces(indent) + line + "\n";
    return out;
  }

 private:
  std::string Spell(const Expr& n) const {
    switch (n.ref) {
      case NameRef::kState:
        return LocalName(m_.states[n.index].name);
      case NameRef::kParam:
        return "p." + MemberName(m_.params[n.index].name);
      case NameRef::kLet:
        return LocalName(m_.lets[n.index].name);
      case NameRef::kInput:
        return m_.inputs.size() > 1 ? "u(" + std::to_string(n.index) + ")" : "u";
      case NameRef::kTime:
        return "t";
      case NameRef::kStepLength:
        return "dt";
      case NameRef::kUnresolved:
        break;
    }
    throw InputError("model file: unresolved name '" + n.text + "' (use ParseModelFile)");
  }

  bool IsT(const Expr& n) const {
    if (n.ref == NameRef::kState || n.ref == NameRef::kTime) return true;
    return n.ref == NameRef::kLet && size_t(n.index) < let_is_t_.size() && let_is_t_[n.index];
  }

  void Use(const Expr& n) {
    if (n.ref == NameRef::kState) states_used_[n.index] = true;
    uses_p |= n.ref == NameRef::kParam;
    uses_u |= n.ref == NameRef::kInput;
    uses_t |= n.ref == NameRef::kTime;
    uses_dt |= n.ref == NameRef::kStepLength;
  }

  const ModelFile& m_;
  bool scalar_t_;
  CppScope scope_;
  std::vector<bool> states_used_;
  std::vector<bool> let_is_t_;
  std::set<std::string> std_functions_;
  std::vector<std::string> lines_;
};

std::string Param(bool used, const std::string& type, const std::string& name) {
  return type + (used ? name : "/*" + name + "*/");
}

// The input as the model's functions take it (InputOf, models/model.h).
std::string InputType(const ModelFile& m) {
  return m.inputs.size() > 1 ? "const Vec<double, " + std::to_string(m.inputs.size()) + ">& "
                             : "double ";
}

// The lets that the equations need, directly or through other lets.
std::vector<bool> NeededLets(const ModelFile& m) {
  std::vector<bool> needed(m.lets.size(), false);
  auto mark = [&](const Expr& n) {
    if (n.ref == NameRef::kLet) needed[n.index] = true;
  };
  for (const Expr& e : m.rhs) ForEachName(e, mark);
  for (size_t i = m.lets.size(); i-- > 0;) {
    if (needed[i]) ForEachName(m.lets[i].expr, mark);
  }
  return needed;
}

// Adds the needed lets as "const T name = ...;" (or const double when the
// value does not depend on the state or t).
void AddLets(const ModelFile& m, Body* body) {
  const std::vector<bool> needed = NeededLets(m);
  std::vector<bool> let_is_t;
  for (size_t i = 0; i < m.lets.size(); ++i) {
    body->SetLetTypes(let_is_t);
    let_is_t.push_back(body->IsTExpr(m.lets[i].expr));
  }
  body->SetLetTypes(let_is_t);
  // A let that uses a parameter (directly or through another let) has the
  // parameters' scalar, double or T: `auto`.
  std::vector<bool> let_uses_p(m.lets.size(), false);
  for (size_t i = 0; i < m.lets.size(); ++i) {
    ForEachName(m.lets[i].expr, [&](const Expr& n) {
      if (n.ref == NameRef::kParam || (n.ref == NameRef::kLet && let_uses_p[n.index]))
        let_uses_p[i] = true;
    });
  }
  for (size_t i = 0; i < m.lets.size(); ++i) {
    if (!needed[i]) continue;
    const char* type = let_is_t[i] ? "const T " : let_uses_p[i] ? "const auto " : "const double ";
    body->Add(type + LocalName(m.lets[i].name) + " = " + body->Code(m.lets[i].expr) + ";");
  }
}

}  // namespace

std::string DynamicsFunction(const ModelFile& m, int indent) {
  const std::string n = std::to_string(m.states.size());
  const std::string vec = "Vec<T, " + n + ">";
  const std::string result = m.discrete ? "next" : "dx";
  Body body(m, true);
  AddLets(m, &body);
  body.Add(vec + " " + result + ";");
  for (size_t i = 0; i < m.rhs.size(); ++i)
    body.Add(result + "(" + std::to_string(i) + ") = " + body.TCode(m.rhs[i]) + ";");
  body.Add("return " + result + ";");
  std::string signature = "static " + vec + (m.discrete ? " Step(" : " Rhs(") +
                          Param(body.uses_t, "const T& ", "t") + ", " +
                          Param(body.uses_x(), "const " + vec + "& ", "x") + ", ";
  if (m.discrete) signature += Param(body.uses_dt, "double ", "dt") + ", ";
  signature += Param(body.uses_u, InputType(m), "u") + ", " + Param(body.uses_p, "const P& ", "p");
  return Spaces(indent) + "template <class T, class P>\n" + Spaces(indent) + signature + ") {\n" +
         body.Text(indent + 2) + Spaces(indent) + "}\n";
}

std::string EvalFunction(const ModelFile& m, const MeasurementDecl& meas, int indent) {
  const std::string vec = "Vec<T, " + std::to_string(meas.outputs.size()) + ">";
  Body body(m, true);
  body.Add(vec + " z;");
  for (size_t i = 0; i < meas.outputs.size(); ++i)
    body.Add("z(" + std::to_string(i) + ") = " + body.TCode(meas.outputs[i].expr) + ";");
  body.Add("return z;");
  const std::string x_type = "const Vec<T, " + std::to_string(m.states.size()) + ">& ";
  // Eval(x, u, p) when an output uses an input (a measurement h(x, u)),
  // Eval(t, x, u, p) when one uses the time (h(t, x, u)).
  const std::string t = body.uses_t ? "const T& t, " : "";
  const std::string u = body.uses_t   ? Param(body.uses_u, InputType(m), "u") + ", "
                        : body.uses_u ? InputType(m) + "u, "
                                      : "";
  return Spaces(indent) + "template <class T, class P>\n" + Spaces(indent) + "static " + vec +
         " Eval(" + t + Param(body.uses_x(), x_type, "x") + ", " + u +
         Param(body.uses_p, "const P& ", "p") + ") {\n" + body.Text(indent + 2) + Spaces(indent) +
         "}\n";
}

std::string InvariantFunctions(const ModelFile& m, int indent) {
  // InvariantsHold: every listed parameter / the input is exactly 0.
  std::vector<std::string> conditions;
  bool uses_p = false, uses_u = false;
  for (const InvariantDecl& inv : m.invariants) {
    for (const std::string& name : inv.zero_when) {
      std::string member, input;
      for (const ParamDecl& p : m.params)
        if (p.name == name) member = "p." + MemberName(p.name);
      for (size_t i = 0; i < m.inputs.size(); ++i)
        if (m.inputs[i].name == name)
          input = m.inputs.size() > 1 ? "u(" + std::to_string(i) + ")" : "u";
      const std::string condition = (input.empty() ? member : input) + " == 0.0";
      bool seen = false;
      for (const std::string& c : conditions) seen |= c == condition;
      if (seen) continue;
      conditions.push_back(condition);
      (input.empty() ? uses_p : uses_u) = true;
    }
  }
  std::string hold = m.invariants.empty() ? "false" : conditions.empty() ? "true" : "";
  for (const std::string& c : conditions) hold += (hold.empty() ? "" : " && ") + c;
  std::string out = Spaces(indent) + "static bool InvariantsHold(" +
                    Param(uses_p, "const Params& ", "p") + ", " + Param(uses_u, InputType(m), "u") +
                    ") { return " + hold + "; }\n";

  const std::string k = std::to_string(m.invariants.size());
  Body body(m, false);
  if (m.invariants.empty()) {
    body.Add("return Vec<double, 0>();");
  } else {
    body.Add("Vec<double, " + k + "> inv;");
    for (size_t i = 0; i < m.invariants.size(); ++i)
      body.Add("inv(" + std::to_string(i) + ") = " + body.Code(m.invariants[i].expr) + ";");
    body.Add("return inv;");
  }
  const std::string x_type = "const Vec<double, " + std::to_string(m.states.size()) + ">& ";
  return out + Spaces(indent) + "static Vec<double, " + k + "> Invariants(" +
         Param(body.uses_x(), x_type, "x") + ", " + Param(body.uses_p, "const Params& ", "p") +
         ") {\n" + body.Text(indent + 2) + Spaces(indent) + "}\n";
}

}  // namespace estlab::modelfile
