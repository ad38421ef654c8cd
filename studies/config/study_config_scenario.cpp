// The [scenario.NAME] sections: the truth (model, simulation, noise), the
// prior, and the '|' alternatives (study_config_parts.h).
#include <Eigen/Core>
#include <algorithm>

#include <cmath>
#include <filesystem>
#include <set>

#include "src/core/parse.h"
#include "src/core/white_accel.h"
#include "src/options/filter_flags.h"
#include "src/options/sensor_rates.h"
#include "src/registry/model_plugin.h"
#include "src/sim/input_signal.h"
#include "src/sim/simulator_impl.h"
#include "studies/config/study_config_parts.h"

namespace estlab {

std::vector<double> WhiteAccelCovariance(const ModelEntry& model, double qc, double dt) {
  const int n = int(model.states.size());
  Eigen::MatrixXd Q(n, n);
  FillWhiteAccel(model.position_rate_pairs, qc, dt, &Q);
  std::vector<double> q(n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) q[i * n + j] = Q(i, j);
  return q;
}

namespace study_config {

namespace fs = std::filesystem;

namespace {

// `input = 2.5 | multisine(...) | prbs(...) | steps(...)` (src/sim/
// input_signal.h), one per input for a model with several, comma-separated.
// A signal is sampled at the scenario's output times t_k = k dt into the
// truth's schedule; the interval before the first measurement holds the
// first measurement's sample (measure-at-t0 = false), as a filter whose
// prior is at t = 0 holds the first row's input (src/run/step_loop.h).
void SetScenarioInput(const SectionValues& v, const Value& value, const ConfigErrors& err,
                      bool recorded, ScenarioConfig* sc) {
  const ModelEntry& model = *sc->model;
  const std::string base = fs::path(err.path()).parent_path().string();  // file(...) paths
  if (!model.has_input()) {
    const InputSignal signal = Checked(
        value, err, [&](const std::string& t) { return ParseInputSignal(t, "input", base); });
    if (signal.kind != InputSignal::kConstant || signal.mean != 0)
      v.Fail("input", "model '" + model.name + "' has no input");
    return;
  }
  const std::vector<InputSignal> signals = Checked(value, err, [&](const std::string& t) {
    return ParseInputSignals(t, "input", model.inputs, base);
  });
  if (std::all_of(signals.begin(), signals.end(),
                  [](const InputSignal& s) { return s.kind == InputSignal::kConstant; })) {
    sc->truth.input.clear();
    for (const InputSignal& s : signals) sc->truth.input.push_back(s.mean);
    return;
  }
  if (recorded)
    v.Fail("input", "a signal applies to simulated runs; recorded data carry their input column");
  SimulationSpec& truth = sc->truth;
  truth.times = OutputTimes(truth);  // k dt, as without a signal
  for (const InputSignal& signal : signals)
    if (const std::string why = signal.Covers(truth.times.front(), truth.times.back());
        !why.empty())
      v.Fail("input", why);
  for (size_t k = 0; k < truth.times.size(); ++k) {
    const size_t sample = (k == 0 && !sc->measure_at_t0 && truth.times.size() > 1) ? 1 : k;
    for (const InputSignal& signal : signals)
      truth.inputs.push_back(signal.At(truth.times[sample]));
  }
  sc->truth_description += ", input " + Trim(value.text);
}

// The model of the scenario (the required `model` key), found by name or
// compiled from its file.
void SetScenarioModel(const SectionValues& v, const ConfigErrors& err, ScenarioConfig* sc) {
  if (!v.Has("model")) v.FailSection("'model' is required (see 'estlab list')");
  // A model file's path is relative to the config file; made absolute, so
  // that the study and a later `estlab figures` (which reads the results
  // folder's copy of the config) name it alike and share its compiled library.
  sc->model_source = v.Get("model")->text;
  if (IsModelPath(sc->model_source) && !fs::path(sc->model_source).is_absolute())
    sc->model_source = fs::absolute(fs::path(err.path()).parent_path() / sc->model_source)
                           .lexically_normal()
                           .string();
  sc->model = Checked(*v.Get("model"), err,
                      [&](const std::string&) { return &FindModel(sc->model_source); });
}

// A state of the model given as `name = value, ...` under `key` (x0, prior-x0).
std::vector<double> ParseState(const SectionValues& v, const ConfigErrors& err,
                               const ModelEntry& model, const std::string& key) {
  return Checked(*v.Get(key), err, [&](const std::string& t) {
    return model.ResolveState(ParseAssignments({t}, key), key);
  });
}

// `steps` against kMaxRunBytes (study_config.h).
void CheckRunMemory(const SectionValues& v, const ModelEntry& model, int steps) {
  const double n = double(model.states.size());
  double m = 0.0;
  for (const MeasurementDesc& d : model.measurements) m = std::max(m, double(d.outputs.size()));
  const double bytes = double(steps) * 8.0 * (4.0 + 3.0 * n + 2.0 * n * n + 3.0 * m + 2.0 * m * m);
  if (bytes > kMaxRunBytes)
    v.Fail("steps", std::to_string(steps) + " steps of a " + std::to_string(model.states.size()) +
                        "-state model would hold about " + FormatNumber(bytes / 1073741824.0) +
                        " GiB per run (at most " + FormatNumber(kMaxRunBytes / 1073741824.0) +
                        "): fewer steps, or a larger dt");
}

// The truth's parameters, then (after checking that the keys of the other
// kind of run are absent) its initial state and, when simulated, dt and steps.
void SetTruthStart(const SectionValues& v, const ConfigErrors& err, bool recorded,
                   ScenarioConfig* sc) {
  const ModelEntry& model = *sc->model;
  SimulationSpec& truth = sc->truth;
  if (v.Has("params")) {
    truth.params = Checked(*v.Get("params"), err, [&](const std::string& t) {
      return model.ResolveParams(ParseAssignments({t}, "params"));
    });
  } else {
    truth.params = model.ResolveParams({});
  }
  // Recorded runs: nothing is simulated, so no simulation key applies.
  for (const auto& key : recorded ? kSimulationKeys : kRecordedKeys) {
    if (v.Has(key))
      v.Fail(key, recorded ? "not allowed with data (recorded runs are not simulated)"
                           : "applies only with data = FILES (recorded runs)");
  }
  truth.x0 =
      v.Has("x0") ? ParseState(v, err, model, "x0") : std::vector<double>(model.states.size(), 0.0);
  if (v.Has("truth-x0")) {
    const std::string mode = v.Get("truth-x0")->text;
    if (mode != "fixed" && mode != "sample")
      v.Fail("truth-x0", "expected fixed or sample, got '" + mode + "'");
    sc->sample_x0 = mode == "sample";
  }
  if (!recorded) {
    if (!v.Has("dt")) v.FailSection("'dt' is required");
    truth.dt =
        Checked(*v.Get("dt"), err, [](const std::string& t) { return ParseNumber(t, "dt"); });
    if (!(truth.dt > 0)) v.Fail("dt", "must be > 0");
    if (!v.Has("steps")) v.FailSection("'steps' is required");
    sc->steps = Checked(*v.Get("steps"), err,
                        [](const std::string& t) { return ParseCount(t, "steps", 1, kMaxSteps); });
    truth.t_end = sc->steps * truth.dt;
    CheckRunMemory(v, model, sc->steps);
  }
}

// The truth's integrator (by default the model's own: discrete or cvodes)
// and its CVODES method, the only keys of the transition that are words.
void SetTruthIntegrator(const SectionValues& v, const ConfigErrors& err, ScenarioConfig* sc) {
  const ModelEntry& model = *sc->model;
  TransitionOptions& tr = sc->truth.transition;
  const bool has = v.Has("truth-integrator");
  tr.integrator = Checked(
      Value{has ? v.Get("truth-integrator")->text : (model.discrete_time ? "discrete" : "cvodes"),
            has ? v.Get("truth-integrator")->line : v.section().line,
            "[" + sc->section + "] truth-integrator"},
      err, [&](const std::string& t) {
        const Integrator i = ParseIntegrator(t);
        const std::string e = model.CheckIntegrator(i);
        if (!e.empty()) throw InputError(e);
        return i;
      });
  if (v.Has("truth-method")) {
    const std::string m = v.Get("truth-method")->text;
    if (m == "bdf")
      tr.method = CvodesMethod::kBdf;
    else if (m == "adams")
      tr.method = CvodesMethod::kAdams;
    else if (m != "default")
      v.Fail("truth-method", "expected bdf, adams or default, got '" + m + "'");
  }
}

// The truth's tolerances, substeps, step limit and input hold, checked
// together, and the truth's description (its integrator) begun.
void SetTruthTransition(const SectionValues& v, const ConfigErrors& err, ScenarioConfig* sc) {
  SetTruthIntegrator(v, err, sc);
  TransitionOptions& tr = sc->truth.transition;
  v.Read("truth-rtol", &tr.rtol, ParseNumber);
  v.Read("truth-atol", &tr.atol, ParseNumber);
  v.Read("truth-substeps", &tr.substeps, ParseCount, 1, kMaxSubsteps);
  v.Read("truth-max-steps", &tr.max_steps, ParseInteger, 1);
  // How the input goes between samples, for the truth and every filter.
  if (v.Has("input-hold"))
    tr.input_hold =
        Checked(*v.Get("input-hold"), err, [](const std::string& t) { return ParseInputHold(t); });
  std::string error;
  if (!tr.IsValid(&error)) v.FailSection(error);
  sc->truth_description = IntegratorName(tr.integrator);
  if (tr.integrator == Integrator::kCvodes)
    sc->truth_description += " rtol " + FormatNumber(tr.rtol) + " atol " + FormatNumber(tr.atol);
  else if (tr.substeps > 1)
    sc->truth_description += " x" + std::to_string(tr.substeps) + " substeps";
}

// `process-noise = diag V1,V2,...`: one variance per state.
void SetDiagProcessNoise(const Value& val, const ConfigErrors& err, ScenarioConfig* sc) {
  const int n = int(sc->model->states.size());
  const auto d = Checked(val, err, [&](const std::string& t) {
    auto list = ParseList(t, "process-noise");
    RequireLength(list, n, "process-noise", "one variance per state");
    RequireNonNegative(list, "process-noise");
    return list;
  });
  for (int i = 0; i < n; ++i) sc->oracle_q[i * n + i] = d[i];
  sc->truth.process_noise_var = d;
  sc->truth_description += ", process noise diag " + JoinDoubles(d);
}

// `process-noise = white-accel QC`: white acceleration on the model's
// (position, rate) state pairs.
void SetWhiteAccelProcessNoise(const SectionValues& v, const Value& val, const ConfigErrors& err,
                               ScenarioConfig* sc) {
  const ModelEntry& model = *sc->model;
  sc->oracle_qc = Checked(val, err, [](const std::string& t) {
    const double qc = ParseNumber(t, "process-noise");
    if (qc < 0) throw InputError("process-noise: qc must be >= 0");
    return qc;
  });
  if (model.position_rate_pairs.empty())
    v.Fail("process-noise",
           "white-accel needs (position, rate) state pairs; model '" + model.name + "' has none");
  sc->oracle_q_white_accel = true;
  sc->oracle_q = WhiteAccelCovariance(model, sc->oracle_qc, sc->truth.dt);
  sc->truth.process_noise_cov = sc->oracle_q;
  sc->truth_description += ", white-accel qc " + FormatNumber(sc->oracle_qc);
}

// Process noise of the truth, per step of dt: `process-noise = KIND ARG`
// (none by default), also the oracle Q.
void SetProcessNoise(const SectionValues& v, const ConfigErrors& err, ScenarioConfig* sc) {
  const int n = int(sc->model->states.size());
  sc->oracle_q.assign(n * n, 0.0);
  const std::string pn = v.Has("process-noise") ? v.Get("process-noise")->text : "none";
  const auto space = pn.find_first_of(" \t");
  const std::string kind = pn.substr(0, space);
  const std::string arg = space == std::string::npos ? "" : Trim(pn.substr(space));
  const Value val{arg, v.Has("process-noise") ? v.Get("process-noise")->line : 0,
                  "[" + sc->section + "] process-noise"};
  if (kind == "none") {
    sc->truth_description += ", no process noise";
  } else if (kind == "diag") {
    SetDiagProcessNoise(val, err, sc);
  } else if (kind == "white-accel") {
    SetWhiteAccelProcessNoise(v, val, err, sc);
  } else if (kind == "matrix") {
    sc->oracle_q = Checked(val, err, [&](const std::string& t) {
      auto q = ParseMatrix(t, n, "process-noise");
      cli::CheckCovariance(q, n, "process-noise", true);
      return q;
    });
    sc->truth.process_noise_cov = sc->oracle_q;
    sc->truth_description += ", process noise matrix";
  } else {
    v.Fail("process-noise",
           "expected none, diag V1,V2,..., white-accel QC or matrix A,B;C,D, "
           "got '" +
               pn + "'");
  }
}

// The truth's measurement (required), its noise variances and its sensor
// rates; returns the measurement.
const MeasurementDesc& SetMeasurement(const SectionValues& v, const ConfigErrors& err,
                                      ScenarioConfig* sc) {
  SimulationSpec& truth = sc->truth;
  if (!v.Has("measurement")) v.FailSection("'measurement' is required (see 'estlab list')");
  const MeasurementDesc& meas = *Checked(*v.Get("measurement"), err, [&](const std::string& t) {
    return &sc->model->FindMeasurement(t);
  });
  truth.measurement = meas.name;  // "imu,gps": the measurement with those groups
  const int m = int(meas.outputs.size());
  truth.meas_noise_var.assign(m, 0.0);
  if (v.Has("meas-noise-var")) {
    truth.meas_noise_var = Checked(*v.Get("meas-noise-var"), err, [&](const std::string& t) {
      auto list = ParseList(t, "meas-noise-var");
      RequireLength(list, m, "meas-noise-var", "one per output of '" + meas.name + "'");
      RequireNonNegative(list, "meas-noise-var");
      return list;
    });
  }
  // The rates alone, then with the every-k groups: an error at its key's line.
  auto text = [&](const char* k) { return v.Has(k) ? v.Get(k)->text : std::string(); };
  for (const bool with_every : {false, true}) {
    const char* key = with_every ? "sensor-every" : "sensor-rate";
    if (!v.Has(key)) continue;
    truth.output_every = Checked(*v.Get(key), err, [&](const std::string&) {
      return OutputEvery(meas, text("sensor-rate"), with_every ? text("sensor-every") : "",
                         truth.dt, "sensor-rate", "sensor-every");
    });
  }
  return meas;
}

// The oracle R (the measurement variances), the noise's distribution
// (`meas-noise = gaussian | poisson`) and measure-at-t0.
void SetMeasurementNoise(const SectionValues& v, const MeasurementDesc& meas, ScenarioConfig* sc) {
  SimulationSpec& truth = sc->truth;
  const int m = int(meas.outputs.size());
  sc->oracle_r.assign(m * m, 0.0);
  for (int j = 0; j < m; ++j) sc->oracle_r[j * m + j] = truth.meas_noise_var[j];
  if (v.Has("meas-noise")) {
    const std::string kind = v.Get("meas-noise")->text;
    if (kind == "poisson") {
      // The counts' variance is lambda, so the oracle R stays diag(lambda);
      // their mean lambda is a bias no filter here models (as in paper 004).
      sc->poisson_meas = true;
      sc->poisson_lambda = truth.meas_noise_var;
      truth.meas_noise_var.assign(m, 0.0);
      sc->truth_description += ", Poisson measurement counts";
    } else if (kind != "gaussian") {
      v.Fail("meas-noise", "expected gaussian or poisson, got '" + kind + "'");
    }
  }
  v.Read("measure-at-t0", &sc->measure_at_t0, ParseBool);
}

// The filters' prior: prior-x0 (the truth's x0 by default) and P0 from
// prior-p0-diag or prior-p0 (identity by default), checked as a covariance.
void SetPrior(const SectionValues& v, const ConfigErrors& err, ScenarioConfig* sc) {
  const int n = int(sc->model->states.size());
  sc->prior_x0 = v.Has("prior-x0") ? ParseState(v, err, *sc->model, "prior-x0") : sc->truth.x0;
  if (v.Has("prior-p0-diag") && v.Has("prior-p0"))
    v.Fail("prior-p0", "give only one of prior-p0-diag and prior-p0");
  sc->prior_p0.assign(n * n, 0.0);
  if (v.Has("prior-p0-diag")) {
    const auto d = Checked(*v.Get("prior-p0-diag"), err, [&](const std::string& t) {
      auto list = ParseList(t, "prior-p0-diag");
      RequireLength(list, n, "prior-p0-diag", "one per state");
      return list;
    });
    for (int i = 0; i < n; ++i) sc->prior_p0[i * n + i] = d[i];
  } else if (v.Has("prior-p0")) {
    sc->prior_p0 = Checked(*v.Get("prior-p0"), err,
                           [&](const std::string& t) { return ParseMatrix(t, n, "prior-p0"); });
  } else {
    for (int i = 0; i < n; ++i) sc->prior_p0[i * n + i] = 1.0;
  }
  const std::string p0_key = v.Has("prior-p0") ? "prior-p0" : "prior-p0-diag";
  try {
    cli::CheckCovariance(sc->prior_p0, n, "P0", false);
  } catch (const InputError& e) {
    v.Fail(p0_key, e.what());
  }
}

}  // namespace

ScenarioConfig BuildScenario(const SectionValues& v, const ConfigErrors& err) {
  ScenarioConfig sc;
  sc.section = v.section().full;
  SetScenarioModel(v, err, &sc);
  const bool recorded = v.Has("data");
  SetTruthStart(v, err, recorded, &sc);
  SetTruthTransition(v, err, &sc);
  SetProcessNoise(v, err, &sc);
  const MeasurementDesc& meas = SetMeasurement(v, err, &sc);
  SetMeasurementNoise(v, meas, &sc);
  if (v.Has("input")) SetScenarioInput(v, *v.Get("input"), err, recorded, &sc);

  if (recorded) ReadRecordedData(v, &sc);

  SetPrior(v, err, &sc);
  return sc;
}

// Expands the '|' alternatives of a scenario section into one Section per
// combination (product in key order; the last key varies fastest).
std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> ExpandScenario(
    const Section& sec, const ConfigErrors& err) {
  std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> out;
  out.push_back({sec, {}});
  out[0].first.entries.clear();
  for (const Entry& e : sec.entries) {
    const auto alts = ParseAlternatives(e, err, "[" + sec.full + "] " + e.key);
    std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> next;
    for (const auto& [s, choices] : out) {
      for (const auto& a : alts) {
        auto s2 = s;
        s2.entries.push_back({e.key, a.value, e.line});
        auto c2 = choices;
        if (alts.size() > 1) c2.emplace_back(e.key, a.label);
        next.emplace_back(std::move(s2), std::move(c2));
      }
    }
    out = std::move(next);
    if (out.size() > 10000) err.Fail(e.line, "[" + sec.full + "]: more than 10000 combinations");
  }
  return out;
}

}  // namespace study_config
}  // namespace estlab
