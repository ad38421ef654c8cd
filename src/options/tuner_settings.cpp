#include "src/options/tuner_settings.h"

#include <limits>

#include "src/core/parse.h"
#include "src/options/group_items.h"

namespace estlab {

namespace {

bool IsMl(const EstimatorInfo& e) { return e.id == Estimator::kMl; }
bool IsEm(const EstimatorInfo& e) { return e.id == Estimator::kEm; }
bool IsAls(const EstimatorInfo& e) { return e.id == Estimator::kAls; }
bool MultiStart(const EstimatorInfo& e) { return e.multi_start; }
bool BurnIn(const EstimatorInfo& e) { return e.burn_in; }
bool Noise(const EstimatorInfo& e) { return e.noise; }
bool Box(const EstimatorInfo& e) { return e.tuner || e.params; }

const std::vector<TunerKey> kTunerKeys = {
    {"estimator", "ml", nullptr},  // help: EstimatorHelp
    {"solver", "lbfgs", "ml: lbfgs (projected L-BFGS) | least-squares (Levenberg-Marquardt)", IsMl,
     "the ml estimator"},
    {"q-param", nullptr,
     "diag | full | white-accel | scalar | fixed (default: the --init-q* shape)", Noise,
     "the estimators of Q and R"},
    {"r-param", nullptr,
     "diag | full | scalar | fixed (default: the --init-r* shape), or one per sensor group: "
     "GROUP=KIND,... (ml; R is then block-diagonal)",
     Noise, "the estimators of Q and R"},
    {"starts", "1", "number of starts (1 = the initial guess only)", MultiStart,
     "the ml estimator"},
    {"jobs", "1",
     "threads running the starts, and with fewer starts each gradient's passes (same result "
     "for any value)",
     MultiStart, "the ml estimator", /*in_studies=*/false},
    {"start-spread", "2", "Latin hypercube half-width in log space", MultiStart,
     "the ml estimator"},
    {"burn-in", "0", "updates skipped at the start of each dataset", BurnIn,
     "the ml and als estimators (and output-error's validation)"},
    {"bound-width", "20", "log parameters within initial +- this", Box, "every estimator"},
    {"log-lower", nullptr, "lower bound(s) of the log parameters: one, or one per parameter", Box,
     "every estimator"},
    {"log-upper", nullptr, "upper bound(s) of the log parameters", Box, "every estimator"},
    {"max-iterations", nullptr,
     "optimiser iterations per start (default 200), EM iterations (default 1000)"},
    {"max-integrator-steps", "200",
     "--integrator cvodes: CVODES steps per interval allowed at a trial point, on average "
     "(+10^4; x5 for a stiff model), 100x in one interval; a point needing more is infeasible"},
    {"tolerance", "1e-9", "em: stop when the relative NLL change is at most this", IsEm,
     "the em estimator"},
    {"lags", "10", "als: innovation autocovariance lags 0..N-1 fitted", IsAls, "the als estimator"},
};

const TunerKey& KeyOf(const std::string& name) {
  for (const TunerKey& k : kTunerKeys)
    if (name == k.name) return k;
  throw std::logic_error("no tuner key '" + name + "'");
}

// Runs parse(text, "--KEY") and turns its InputError "--KEY: message" into
// a KeyError.
template <class Parse>
auto Keyed(const std::string& key, const std::string& text, Parse&& parse) {
  try {
    return parse(text, "--" + key);
  } catch (const KeyError&) {
    throw;
  } catch (const InputError& e) {
    const std::string prefix = "--" + key + ": ";
    const std::string what = e.what();
    throw KeyError(key, what.rfind(prefix, 0) == 0 ? what.substr(prefix.size()) : what);
  }
}

}  // namespace

const std::vector<TunerKey>& TunerKeyTable() {
  static const std::vector<TunerKey> keys = [] {
    std::vector<TunerKey> k = kTunerKeys;
    static const std::string help = EstimatorNames(" | ", " | ");
    k[0].help = help.c_str();
    return k;
  }();
  return keys;
}

std::string StudyTunerKey(const TunerKey& key) {
  const std::string name = key.name;
  return name == "q-param" || name == "r-param" ? name : "tune-" + name;
}

std::string TunerSettings::Get(const std::string& key) const {
  const auto it = values_.find(key);
  if (it != values_.end()) return it->second;
  const char* d = KeyOf(key).default_text;
  return d ? d : "";
}

NoiseParam NoiseParamOfGuess(const std::string& guess_key) {
  auto ends = [&](const std::string& tail) {
    return guess_key.size() >= tail.size() &&
           guess_key.compare(guess_key.size() - tail.size(), tail.size(), tail) == 0;
  };
  if (ends("-white-accel")) return NoiseParam::kWhiteAccel;
  if (ends("-scalar")) return NoiseParam::kScalar;
  if (guess_key == "q" || guess_key == "r") return NoiseParam::kFull;
  return NoiseParam::kDiag;
}

// "imu=full,gps=scalar": a kind per sensor group, each group once; `key`
// is the option as written ("--r-param").
std::vector<std::pair<std::string, NoiseParam>> ParseGroupNoiseParams(const std::string& text,
                                                                      const std::string& key) {
  std::vector<std::pair<std::string, NoiseParam>> out;
  for (const auto& [group, text_kind] : ParseGroupItems(text, key, "KIND")) {
    const NoiseParam kind = ParseNoiseParam(text_kind, key);
    if (kind == NoiseParam::kWhiteAccel)
      throw InputError(key + ": white-accel applies to Q only (group '" + group + "')");
    out.push_back({group, kind});
  }
  return out;
}

TunerOptions BuildTunerOptions(const TunerSettings& s, const std::string& q_guess,
                               const std::string& r_guess) {
  TunerOptions o;
  o.estimator =
      Keyed("estimator", s.Get("estimator"),
            [](const std::string& t, const std::string& k) { return ParseEstimator(t, k); });
  const EstimatorInfo& e = InfoOf(o.estimator);
  for (const auto& [name, text] : s.values()) {  // a key of another estimator is an error
    const TunerKey& key = KeyOf(name);
    if (key.applies != nullptr && !key.applies(e))
      throw KeyError(name, std::string("applies to ") + key.applies_to +
                               " only (the estimator is " + e.name + ")");
  }
  auto number = [&](const char* key) {
    return Keyed(key, s.Get(key),
                 [](const std::string& t, const std::string& k) { return ParseNumber(t, k); });
  };
  auto count = [&](const char* key, int lo, int hi) {
    return Keyed(key, s.Get(key), [&](const std::string& t, const std::string& k) {
      return ParseCount(t, k, lo, hi);
    });
  };
  auto list = [&](const char* key) {
    if (!s.Given(key)) return std::vector<double>{};
    return Keyed(key, s.Get(key),
                 [](const std::string& t, const std::string& k) { return ParseList(t, k); });
  };
  auto noise = [&](const char* key, const std::string& guess) {
    if (!s.Given(key)) return NoiseParamOfGuess(guess);
    return Keyed(key, s.Get(key),
                 [](const std::string& t, const std::string& k) { return ParseNoiseParam(t, k); });
  };
  o.solver = Keyed("solver", s.Get("solver"),
                   [](const std::string& t, const std::string& k) { return ParseMlSolver(t, k); });
  o.q_param = noise("q-param", q_guess);
  if (s.Given("r-param") && s.Get("r-param").find('=') != std::string::npos) {
    o.r_param = NoiseParamOfGuess(r_guess);
    o.r_param_groups = Keyed("r-param", s.Get("r-param"), ParseGroupNoiseParams);
  } else {
    o.r_param = noise("r-param", r_guess);
  }
  if (o.r_param == NoiseParam::kWhiteAccel)
    throw KeyError("r-param", "white-accel applies to Q only");
  constexpr int kMax = std::numeric_limits<int>::max();
  o.starts = count("starts", 1, 1000000);
  o.jobs = count("jobs", 1, 1024);
  o.start_spread = number("start-spread");
  o.burn_in = count("burn-in", 0, kMax);
  o.bound_width = number("bound-width");
  o.log_lower = list("log-lower");
  o.log_upper = list("log-upper");
  o.max_iterations =
      s.Given("max-iterations") ? count("max-iterations", 1, 100000000) : e.default_max_iterations;
  o.max_integrator_steps = count("max-integrator-steps", 1, 100000000);
  o.em_tolerance = number("tolerance");
  o.als_lags = count("lags", 1, 10000);
  std::string error;
  if (!o.IsValid(&error)) throw InputError(error);
  return o;
}

}  // namespace estlab
