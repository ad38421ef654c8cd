// The filter x noise combinations of a scenario: each one's FilterSpec from
// the scenario's, filter's and noise section's keys (study_config_parts.h).
#include <algorithm>
#include <cmath>
#include <map>
#include <variant>

#include "adaptive/tuner.h"
#include "src/core/parse.h"
#include "src/filters/filter_options.h"
#include "src/io/output_file.h"
#include "src/options/estimate_flags.h"
#include "src/options/filter_settings.h"
#include "src/options/group_items.h"
#include "src/options/tuner_settings.h"
#include "studies/config/study_config_parts.h"

namespace estlab::study_config {

// The tuner keys of a [noise.*] section (tuner_settings.h, as tune-<key>),
// and the study's own tune-datasets and tune-per-run.
std::vector<std::string> StudyTuneKeys() {
  std::vector<std::string> keys = {"tune-datasets", "tune-per-run"};
  for (const TunerKey& k : TunerKeyTable())
    if (k.in_studies) keys.push_back(StudyTunerKey(k));
  return keys;
}

namespace {

// The tuner options of a tuned [noise.*] section: its tune-<key> lines
// through the tuner key table (BuildTunerOptions, as `estlab tune`), an
// error reported at its line. The side not tuned is fixed; the tuned one's
// parameterisation defaults to its guess's shape (the oracle's, when it
// starts from the oracle: full when it has off-diagonal entries).
TunerOptions StudyTunerOptions(const SectionValues& noise, const ScenarioConfig& sc, bool q_tuned,
                               const std::string& q_shape, bool r_tuned, const std::string& r_shape,
                               int n) {
  const ConfigErrors& err = noise.errors();
  if (noise.Has("tune-estimator"))  // studies offer ml, em and als
    Checked(*noise.Get("tune-estimator"), err, [](const std::string& t) {
      return ParseEstimator(t, "tune-estimator", /*studies_only=*/true);
    });
  TunerSettings settings;
  for (const TunerKey& k : TunerKeyTable()) {
    if (!k.in_studies || !noise.Has(StudyTunerKey(k))) continue;
    settings.Set(k.name, noise.Get(StudyTunerKey(k))->text);
  }
  for (const auto& [which, tuned] : {std::pair<std::string, bool>{"q", q_tuned}, {"r", r_tuned}})
    if (!tuned && noise.Has(which + "-param"))
      noise.Fail(which + "-param", "needs " + which + " = tuned");
  std::string q_guess = q_shape;
  if (q_tuned && q_guess.empty() && sc.oracle_q_white_accel) q_guess = "q-white-accel";
  for (int i = 0; q_tuned && q_guess.empty() && i < n * n && i < int(sc.oracle_q.size()); ++i)
    if (i / n != i % n && sc.oracle_q[i] != 0.0) q_guess = "q";
  TunerOptions t;
  try {
    t = BuildTunerOptions(settings, q_guess, r_shape);
  } catch (const KeyError& e) {
    for (const TunerKey& k : TunerKeyTable())
      if (e.key() == k.name) noise.Fail(StudyTunerKey(k), e.message());
    noise.FailSection(e.what());
  } catch (const InputError& e) {
    noise.FailSection(e.what());
  }
  for (const auto& [which, tuned] : {std::pair<std::string, bool>{"q", q_tuned}, {"r", r_tuned}}) {
    NoiseParam& p = which == "q" ? t.q_param : t.r_param;
    if (!tuned) p = NoiseParam::kFixed;
    if (tuned && p == NoiseParam::kFixed) noise.Fail(which + "-param", "fixed contradicts tuned");
  }
  // R per sensor group: none when R is not tuned; not every group fixed.
  if (!r_tuned) t.r_param_groups.clear();
  bool all_fixed = !t.r_param_groups.empty();
  for (const auto& [group, kind] : t.r_param_groups)
    all_fixed = all_fixed && kind == NoiseParam::kFixed;
  if (all_fixed) noise.Fail("r-param", "every sensor group fixed contradicts tuned");
  return t;
}

}  // namespace

// ---------------------------------------------------------------------------
// Filter specs: the scenario's, filter's and noise section's keys fill one
// FilterSettings and BuildFilterSpec (src/options/filter_settings.h) turns
// it into a spec, exactly as for `estlab filter`; an error names the key it
// is about, reported at the line that set it.

namespace {

// What BuildCombo's steps share: the scenario, filter and noise sections,
// the FilterSettings they fill (with where each key was set) and what the
// noise section says about Q and R.
struct ComboBuilder {
  ComboBuilder(const ScenarioConfig& sc, const SectionValues& scen, const SectionValues& filt,
               const SectionValues& noise, const ConfigErrors& err)
      : sc(sc),
        scen(scen),
        filt(filt),
        noise(noise),
        err(err),
        model(*sc.model),
        n(int(model.states.size())),
        m(int(model.FindMeasurement(sc.truth.measurement).outputs.size())) {}

  void Add(const std::string& key, const std::string& value, const Value* from);
  void AddScenarioKeys();
  void AddFilterKeys();
  void AddNoiseKeys();
  void AddOracleOrTuned(const std::string& k, const std::string& which, const Value* val);
  void BuildSpec(FilterSpec* spec) const;
  void CheckParticleSmoother(const FilterSpec& spec) const;
  void SetOracleNoise(FilterSpec* spec) const;
  void ApplyInitScale(FilterSpec* spec) const;
  std::vector<EstimatedParam> EstimatedParams() const;
  void CheckModelHasParams(const std::vector<EstimatedParam>& estimate) const;
  void SetTuner(const std::vector<EstimatedParam>& estimate, Combo* combo) const;
  void SetTuneDatasets(Combo* combo) const;
  void SetTunePerRun(Combo* combo) const;
  [[noreturn]] void FailCombo(const std::string& message) const;

  const ScenarioConfig& sc;
  const SectionValues& scen;
  const SectionValues& filt;
  const SectionValues& noise;
  const ConfigErrors& err;
  const ModelEntry& model;
  const int n;  // states
  const int m;  // outputs of the scenario's measurement
  FilterSettings settings;
  std::map<std::string, const Value*> origin;  // settings key -> where it was set (null: by us)
  std::string smoothed;  // the filter a smoother kind runs ("" for a filter kind)
  bool q_oracle = false, r_oracle = false, q_tuned = false, r_tuned = false;
  bool r_oracle_std = false;
  std::string q_shape, r_shape;  // the key that gave the (initial) matrix
};

// Sets one settings key (adds it when repeatable, one value per sensor
// group for r and r-diag), remembering the value that set it.
void ComboBuilder::Add(const std::string& key, const std::string& value, const Value* from) {
  const FilterKey* k = FindFilterKey(key, "");
  if (key == "r-diag" || key == "r")  // `r-diag = imu=..., gps=...`: one value per group
    for (const std::string& group : SplitGroupValues(value)) settings.Add(key, group);
  else if (k != nullptr && k->kind == FilterKey::kRepeatable)
    settings.Add(key, value);
  else
    settings.Set(key, value);
  origin[key] = from;
}

// The scenario's keys: its measurement, params, prior, input and
// input-hold.
void ComboBuilder::AddScenarioKeys() {
  Add("measure", sc.truth.measurement, scen.Get("measurement"));
  if (scen.Has("params")) Add("param", scen.Get("params")->text, scen.Get("params"));
  // Prior from the scenario (already validated): pass as numbers.
  std::string x0;
  for (int i = 0; i < n; ++i) {
    if (i) x0 += ',';
    x0 += model.states[i] + "=" + FormatDouble(sc.prior_x0[i]);
  }
  Add("x0", x0, scen.Get(scen.Has("prior-x0") ? "prior-x0" : "x0"));
  std::string p0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (j) p0 += ',';
      p0 += FormatDouble(sc.prior_p0[i * n + j]);
    }
    if (i + 1 < n) p0 += ";";
  }
  Add("p0", p0, nullptr);
  std::string input;
  for (double u : sc.truth.input) {
    if (!input.empty()) input += ',';
    input += FormatDouble(u);
  }
  Add("input", input.empty() ? "0" : input, scen.Get("input"));
  if (scen.Has("input-hold"))
    Add("input-hold", scen.Get("input-hold")->text, scen.Get("input-hold"));
}

// The filter section's keys: its kind as the filter, then the rest.
void ComboBuilder::AddFilterKeys() {
  // A smoother kind (urts, ...) runs its filter with spec.smooth set (BuildSpec).
  const Value* kind = filt.Get("kind");
  smoothed = FilterOfSmoother(kind->text);
  Add("filter", smoothed.empty() ? kind->text : smoothed, kind);
  for (const Entry& e : filt.section().entries) {
    if (e.key == "kind" || e.key == "scenarios" || e.key == "description") continue;
    Add(e.key, filt.Get(e.key)->text, filt.Get(e.key));
  }
}

// Q and R: the noise section's keys, or placeholders (SetOracleNoise replaces).
// `tuned` starts from the init-q-* / init-r-* key, else from the oracle.
void ComboBuilder::AddNoiseKeys() {
  for (const char* key : {"q", "q-diag", "q-white-accel", "r", "r-diag"}) {
    const Value* val = noise.Get(key);
    if (!val) continue;
    const std::string k = key;
    const std::string which = k.substr(0, 1);
    if (sc.recorded && (val->text == "oracle" || val->text == "oracle-std"))
      noise.Fail(k, "no oracle on recorded data: [" + sc.section +
                        "] has no known noise (use a hand Q/R or '" + which + " = tuned')");
    if (val->text == "oracle-std") {
      // Paper 003's sweep: R = diag(std) instead of diag(std^2).
      if (k != "r") noise.Fail(k, "'oracle-std' goes in key r");
      r_oracle = r_oracle_std = true;
      r_shape = "r-diag";
      Add("r-diag", JoinDoubles(std::vector<double>(m, 1.0)), val);
      continue;
    }
    if (val->text == "oracle" || val->text == "tuned") {
      AddOracleOrTuned(k, which, val);
      continue;
    }
    (which == "q" ? q_shape : r_shape) = k;
    Add(k, val->text, val);
  }
  for (const char* ik : {"init-q-diag", "init-q", "init-q-white-accel", "init-r-diag", "init-r"})
    if (noise.Has(ik) && !(ik[5] == 'q' ? q_tuned : r_tuned))
      noise.Fail(ik, std::string("an initial guess needs ") + ik[5] + " = tuned");
}

// `which = oracle` or `which = tuned` (in key k = val): the init-* key's
// matrix, else a placeholder that SetOracleNoise replaces by the oracle's.
void ComboBuilder::AddOracleOrTuned(const std::string& k, const std::string& which,
                                    const Value* val) {
  if (k != which) noise.Fail(k, "'" + val->text + "' goes in key " + which);
  const bool tuned = val->text == "tuned";
  (which == "q" ? q_tuned : r_tuned) = tuned;
  const Value* init = nullptr;
  for (const std::string& ik :
       which == "q" ? std::vector<std::string>{"init-q-diag", "init-q", "init-q-white-accel"}
                    : std::vector<std::string>{"init-r-diag", "init-r"}) {
    if (!noise.Has(ik)) continue;
    if (!tuned) noise.Fail(ik, "an initial guess needs " + which + " = tuned");
    if (init) noise.Fail(ik, "give only one initial " + which + " (init-" + which + "*)");
    init = noise.Get(ik);
    (which == "q" ? q_shape : r_shape) = ik.substr(5);
    Add(ik.substr(5), init->text, init);
  }
  if (!init) {
    if (sc.recorded)
      noise.Fail(k, "'tuned' on recorded data needs a start (init-" + which +
                        "-diag, ...): there is no oracle to start from");
    (which == "q" ? q_oracle : r_oracle) = true;
    Add(which + "-diag",
        which == "q" ? JoinDoubles(std::vector<double>(n, 0.0))
                     : JoinDoubles(std::vector<double>(m, 1.0)),
        val);
  }
}

// "FILE:LINE: [filter.F] with [scenario.S] and [noise.N]: message", at the
// filter section's line.
void ComboBuilder::FailCombo(const std::string& message) const {
  err.Fail(filt.section().line, "[" + filt.section().full + "] with [" + sc.section + "] and [" +
                                    noise.section().full + "]: " + message);
}

// The spec from the settings (BuildFilterSpec); an error about a key is
// reported at the line that set it, else at the filter section's.
void ComboBuilder::BuildSpec(FilterSpec* spec) const {
  const std::string context = " (for [" + sc.section + "] with [" + noise.section().full + "])";
  try {
    *spec = BuildFilterSpec(settings, model);
    spec->smooth = !smoothed.empty();
  } catch (const KeyError& e) {
    const auto it = origin.find(e.key());
    if (it != origin.end() && it->second != nullptr)
      err.Fail(it->second->line, it->second->where + ": " + e.message() + context);
    FailCombo(e.what());
  } catch (const InputError& e) {
    FailCombo(e.what());
  }
  CheckParticleSmoother(*spec);
}

// pf-bs keeps every step's particle cloud (particles x rows x (2n + 1)
// doubles, src/filters/particle_smoother.h): over kMaxRunBytes per run it is
// refused at the filter's particles key, before any run.
void ComboBuilder::CheckParticleSmoother(const FilterSpec& spec) const {
  const auto* pf = std::get_if<ParticleOptions>(&spec.filter);
  if (!spec.smooth || pf == nullptr) return;
  double rows = double(sc.steps);
  for (const FilterData& d : sc.data_runs) rows = std::max(rows, double(d.t.size()));
  const double bytes = ParticleSmootherBytes(pf->num_particles, rows, int(model.states.size()));
  if (bytes > kMaxRunBytes)
    filt.Fail("particles", std::to_string(pf->num_particles) + " particles over " +
                               FormatNumber(rows) +
                               " rows: the particle smoother's clouds would "
                               "take " +
                               FormatNumber(bytes / 1073741824.0) +
                               " GiB per run (at "
                               "most " +
                               FormatNumber(kMaxRunBytes / 1073741824.0) + " for [" + sc.section +
                               "]): fewer particles or steps");
}

// Replaces the placeholders of q = oracle / r = oracle (and their tuned
// starts) by the scenario's oracle Q and R; R must not be singular.
void ComboBuilder::SetOracleNoise(FilterSpec* spec) const {
  if (q_oracle) {
    spec->q_white_accel = sc.oracle_q_white_accel;
    spec->qc = sc.oracle_qc;
    spec->q = sc.oracle_q;
  }
  if (r_oracle) {
    for (int j = 0; j < m; ++j) {
      if (!(sc.oracle_r[j * m + j] > 0)) {
        noise.Fail("r", "the oracle R of [" + sc.section +
                            "] is singular: its meas-noise-var is 0 for output '" +
                            model.FindMeasurement(sc.truth.measurement).outputs[j] + "'");
      }
    }
    spec->r = sc.oracle_r;
    if (r_oracle_std)
      for (double& x : spec->r) x = std::sqrt(x);
  }
}

// init-scale = s: the tuner starts from s times the oracle (robustness).
void ComboBuilder::ApplyInitScale(FilterSpec* spec) const {
  if (!noise.Has("init-scale")) return;
  const double scale = Checked(*noise.Get("init-scale"), err, [](const std::string& t) {
    const double v = ParseNumber(t, "init-scale");
    if (!(v > 0 && std::isfinite(v)))
      throw InputError("init-scale must be a finite number > 0, got '" + t + "'");
    return v;
  });
  if (!(q_tuned && q_oracle) && !(r_tuned && r_oracle))
    noise.Fail("init-scale", "scales the oracle start of q = tuned or r = tuned (no init-* key)");
  if ((q_tuned && !q_oracle) || (r_tuned && !r_oracle))
    noise.Fail("init-scale",
               "scales the oracle start: every tuned side must start from the oracle (drop the "
               "init-* key)");
  if (q_tuned && q_oracle) {
    spec->qc *= scale;
    for (double& x : spec->q) x *= scale;
  }
  if (r_tuned && r_oracle)
    for (double& x : spec->r) x *= scale;
}

// params = tuned NAME,...: the physical parameters fitted with Q and R
// (with their param-bounds and param-prior); none without the key.
std::vector<EstimatedParam> ComboBuilder::EstimatedParams() const {
  std::vector<EstimatedParam> estimate;
  if (noise.Has("params")) {
    const Value& v = *noise.Get("params");
    const std::string text = Trim(v.text);
    if (text.rfind("tuned", 0) != 0 || Trim(text.substr(5)).empty())
      noise.Fail("params", "expected 'tuned NAME[,NAME...]', got '" + v.text + "'");
    auto text_of = [&](const char* key) { return noise.Has(key) ? noise.Get(key)->text : ""; };
    estimate = Checked(v, err, [&](const std::string&) {
      return ParseEstimatedParams(Trim(text.substr(5)), text_of("param-bounds"),
                                  text_of("param-prior"));
    });
    CheckModelHasParams(estimate);
  } else {
    for (const char* key : {"param-bounds", "param-prior"})
      if (noise.Has(key)) noise.Fail(key, "applies only with params = tuned ...");
  }
  return estimate;
}

// Each estimated parameter must be one of the model's.
void ComboBuilder::CheckModelHasParams(const std::vector<EstimatedParam>& estimate) const {
  for (const EstimatedParam& e : estimate) {
    std::string known;
    bool found = false;
    for (const ParamDesc& p : model.params) {
      known += (known.empty() ? "" : ", ") + p.name;
      found = found || p.name == e.name;
    }
    if (!found)
      noise.Fail("params", "model '" + model.name + "' has no parameter '" + e.name + "' (it has " +
                               known + ")");
  }
}

// A tuned combination's tuner options (StudyTunerOptions), its tuning data
// sets and tune-per-run, checked against the spec it tunes.
void ComboBuilder::SetTuner(const std::vector<EstimatedParam>& estimate, Combo* combo) const {
  combo->tune = true;
  // A model file compiles its tuner now, on first use (the same entry).
  if (model.tune == nullptr) FindModel(sc.model_source, {.tuner = true});
  TunerOptions& t = combo->tuner;
  t = StudyTunerOptions(noise, sc, q_tuned, q_shape, r_tuned, r_shape, n);
  SetTuneDatasets(combo);
  t.em_compare_ml = false;  // the study scores EM's own solution
  SetTunePerRun(combo);
  t.estimate = estimate;
  t.compute_std_errors = true;
  std::string error;
  if (!t.IsValid(&error)) noise.FailSection(error);
  if (!IsTunable(combo->spec, t, n, &error)) FailCombo(error);
}

// tune-datasets (3 by default); on recorded data, the scenario's tune-data
// files instead.
void ComboBuilder::SetTuneDatasets(Combo* combo) const {
  auto integer = [&](const std::string& key, int fallback, int min_value, int max_value) {
    if (!noise.Has(key)) return fallback;
    return Checked(*noise.Get(key), err,
                   [&](const std::string& t) { return ParseCount(t, key, min_value, max_value); });
  };
  combo->tune_datasets = integer("tune-datasets", 3, 1, 10000);
  if (sc.recorded) {
    // The tuning runs are the scenario's tune-data files.
    const std::string key = q_tuned ? "q" : r_tuned ? "r" : "params";
    if (noise.Has("tune-datasets"))
      noise.Fail("tune-datasets",
                 "not used on recorded data ([" + sc.section + "] fits on its tune-data files)");
    if (sc.tune_runs.empty())
      noise.Fail(key, "[" + sc.section + "] has no tune-data files to fit on");
    combo->tune_datasets = int(sc.tune_runs.size());
  }
}

// tune-per-run: Q/R fitted in every simulated run on its own measurements.
void ComboBuilder::SetTunePerRun(Combo* combo) const {
  combo->tune_per_run = noise.Has("tune-per-run") &&
                        Checked(*noise.Get("tune-per-run"), err,
                                [](const std::string& t) { return ParseBool(t, "tune-per-run"); });
  if (combo->tune_per_run && !q_tuned && !r_tuned)
    noise.Fail("tune-per-run", "identifies Q/R: it needs q = tuned or r = tuned");
  if (combo->tune_per_run && sc.recorded)
    noise.Fail("tune-per-run",
               "applies to simulated scenarios: [" + sc.section +
                   "] tunes on its tune-data files (and has no truth noise to compare with)");
  if (combo->tune_per_run && noise.Has("tune-datasets"))
    noise.Fail("tune-datasets", "with tune-per-run each run fits on its own measurements");
}

}  // namespace

Combo BuildCombo(const ScenarioConfig& sc, const SectionValues& scen, int fi,
                 const SectionValues& filt, int ni, const SectionValues& noise,
                 const ConfigErrors& err) {
  ComboBuilder b(sc, scen, filt, noise, err);
  b.AddScenarioKeys();
  b.AddFilterKeys();
  b.AddNoiseKeys();
  Combo combo;
  combo.filter = fi;
  combo.noise = ni;
  b.BuildSpec(&combo.spec);
  b.SetOracleNoise(&combo.spec);
  b.ApplyInitScale(&combo.spec);
  // Simulated runs: the prior holds at t = 0; recorded runs: at the first row.
  combo.spec.has_t0 = !sc.measure_at_t0 && !sc.recorded;
  combo.spec.t0 = 0.0;
  const std::vector<EstimatedParam> estimate = b.EstimatedParams();
  if (b.q_tuned || b.r_tuned || !estimate.empty()) {
    b.SetTuner(estimate, &combo);
  } else {
    for (const std::string& key : StudyTuneKeys())
      if (noise.Has(key)) noise.Fail(key, "applies only with q = tuned or r = tuned");
  }
  return combo;
}

std::string NoiseDescription(const SectionValues& noise) {
  auto describe = [&](const std::string& which, std::vector<std::string> keys) {
    for (const auto& key : keys) {
      if (!noise.Has(key)) continue;
      const std::string& v = noise.Get(key)->text;
      if (v == "oracle") return std::string("oracle");
      if (v == "oracle-std") return std::string("diag(sqrt(oracle variance)) (paper 003's R)");
      if (v != "tuned") return key + " " + v;
      std::string out = "tuned";
      if (noise.Has(which + "-param")) out += " (" + noise.Get(which + "-param")->text + ")";
      for (const auto& ik :
           {"init-" + which + "-diag", "init-" + which, "init-" + which + "-white-accel"})
        if (noise.Has(ik)) return out + " from " + ik.substr(5) + " " + noise.Get(ik)->text;
      return out + " from the oracle";
    }
    return std::string("?");
  };
  std::string d = "Q " + describe("q", {"q", "q-diag", "q-white-accel"}) + ", R " +
                  describe("r", {"r", "r-diag"});
  if (noise.Has("params")) d += ", model parameters " + noise.Get("params")->text;
  if (noise.Has("tune-estimator")) d += ", estimator " + noise.Get("tune-estimator")->text;
  if (noise.Has("init-scale"))
    d += ", started at " + noise.Get("init-scale")->text + " x the oracle";
  const std::string per_run = noise.Has("tune-per-run") ? noise.Get("tune-per-run")->text : "";
  if (per_run == "true" || per_run == "yes" || per_run == "1")
    d += ", fitted in every run on its own measurements";
  if (noise.Has("tune-datasets") || noise.Has("tune-starts"))
    d += " (" + (noise.Has("tune-datasets") ? noise.Get("tune-datasets")->text : "3") +
         " tuning trajectories, " +
         (noise.Has("tune-starts") ? noise.Get("tune-starts")->text : "1") + " start(s))";
  return d;
}

}  // namespace estlab::study_config
