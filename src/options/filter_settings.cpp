#include "src/options/filter_settings.h"

#include <algorithm>
#include <cstdint>
#include <exception>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "src/core/parse.h"
#include "src/options/filter_flags.h"

namespace estlab {

const std::vector<FilterKey>& FilterKeyTable() {
  using K = FilterKey;
  // clang-format off
  static const std::vector<FilterKey> table = {
      {"model", nullptr, "model name (see 'estlab list')", K::kValue, false, true},
      {"measure", nullptr, "measurement name of the model, or its sensor groups, comma-separated (see 'estlab list')", K::kValue, false, true},
      {"filter", "ukf", "kf | ekf | iekf | ukf | ckf | ghkf | pf", K::kValue, false, true},
      {"param", nullptr, "model parameter name=value (repeatable)", K::kRepeatable, false, true},
      {"t0", nullptr, "time of the prior (default: the first row's time)", K::kValue, false, true},
      {"integrator", "rk4", "process model: rk4 | euler | semi-implicit-euler | cvodes | discrete (the default and only choice for a discrete-time model)"},
      {"substeps", "1", "fixed-step integrators: steps per measurement interval"},
      {"method", "default", "CVODES method: bdf | adams | default"},
      {"rtol", "1e-8", "CVODES relative tolerance"},
      {"atol", "1e-10", "CVODES absolute tolerance"},
      {"max-steps", "500000", "CVODES maximum steps per interval"},
      {"x0", nullptr,
       "prior mean name=value,... (others 0), or first-sample: each data file's first "
       "measured states",
       K::kRepeatable, false, true},
      {"p0-diag", nullptr, "prior covariance diagonal (default 1 for every state)", K::kValue, false, true},
      {"p0", nullptr, "prior covariance matrix \"a,b;c,d\"", K::kValue, false, true},
      {"q-diag", nullptr, "process noise Q diagonal (per step)", K::kValue, true, true},
      {"q", nullptr, "process noise Q matrix \"a,b;c,d\" (per step)", K::kValue, true, true},
      {"q-white-accel", nullptr, "Q = qc [[dt^3/3, dt^2/2], [dt^2/2, dt]] per (position, rate) pair, dt of each step", K::kValue, true, true},
      {"r-diag", nullptr, "measurement noise R diagonal, or one sensor group's: GROUP=a,b (repeatable, one per group)", K::kRepeatable, true, true},
      {"r", nullptr, "measurement noise R matrix, or one sensor group's: GROUP=\"a,b;c,d\" (repeatable)", K::kRepeatable, true, true},
      {"linearize-at", nullptr, "kf: operating point name=value,... (default: the prior mean)", K::kRepeatable},
      {"iterations", "1", "ekf: update iterations (> 1 = iterated EKF; 'iekf' sets 3 by default)"},
      {"alpha", "1e-3", "ukf: spread alpha"},
      {"beta", "2", "ukf: prior knowledge beta"},
      {"kappa", "0", "ukf: secondary scaling kappa"},
      {"gh-order", "3", "ghkf: Gauss-Hermite order p (p^n points)"},
      {"sigma-update", "redraw", "propagate (reuse propagated points) | redraw (new points from x-, P-)"},
      {"jitter", "0", "sigma-point: add jitter*I to P, P- and S (paper 003: 1e-3)"},
      {"adapt", nullptr, "adaptive sigma-point filter: sage-husa | innovation-matching"},
      {"adapt-what", "r", "q | r | qr"},
      {"forgetting", "0.97", "sage-husa forgetting factor b"},
      {"window", "30", "innovation-matching window N"},
      {"particles", "1000", "pf: number of particles"},
      {"resample", "systematic", "pf: multinomial | systematic | stratified | residual"},
      {"ess-threshold", "0.5", "pf: resample when ESS < threshold * N (1 = every step)"},
      {"seed", "1", "random seed (pf: the particles; tune: the multi-start points)", K::kValue, false, true},
      {"input", "0", "constant input, for data without the input's column (else that column, held between samples); a model with several inputs takes one value each, comma-separated", K::kValue, false, true},
      {"input-hold", "zoh", "how the input is held between samples: zoh (u_k over [t_k, t_k+1)) | linear (the line from u_k to u_k+1); every process model, CVODES included, stops at the samples", K::kValue, false, true},
      {"column", nullptr, "map a column: ours=[a*]theirs[+-b] (ours = a theirs + b; a, b numbers or pi), e.g. z_theta=angle_rad, theta=angle-pi, theta=0.0174533*angle_deg", K::kRepeatable, false, true},
      {"full-cov", nullptr, "write every covariance entry, not only the diagonal", K::kFlag, false, true},
  };
  // clang-format on
  return table;
}

const FilterKey* FindFilterKey(const std::string& key, const std::string& noise_prefix) {
  // No string is built: every spec looks up each key's default here.
  const bool prefixed = key.compare(0, noise_prefix.size(), noise_prefix) == 0;
  const std::string_view rest =
      std::string_view(key).substr(std::min(noise_prefix.size(), key.size()));
  for (const FilterKey& k : FilterKeyTable())
    if (k.noise ? prefixed && rest == k.name : key == k.name) return &k;
  return nullptr;
}

RunNeeds RunNeedsOf(const FilterSettings& settings, bool smooth) {
  RunNeeds needs;
  if (settings.Given("measure")) needs.measurement = settings.Get("measure");
  try {
    needs.filter = int(DefaultFilterOptions(ParseFilterKind(settings.Get("filter"))).index());
  } catch (const InputError&) {
    needs.filter = -1;
  }
  needs.adapt = settings.Given("adapt");
  needs.smooth = smooth;
  return needs;
}

std::string FilterSettings::Get(const std::string& key) const {
  const auto it = values_.find(key);
  if (it != values_.end() && !it->second.empty()) return it->second.back();
  const FilterKey* k = FindFilterKey(key, prefix_);
  if (k == nullptr || k->default_text == nullptr) throw KeyError(key, "is required");
  return k->default_text;
}

std::vector<std::string> FilterSettings::GetAll(const std::string& key) const {
  const auto it = values_.find(key);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

namespace {

// "--KEY: msg" / "KEY: msg" -> "msg" (the parsers name the option they were given).
std::string StripKey(const std::string& message, const std::string& key) {
  for (const std::string& p : {"--" + key + ": ", key + ": ", "--" + key + " "})
    if (message.compare(0, p.size(), p) == 0) return message.substr(p.size());
  return message;
}

// Runs fn(), turning an InputError into a KeyError of `key`.
template <class Fn>
auto ForKey(const std::string& key, Fn&& fn) {
  try {
    return fn();
  } catch (const KeyError&) {
    throw;
  } catch (const InputError& e) {
    throw KeyError(key, StripKey(e.what(), key));
  }
}

class Reader {
 public:
  Reader(const FilterSettings& s) : s_(s) {}
  bool Given(const std::string& key) const { return s_.Given(key); }
  std::string Text(const std::string& key) const {
    return ForKey(key, [&] { return s_.Get(key); });
  }
  double Number(const std::string& key) const {
    return ForKey(key, [&] { return ParseNumber(s_.Get(key), key); });
  }
  long Integer(const std::string& key, long min_value) const {
    return ForKey(key, [&] { return ParseInteger(s_.Get(key), key, min_value); });
  }
  int Count(const std::string& key, int min_value, int max_value) const {
    return ForKey(key, [&] { return ParseCount(s_.Get(key), key, min_value, max_value); });
  }
  std::vector<std::string> All(const std::string& key) const { return s_.GetAll(key); }
  std::vector<std::pair<std::string, double>> Assignments(const std::string& key) const {
    return ForKey(key, [&] { return ParseAssignments(s_.GetAll(key), key); });
  }
  // An n x n matrix from KEY-diag (a list) or KEY (a matrix), at most one.
  std::vector<double> DiagOrMatrix(const std::string& diag_key, const std::string& mat_key, int n,
                                   const std::string& what) const {
    if (Given(diag_key) && Given(mat_key))
      throw KeyError(mat_key, "give only one of --" + diag_key + " and --" + mat_key);
    std::vector<double> out(n * n, 0.0);
    if (Given(diag_key)) {
      ForKey(diag_key, [&] {
        const auto d = ParseList(s_.Get(diag_key), diag_key);
        RequireLength(d, n, diag_key, what);
        for (int i = 0; i < n; ++i) out[i * n + i] = d[i];
        return 0;
      });
    } else if (Given(mat_key)) {
      out = ForKey(mat_key, [&] { return ParseMatrix(s_.Get(mat_key), n, mat_key); });
    }
    return out;
  }

 private:
  const FilterSettings& s_;
};

// A discrete-time model's process model is its own map: 'discrete' is its
// default, and the only integrator either kind of model rejects is named.
void ReadTransition(const Reader& r, const ModelEntry& model, TransitionOptions* t) {
  t->integrator = model.discrete_time && !r.Given("integrator")
                      ? Integrator::kDiscrete
                      : ForKey("integrator", [&] { return ParseIntegrator(r.Text("integrator")); });
  const std::string error = model.CheckIntegrator(t->integrator);
  if (!error.empty()) throw KeyError("integrator", error);
  t->substeps = r.Count("substeps", 0, 100000);
  t->input_hold = ForKey("input-hold", [&] { return ParseInputHold(r.Text("input-hold")); });
  const std::string method = r.Text("method");
  if (method == "bdf")
    t->method = CvodesMethod::kBdf;
  else if (method == "adams")
    t->method = CvodesMethod::kAdams;
  else if (method != "default")
    throw KeyError("method", "unknown CVODES method '" + method + "' (bdf, adams, default)");
  t->rtol = r.Number("rtol");
  t->atol = r.Number("atol");
  t->max_steps = r.Integer("max-steps", 0);
}

// Q (one of q-diag, q, q-white-accel) and R (one of r-diag, r).
// R of one sensor group from "GROUP=values" of --KEY (a list for r-diag, a
// matrix for r) into its block of spec->r (m x m).
void ReadGroupR(const std::string& key, bool diag, const std::string& text,
                const MeasurementDesc& meas, std::vector<bool>* seen, FilterSpec* spec) {
  const size_t eq = text.find('=');
  const std::string group = Trim(text.substr(0, eq)), values = text.substr(eq + 1);
  const OutputGroup* g = meas.FindGroup(group);
  if (g == nullptr) {
    std::string known;
    for (const OutputGroup& o : meas.groups) known += (known.empty() ? "" : ", ") + o.name;
    throw KeyError(key, "unknown sensor group '" + group + "'" +
                            (known.empty() ? " (measurement '" + meas.name + "' has none)"
                                           : " (groups of " + meas.name + ": " + known + ")"));
  }
  const size_t index = size_t(g - meas.groups.data());
  if ((*seen)[index]) throw KeyError(key, "sensor group '" + group + "' is given twice");
  (*seen)[index] = true;
  const int m = int(meas.outputs.size()), c = g->count;
  std::vector<double> block(size_t(c * c), 0.0);
  ForKey(key, [&] {
    if (diag) {
      const auto d = ParseList(values, key);
      RequireLength(d, size_t(c), key, "one per output of group '" + group + "'");
      for (int i = 0; i < c; ++i) block[size_t(i * c + i)] = d[size_t(i)];
    } else {
      block = ParseMatrix(values, c, key);
    }
    return cli::CheckCovariance(block, c, "R of group '" + group + "'", false), 0;
  });
  for (int i = 0; i < c; ++i)
    for (int j = 0; j < c; ++j)
      spec->r[size_t((g->first + i) * m + g->first + j)] = block[size_t(i * c + j)];
}

// R (m x m): one of --r-diag, --r for all outputs, or a block per sensor
// group ("GROUP=values", each group once; 0 between groups).
void ReadR(const Reader& r, const std::string& np, const MeasurementDesc& meas, FilterSpec* spec) {
  const std::string rd = np + "r-diag", rm = np + "r";
  const std::vector<std::string> diags = r.All(rd), mats = r.All(rm);
  bool grouped = false;
  for (const auto* list : {&diags, &mats})
    for (const std::string& t : *list) grouped = grouped || t.find('=') != std::string::npos;
  const int m = int(meas.outputs.size());
  if (!grouped) {
    if (diags.empty() == mats.empty())  // neither, or both
      throw KeyError(rd, "give exactly one of --" + rd + ", --" + rm + " (measurement noise R)");
    if (diags.size() + mats.size() > 1) {
      throw KeyError(diags.empty() ? rm : rd,
                     meas.groups.empty() ? "is given more than once"
                                         : "is given more than once (once per sensor group "
                                           "takes GROUP=values)");
    }
    spec->r = r.DiagOrMatrix(rd, rm, m, "one per output of '" + meas.name + "'");
    const std::string key = r.Given(rd) ? rd : rm;
    ForKey(key, [&] { return cli::CheckCovariance(spec->r, m, "R", false), 0; });
    return;
  }
  spec->r.assign(size_t(m * m), 0.0);
  std::vector<bool> seen(meas.groups.size(), false);
  for (const bool diag : {true, false}) {
    const std::string& key = diag ? rd : rm;
    for (const std::string& text : diag ? diags : mats) {
      if (text.find('=') == std::string::npos)
        throw KeyError(key, "give R for all outputs or per sensor group (GROUP=values), not both");
      ReadGroupR(key, diag, text, meas, &seen, spec);
    }
  }
  for (size_t i = 0; i < seen.size(); ++i)
    if (!seen[i])
      throw KeyError(diags.empty() ? rm : rd,
                     "no R for sensor group '" + meas.groups[i].name + "'");
}

void ReadNoise(const Reader& r, const std::string& np, int n, const MeasurementDesc& meas,
               FilterSpec* spec) {
  const std::string qd = np + "q-diag", qm = np + "q", qw = np + "q-white-accel";
  const int q_given = int(r.Given(qd)) + int(r.Given(qm)) + int(r.Given(qw));
  if (q_given != 1)
    throw KeyError(
        qd, "give exactly one of --" + qd + ", --" + qm + ", --" + qw + " (process noise Q)");
  if (r.Given(qw)) {
    spec->q_white_accel = true;
    spec->qc = r.Number(qw);
    if (spec->qc < 0) throw KeyError(qw, "must be >= 0, got " + FormatNumber(spec->qc));
  } else {
    const std::string key = r.Given(qd) ? qd : qm;
    spec->q = r.DiagOrMatrix(qd, qm, n, "one per state");
    ForKey(key, [&] { return cli::CheckCovariance(spec->q, n, "Q", true), 0; });
  }
  ReadR(r, np, meas, spec);
}

// A seed: a non-negative 64-bit integer, all digits.
uint64_t ParseSeed(const std::string& text) {
  if (text.empty() || text.size() > 20 || text.find_first_not_of("0123456789") != std::string::npos)
    throw InputError("expected a non-negative integer, got '" + text + "'");
  try {
    return std::stoull(text);
  } catch (const std::exception&) {
    throw InputError("'" + text + "' does not fit in 64 bits");
  }
}

// An IsValid message "key: what" as the KeyError of that key.
[[noreturn]] void ThrowKeyed(const std::string& error) {
  const auto colon = error.find(": ");
  if (colon == std::string::npos) throw KeyError("filter", error);
  throw KeyError(error.substr(0, colon), error.substr(colon + 2));
}

void ReadAdapt(const Reader& r, AdaptSpec* adapt) {
  if (!r.Given("adapt")) return;
  adapt->rule = r.Text("adapt");
  const std::string what = r.Text("adapt-what");
  if (what != "q" && what != "r" && what != "qr")
    throw KeyError("adapt-what", "expected q, r or qr, got '" + what + "'");
  adapt->adapt_q = what.find('q') != std::string::npos;
  adapt->adapt_r = what.find('r') != std::string::npos;
  adapt->forgetting = r.Number("forgetting");
  adapt->window = r.Count("window", 0, 100000000);
}

// The options of every kind from the settings. Each is checked with its
// own IsValid: a bad value of an option the chosen filter does not use is
// still an error (the user may think it applies).
struct KindSettings {
  KfOptions kf;
  EkfOptions ekf;
  SigmaPointOptions sigma;
  ParticleOptions pf;
};

KindSettings ReadKindSettings(const Reader& r, const std::string& filter_name) {
  KindSettings k;
  k.ekf.iterations = r.Count("iterations", 0, 100000);
  if (filter_name == "iekf" && !r.Given("iterations")) k.ekf.iterations = 3;
  k.sigma.alpha = r.Number("alpha");
  k.sigma.beta = r.Number("beta");
  k.sigma.kappa = r.Number("kappa");
  k.sigma.gh_order = r.Count("gh-order", 0, 100000);
  const std::string upd = r.Text("sigma-update");
  if (upd != "propagate" && upd != "redraw")
    throw KeyError("sigma-update", "expected propagate or redraw, got '" + upd + "'");
  k.sigma.update =
      upd == "redraw" ? SigmaPointOptions::Update::kRedraw : SigmaPointOptions::Update::kPropagate;
  k.sigma.jitter = r.Number("jitter");
  k.pf.num_particles = r.Count("particles", 1, 10000000);  // ParticleOptions::IsValid's range
  const std::string resample = r.Text("resample");
  k.pf.resample = ForKey("resample", [&] { return ParseResampleScheme(resample); });
  k.pf.ess_threshold = r.Number("ess-threshold");
  k.pf.seed = ForKey("seed", [&] { return ParseSeed(r.Text("seed")); });
  return k;
}

// The constant input: one value per model input (a single 0 for any model
// means none was asked; empty then).
std::vector<double> ReadConstantInput(const Reader& r, const ModelEntry& model) {
  const std::vector<double> values =
      ForKey("input", [&] { return ParseList(r.Text("input"), "input"); });
  const bool zero = values.size() == 1 && values[0] == 0.0;
  if (!model.has_input()) {
    if (!zero) throw KeyError("input", "model '" + model.name + "' has no input");
    return {};
  }
  if (zero) return {};
  if (values.size() != model.inputs.size())
    throw KeyError("input", std::to_string(values.size()) + " value(s) for model '" + model.name +
                                "' with " + std::to_string(model.inputs.size()) + " inputs");
  return values;
}

// spec->filter from the settings: the chosen kind's options (filter_kinds.h).
void ReadFilterKind(const Reader& r, const ModelEntry& model, FilterSpec* spec) {
  const std::string name = r.Text("filter");
  const FilterKind kind = ForKey("filter", [&] { return ParseFilterKind(name); });
  KindSettings k = ReadKindSettings(r, name);
  if (r.Given("linearize-at")) {
    k.kf.operating_point = ForKey("linearize-at", [&] {
      return model.ResolveState(r.Assignments("linearize-at"), "linearize-at");
    });
  }
  k.kf.operating_input = spec->input;
  // Every kind's values on their own, then the chosen kind in n dimensions.
  std::string error;
  if (!k.kf.IsValid(&error) || !k.ekf.IsValid(&error) || !k.sigma.IsValid(&error) ||
      !k.pf.IsValid(&error))
    ThrowKeyed(error);
  spec->filter = DefaultFilterOptions(kind);
  std::visit(
      [&](auto& o) {
        using O = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<O, KfOptions>) o = k.kf;
        if constexpr (std::is_same_v<O, EkfOptions>) o = k.ekf;
        if constexpr (std::is_same_v<O, ParticleOptions>) o = k.pf;
        if constexpr (std::is_same_v<O, SigmaPointOptions>) {
          const SigmaRule rule = o.rule;  // the kind's
          o = k.sigma;
          o.rule = rule;
        }
      },
      spec->filter);
  const int n = int(model.states.size());
  if (!std::visit([&](const auto& o) { return o.IsValidFor(n, &error); }, spec->filter))
    ThrowKeyed(error);
}

}  // namespace

uint64_t SeedOf(const FilterSettings& settings) {
  return ForKey("seed", [&] { return ParseSeed(settings.Get("seed")); });
}

FilterSpec BuildFilterSpec(const FilterSettings& settings, const ModelEntry& model) {
  const Reader r(settings);
  FilterSpec spec;
  const int n = int(model.states.size());
  const MeasurementDesc& meas = ForKey("measure", [&]() -> const MeasurementDesc& {
    return model.FindMeasurement(r.Text("measure"));
  });
  spec.measurement = meas.name;  // "imu,gps" names the measurement with those groups
  spec.params = ForKey("param", [&] { return model.ResolveParams(r.Assignments("param")); });
  ReadTransition(r, model, &spec.transition);
  if (r.Given("t0")) {
    spec.has_t0 = true;
    spec.t0 = r.Number("t0");
  }
  const std::vector<std::string> x0_text = settings.GetAll("x0");
  if (x0_text.size() == 1 && Trim(x0_text[0]) == "first-sample") {
    spec.x0_first_sample = true;
    spec.x0.assign(n, 0.0);
    ForKey("x0", [&] {
      bool any = false;
      for (const std::string& o : meas.outputs)
        for (const std::string& s : model.states) any = any || o == s;
      if (!any)
        throw InputError("first-sample: measurement '" + meas.name +
                         "' has no output named like a state");
      return 0;
    });
  } else {
    spec.x0 = ForKey("x0", [&] { return model.ResolveState(r.Assignments("x0"), "x0"); });
  }
  if (r.Given("p0-diag") || r.Given("p0")) {
    spec.p0 = r.DiagOrMatrix("p0-diag", "p0", n, "one per state");
  } else {
    spec.p0.assign(n * n, 0.0);
    for (int i = 0; i < n; ++i) spec.p0[i * n + i] = 1.0;
  }
  const std::string p0_key = r.Given("p0") ? "p0" : "p0-diag";
  ForKey(p0_key, [&] { return cli::CheckCovariance(spec.p0, n, "P0", false), 0; });
  ReadNoise(r, settings.noise_prefix(), n, meas, &spec);
  spec.input = ReadConstantInput(r, model);
  spec.full_cov = r.Given("full-cov");
  ReadFilterKind(r, model, &spec);
  ReadAdapt(r, &spec.adapt);
  // The rest of the spec (transition, adaptation): messages start with the key.
  std::string error;
  if (!IsValidFilterOptions(spec, n, &error)) ThrowKeyed(error);
  return spec;
}

}  // namespace estlab
