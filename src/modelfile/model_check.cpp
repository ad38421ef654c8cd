#include "src/modelfile/model_check.h"

#include <algorithm>
#include <map>
#include <string>

#include "src/modelfile/names.h"

namespace estlab::modelfile {
namespace {

// Where an expression is used decides which names it may refer to.
enum class Context { kLet, kDynamics, kMeasurement, kInvariant };

struct Decl {
  NameRef ref;
  int index;
  SourcePos pos;
};

const char* KindName(NameRef ref) {
  switch (ref) {
    case NameRef::kState:
      return "a state";
    case NameRef::kParam:
      return "a parameter";
    case NameRef::kLet:
      return "a [let] value";
    case NameRef::kInput:
      return "an input";
    default:
      return "a name";
  }
}

bool IsObservation(Context c) { return c == Context::kMeasurement || c == Context::kInvariant; }
const char* ContextWord(Context c) {
  return c == Context::kMeasurement ? "measurements" : "invariants";
}

class Checker {
 public:
  Checker(RawModel* raw, std::vector<Diagnostic>* diagnostics)
      : raw_(*raw), m_(raw->model), diagnostics_(diagnostics) {}

  void Run() {
    CheckPresence();
    DeclareNames();
    AssembleEquations();
    for (size_t i = 0; i < m_.lets.size(); ++i) Resolve(&m_.lets[i].expr, Context::kLet, int(i));
    for (Expr& e : m_.rhs) Resolve(&e, Context::kDynamics, int(m_.lets.size()));
    for (MeasurementDecl& meas : m_.measurements)
      for (OutputDecl& out : meas.outputs) Resolve(&out.expr, Context::kMeasurement, 0);
    for (InvariantDecl& inv : m_.invariants) Resolve(&inv.expr, Context::kInvariant, 0);
    CheckZeroWhen();
  }

 private:
  void Report(SourcePos pos, std::string message) {
    diagnostics_->push_back(MakeDiagnostic(pos, std::move(message)));
  }

  void CheckPresence() {
    const SourcePos top{1, 1};
    if (!raw_.model_section) {
      Report(top, "missing [model] section with 'name = ...'");
    } else if (!raw_.has_name) {
      Report(*raw_.model_section, "missing model name (add 'name = ...' to [model])");
    }
    if (!raw_.states_section) {
      Report(top, "missing [states] section");
    } else if (m_.states.empty()) {
      Report(*raw_.states_section, "the model has no states");
    } else if (m_.states.size() > size_t(kMaxStates)) {
      Report(m_.states[kMaxStates].pos,
             "state '" + m_.states[kMaxStates].name + "' is one too many: a model has at most " +
                 std::to_string(kMaxStates) + " states (the filters' fixed gain storage)");
    }
    if (!raw_.has_measurement_section) Report(top, "the model has no [measurement NAME] section");
    if (raw_.rhs_section && raw_.step_section) {
      const SourcePos later = std::max(*raw_.rhs_section, *raw_.step_section, PosLess);
      Report(later,
             "a model has either [rhs] (continuous time) or [step] (discrete time), "
             "not both");
    } else if (!raw_.rhs_section && !raw_.step_section) {
      Report(top, "missing [rhs] (continuous time) or [step] (discrete time) section");
    }
  }

  static bool PosLess(SourcePos a, SourcePos b) {
    return a.line != b.line ? a.line < b.line : a.column < b.column;
  }

  // Fills decls_ in file order; later definitions of a name are reported.
  void DeclareNames() {
    std::vector<std::pair<std::string, Decl>> all;
    for (size_t i = 0; i < m_.states.size(); ++i)
      all.push_back({m_.states[i].name, {NameRef::kState, int(i), m_.states[i].pos}});
    for (size_t i = 0; i < m_.params.size(); ++i)
      all.push_back({m_.params[i].name, {NameRef::kParam, int(i), m_.params[i].pos}});
    for (size_t i = 0; i < m_.lets.size(); ++i)
      all.push_back({m_.lets[i].name, {NameRef::kLet, int(i), m_.lets[i].pos}});
    for (size_t i = 0; i < m_.inputs.size(); ++i)
      all.push_back({m_.inputs[i].name, {NameRef::kInput, int(i), m_.inputs[i].pos}});
    std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
      return PosLess(a.second.pos, b.second.pos);
    });
    for (const auto& [name, decl] : all) {
      if (const std::string why = ReservedMeaning(name); !why.empty()) {
        Report(decl.pos, Quoted(name) + " is reserved (" + why + ")");
        continue;
      }
      const auto [first, inserted] = decls_.insert({name, decl});
      if (!inserted) {
        Report(decl.pos, Quoted(name) + " is already defined as " + KindName(first->second.ref) +
                             " at line " + std::to_string(first->second.pos.line));
      }
    }
  }

  static std::string ReservedMeaning(const std::string& name) {
    if (name == "t") return "the time";
    if (name == "dt") return "the step length of [step] models";
    if (name == "pi") return "the constant pi";
    if (FindFunction(name)) return "a function";
    return "";
  }

  const Decl* Find(const std::string& name) const {
    const auto it = decls_.find(name);
    return it == decls_.end() ? nullptr : &it->second;
  }

  std::vector<std::string> StateNames() const {
    std::vector<std::string> names;
    for (const StateDecl& s : m_.states) names.push_back(s.name);
    return names;
  }

  const std::string& StateName(size_t i) const { return m_.states[i].name; }

  // m_.rhs from the [rhs] (or, without one, the [step]) equations.
  void AssembleEquations() {
    m_.discrete = !raw_.rhs_section && raw_.step_section;
    const std::vector<RawEquation>& equations =
        raw_.rhs_section ? raw_.rhs_equations : raw_.step_equations;
    const std::string section = raw_.rhs_section ? "[rhs]" : "[step]";
    std::vector<const RawEquation*> by_state(m_.states.size(), nullptr);
    for (const RawEquation& eq : equations) {
      const Decl* d = Find(eq.state);
      if (d == nullptr || d->ref != NameRef::kState) {
        Report(eq.pos, Quoted(eq.state) + " is " + (d ? KindName(d->ref) : "not a state") +
                           (d ? ", not a state" : DidYouMean(eq.state, StateNames())));
      } else if (const RawEquation* first = by_state[d->index]) {
        Report(eq.pos, "second equation for state " + Quoted(eq.state) + " (first at line " +
                           std::to_string(first->pos.line) + ")");
      } else {
        by_state[d->index] = &eq;
      }
    }
    for (size_t i = 0; i < m_.states.size(); ++i) {
      if (by_state[i] != nullptr) {
        m_.rhs.push_back(by_state[i]->expr);
        continue;
      }
      const Decl* d = Find(m_.states[i].name);
      const bool declared = d && d->ref == NameRef::kState && d->index == int(i) &&
                            IsIdentifier(StateName(i)) && !IsReservedSpelling(StateName(i));
      if ((raw_.rhs_section || raw_.step_section) && declared)
        Report(m_.states[i].pos,
               "state " + Quoted(m_.states[i].name) + " has no equation in " + section);
      Expr zero;
      zero.pos = m_.states[i].pos;
      m_.rhs.push_back(zero);
    }
  }

  void Resolve(Expr* e, Context context, int visible_lets) {
    ForEachName(*e, [&](Expr& name) { ResolveName(&name, context, visible_lets); });
  }

  void ResolveName(Expr* n, Context context, int visible_lets) {
    if (const Decl* d = Find(n->text)) return ResolveDeclared(n, *d, context, visible_lets);
    if (n->text == "t" && context != Context::kInvariant) {  // measurements: h(t, x, u)
      n->ref = NameRef::kTime;
    } else if (n->text == "t") {
      Report(n->pos, std::string(ContextWord(context)) + " cannot use the time 't'");
    } else if (n->text == "dt" && !m_.discrete) {
      Report(n->pos, "'dt' (the step length) exists only in [step] models");
    } else if (n->text == "dt" && IsObservation(context)) {
      Report(n->pos, std::string(ContextWord(context)) + " cannot use the step length 'dt'");
    } else if (n->text == "dt") {
      n->ref = NameRef::kStepLength;
    } else if (FindFunction(n->text)) {
      Report(n->pos, Quoted(n->text) + " is a function; call it as " + n->text + "(...)");
    } else {
      ReportUnknown(*n, context, visible_lets);
    }
  }

  void ResolveDeclared(Expr* n, const Decl& d, Context context, int visible_lets) {
    if ((IsObservation(context) && d.ref == NameRef::kLet) ||
        (context == Context::kInvariant && d.ref == NameRef::kInput)) {
      Report(n->pos, std::string(ContextWord(context)) + " cannot use " + KindName(d.ref) + " " +
                         Quoted(n->text) +
                         (context == Context::kMeasurement
                              ? " (they see states, parameters, inputs, the time and numbers)"
                              : " (they see only states, parameters and numbers)"));
      return;
    }
    if (context == Context::kLet && d.ref == NameRef::kLet && d.index >= visible_lets) {
      Report(n->pos, d.index == visible_lets
                         ? Quoted(n->text) + " is defined in terms of itself"
                         : Quoted(n->text) + " is used before it is defined (line " +
                               std::to_string(d.pos.line) + ")");
      return;
    }
    n->ref = d.ref;
    n->index = d.index;
  }

  // "Did you mean" for the first kMaxSuggestions unknown names only: each
  // search reads every declaration, and a file repeating an unknown name on
  // 20 000 lines took 41 s (issue 40 item 14).
  static constexpr int kMaxSuggestions = 100;

  void ReportUnknown(const Expr& n, Context context, int visible_lets) {
    std::vector<std::string> candidates;
    for (const auto& [name, d] : decls_) {
      if (suggestions_ >= kMaxSuggestions) break;
      const bool observation_ok = d.ref == NameRef::kState || d.ref == NameRef::kParam ||
                                  (context == Context::kMeasurement && d.ref == NameRef::kInput);
      const bool let_ok = d.ref != NameRef::kLet || d.index < visible_lets;
      if (IsObservation(context) ? observation_ok : let_ok) candidates.push_back(name);
    }
    ++suggestions_;
    const std::string suggestion = DidYouMean(n.text, candidates);
    std::string message = "unknown name " + Quoted(n.text) + suggestion;
    if (suggestion.empty() && m_.inputs.empty() && context != Context::kInvariant) {
      message += "; if " + Quoted(n.text) + " is the input, declare it with 'input = " + n.text +
                 "' in [model]";
    }
    Report(n.pos, message);
  }

  void CheckZeroWhen() {
    std::vector<std::string> candidates;
    for (const ParamDecl& p : m_.params) candidates.push_back(p.name);
    for (const InputDecl& input : m_.inputs) candidates.push_back(input.name);
    for (const NameUse& use : raw_.zero_when_uses) {
      const Decl* d = Find(use.name);
      if (d && (d->ref == NameRef::kParam || d->ref == NameRef::kInput)) continue;
      Report(use.pos, d ? Quoted(use.name) + " is " + KindName(d->ref) +
                              "; conserved-if-zero lists parameters and the input"
                        : "unknown parameter or input " + Quoted(use.name) +
                              " in conserved-if-zero" + DidYouMean(use.name, candidates));
    }
  }

  RawModel& raw_;
  ModelFile& m_;
  std::vector<Diagnostic>* diagnostics_;
  std::map<std::string, Decl> decls_;
  int suggestions_ = 0;  // "did you mean" searches so far
};

}  // namespace

void CheckModel(RawModel* raw, std::vector<Diagnostic>* diagnostics) {
  Checker(raw, diagnostics).Run();
}

}  // namespace estlab::modelfile
