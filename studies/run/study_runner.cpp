#include "studies/run/study_runner.h"

#include <unistd.h>

#include <ceres/version.h>
#include <sundials/sundials_config.h>
#include <Eigen/Cholesky>
#include <algorithm>
#include <boost/version.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "adaptive/tuner.h"
#include "estlab_version.h"
#include "src/core/random.h"
#include "src/core/task_pool.h"
#include "src/core/types.h"
#include "src/io/folder_lock.h"
#include "src/io/json.h"
#include "src/io/output_file.h"
#include "studies/report/study_finalize.h"
#include "studies/report/study_metrics.h"
#include "studies/results/study_integrity.h"
#include "studies/run/study_identification.h"
#include "studies/run/study_runner_parts.h"
#include "studies/run/study_schedule.h"
#include "studies/run/study_tuning.h"

namespace fs = std::filesystem;

namespace estlab {

bool StudyRunOptions::IsValid(std::string* error) const {
  if (out_dir.empty()) return *error = "the output folder is empty", false;
  if (runs < 0) return *error = "runs must be >= 1", false;
  if (jobs < 0 || jobs > 1024) return *error = "jobs must be in 1..1024", false;
  if (shards < 1 || shard < 1 || shard > shards)
    return *error = "shard must be k/N with 1 <= k <= N", false;
  return true;
}

namespace {

std::string Sig6(double v) {
  if (std::isnan(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string Full(double v) { return FormatDouble(v); }  // %.17g, NaN = ""

std::string HexHash(uint64_t h) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// The text one run adds to each file, formatted by the worker.
struct RunText {
  std::string runs, steps, timing;
  long failed = 0;
};

struct RunContext {
  const StudyConfig* config;
  std::string dir;
  int every = 1;
  std::set<int> keep;
};

// Particle-filter seeds: from the run seed and the names, so that adding or
// reordering filters leaves the others' draws alone.
uint64_t ComboSeed(uint64_t run_seed, const std::string& filter, const std::string& noise) {
  return DeriveSeed({run_seed, ConfigHash("filter:" + filter), ConfigHash("noise:" + noise)});
}

}  // namespace

namespace study_runner {

std::string NowUtc() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string Sig10(double v) {
  if (std::isnan(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::vector<double> SampleX0(const ScenarioConfig& sc, uint64_t run_seed) {
  const int n = int(sc.truth.x0.size());
  Eigen::MatrixXd P(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) P(i, j) = sc.prior_p0[i * n + j];
  const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(P).matrixL();
  Rng rng(DeriveSeed({run_seed, 0x7830ull}));  // "x0"
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) w(i) = rng.Normal();
  const Eigen::VectorXd d = L * w;
  std::vector<double> x0 = sc.truth.x0;
  for (int i = 0; i < n; ++i) x0[i] += d(i);
  return x0;
}

// The measurements (and truth) of a simulated trajectory, as a filter reads
// them. With meas-noise = poisson the simulator drew no measurement noise and
// the counts are added here from their own stream DeriveSeed({seed, "pois"}).
FilterData DataFromTruth(const ScenarioConfig& sc, const SimulationResult& truth,
                         const std::string& label, uint64_t seed) {
  Rng poisson(DeriveSeed({seed, 0x706F6973ull}));
  const int n = int(sc.model->states.size());
  FilterData data;
  data.path = label;
  data.m = int(truth.columns.size()) - 1 - n;
  data.has_truth = true;
  // Input signals: one value per input per row (the truth's schedule).
  const size_t nu = sc.truth.inputs.empty() ? 0 : sc.model->inputs.size();
  data.nu = int(nu);
  for (size_t k = sc.measure_at_t0 ? 0 : 1; k < truth.rows.size(); ++k) {
    const auto& row = truth.rows[k];
    data.t.push_back(row[0]);
    for (size_t i = 0; i < nu; ++i) data.u.push_back(sc.truth.inputs[k * nu + i]);
    data.lines.push_back(long(k));
    for (int i = 0; i < n; ++i) data.truth.push_back(row[1 + i]);
    for (int j = 0; j < data.m; ++j)
      data.z.push_back(row[1 + n + j] +
                       (sc.poisson_meas ? PoissonCount(poisson, sc.poisson_lambda[j]) : 0.0));
  }
  return data;
}

}  // namespace study_runner

namespace {

using study_runner::DataFromTruth;
using study_runner::NowUtc;
using study_runner::SampleX0;
using study_runner::Sig10;

int Column(const std::vector<std::string>& cols, const std::string& name) {
  for (size_t i = 0; i < cols.size(); ++i)
    if (cols[i] == name) return int(i);
  return -1;
}

void WriteTimeseries(const RunContext& ctx, const ScenarioConfig& sc, int run,
                     const std::string& filter, const std::string& noise, const FilterData& data,
                     const FilterRunOutput& out) {
  const auto& states = sc.model->states;
  const int n = int(states.size());
  const fs::path folder = fs::path(ctx.dir) / "timeseries" / sc.name;  // made by RunStudy
  OutputFile file(
      (folder / ("run" + std::to_string(run) + "_" + filter + "_" + noise + ".csv")).string());
  std::ostream& os = file.stream();
  os << "t";
  for (const auto& s : states)
    os << "," << s << "_true," << s << "_est," << s << "_lo2sd," << s << "_hi2sd," << s << "_err";
  os << ",nees,nis";
  // The measurements (outputs in the measurement's order), for the
  // estimate figures.
  const auto& outputs = sc.model->FindMeasurement(sc.truth.measurement).outputs;
  for (const auto& o : outputs) os << ",z_" << o;
  os << "\n";
  const int nees_c = Column(out.columns, "nees"), nis_c = Column(out.columns, "nis");
  const int m = data.m;
  for (size_t k = 0; k < out.rows.size(); ++k) {
    const auto& r = out.rows[k];
    os << Full(r[0]);
    for (int i = 0; i < n; ++i) {
      const double est = r[Column(out.columns, states[i] + "_est")];
      const double sd = std::sqrt(std::max(0.0, r[Column(out.columns, states[i] + "_var")]));
      const double true_value = data.has_truth ? data.truth[k * n + i] : NAN;
      os << "," << Full(true_value) << "," << Full(est) << "," << Full(est - 2 * sd) << ","
         << Full(est + 2 * sd) << ","
         << Full(data.has_truth ? r[Column(out.columns, states[i] + "_err")] : NAN);
    }
    os << "," << Full(nees_c >= 0 ? r[nees_c] : NAN) << "," << Full(nis_c >= 0 ? r[nis_c] : NAN);
    for (size_t j = 0; j < outputs.size(); ++j)
      os << "," << Full(int(j) < m && k < data.t.size() ? data.z[k * m + j] : NAN);
    os << "\n";
  }
  file.Commit();
}

// The runs.csv fields of the metrics that need no truth (study_metrics.h):
// nll_per_step, nis_lo95, nis_hi95, pred_rmse_OUTPUT for every output column
// of the study (empty where this scenario's measurement has no such output).
void AppendNoTruthMetrics(const StudyConfig& c, const ScenarioConfig& sc, bool ran,
                          const NoTruthMetrics& m, std::vector<std::string>* row) {
  const auto& outputs = sc.model->FindMeasurement(sc.truth.measurement).outputs;
  row->push_back(ran ? Full(m.nll_per_step) : "");
  row->push_back(ran ? Full(m.nis_bounds95[0]) : "");
  row->push_back(ran ? Full(m.nis_bounds95[1]) : "");
  for (const auto& o : c.output_columns) {
    const auto it = std::find(outputs.begin(), outputs.end(), o);
    row->push_back(ran && it != outputs.end() ? Full(m.pred_rmse[size_t(it - outputs.begin())])
                                              : "");
  }
}

// The IdentificationColumns of a runs.csv row: empty unless the combo
// tunes per run and its tuner gave a result.
void AppendIdentification(const StudyConfig& c, const ScenarioConfig& sc, const Combo& cb,
                          const RunIdentification& id, std::vector<std::string>* row) {
  const bool has = cb.tune_per_run && id.attempted && id.failure.empty();
  row->push_back(has ? Full(id.q_err) : "");
  row->push_back(has ? Full(id.r_err) : "");
  row->push_back(has ? std::to_string(id.iterations) : "");
  row->push_back(has ? (id.converged ? "1" : "0") : "");
  row->push_back(has ? (id.at_bound ? "1" : "0") : "");
  auto element = [&](const std::vector<std::string>& names, const std::string& name,
                     const std::vector<double>& ratios) {
    const auto it = std::find(names.begin(), names.end(), name);
    const size_t i = size_t(it - names.begin());
    row->push_back(has && it != names.end() && i < ratios.size() ? Full(ratios[i]) : "");
  };
  for (const auto& s : c.state_columns) element(sc.model->states, s, id.q_ratio);
  const auto& outputs = sc.model->FindMeasurement(sc.truth.measurement).outputs;
  for (const auto& o : c.identification_outputs) element(outputs, o, id.r_ratio);
}

// Run `run` of a scenario: its simulated truth and measurements, or its
// recorded file. Sets *truth_error when the truth could not be simulated.
FilterData RunData(const ScenarioConfig& sc, int run, uint64_t seed, SimulationResult* truth,
                   std::string* truth_error) {
  if (sc.recorded) return sc.data_runs[size_t(run)];
  SimulationSpec sim = sc.truth;
  sim.seed = seed;
  if (sc.sample_x0) sim.x0 = SampleX0(sc, seed);
  try {
    *truth = sc.model->simulate(sim);
    if (!truth->ok) *truth_error = "truth simulation failed: " + truth->error;
  } catch (const std::exception& e) {
    *truth_error = std::string("truth simulation failed: ") + e.what();
  }
  if (!truth_error->empty()) return FilterData{};
  return DataFromTruth(sc, *truth, "scenario " + sc.name + " run " + std::to_string(run), seed);
}

// One combo's filter run within a run: the row key (scenario, filter, noise,
// run), the filter's output, the per-run identification and the status.
struct ComboRun {
  std::vector<std::string> key;
  FilterRunOutput out;
  RunIdentification id;
  std::string status = "ok", message;
};

// Runs combo `cb` on a run's data: identifies its Q/R first when it tunes
// per run, then runs the filter; a failed truth, tuning or filter sets the
// status and message instead.
ComboRun RunCombo(const StudyConfig& c, const ScenarioConfig& sc, const Combo& cb, int run,
                  uint64_t seed, const FilterData& data, const std::string& truth_error) {
  const std::string& fname = c.filters[cb.filter].name;
  const std::string& nname = c.noises[cb.noise].name;
  ComboRun r;
  r.key = {sc.name, fname, nname, std::to_string(run)};
  if (cb.tune_per_run && truth_error.empty())
    r.id = IdentifyInRun(sc, cb, data, ComboSeed(seed, fname, nname));
  if (!truth_error.empty()) {
    r.status = "truth_failed";
    r.message = truth_error;
  } else if (!cb.tune_failure.empty() || !r.id.failure.empty()) {
    r.status = "tune_failed";
    r.message = cb.tune_per_run ? r.id.failure : cb.tune_failure;
  } else {
    FilterSpec spec = cb.tune_per_run ? r.id.spec : cb.spec;
    if (auto* pf = std::get_if<ParticleOptions>(&spec.filter))
      pf->seed = ComboSeed(seed, fname, nname);
    try {
      r.out = sc.model->run_filter(spec, data);
      if (!r.out.summary.ok) {
        r.status = r.out.summary.status.empty() ? "failed" : r.out.summary.status;
        r.message = r.out.summary.message;
      }
    } catch (const std::exception& e) {
      r.status = "error";
      r.message = e.what();
    }
  }
  return r;
}

// "1" when v is within the bounds b, "0" when not, "" when v is not finite.
std::string InsideText(double v, const double b[2]) {
  return std::isfinite(v) ? std::string(v >= b[0] && v <= b[1] ? "1" : "0") : std::string();
}

// The runs.csv row of a combo's run: its metrics, empty where the filter did
// not run.
std::string RunsRow(const StudyConfig& c, const ScenarioConfig& sc, const Combo& cb, uint64_t seed,
                    const ComboRun& r) {
  const FilterSummary& sum = r.out.summary;
  std::vector<std::string> row = r.key;
  row.push_back(std::to_string(seed));
  row.push_back(r.status);
  for (const char* kind : {"rmse", "mae"}) {
    const auto& v = std::string(kind) == "rmse" ? sum.rmse : sum.mae;
    for (const auto& col : c.state_columns) {
      const int i = Column(sc.model->states, col);
      row.push_back(i >= 0 && size_t(i) < v.size() ? Full(v[i]) : "");
    }
  }
  const bool ran = r.status == "ok" || !r.out.rows.empty();
  // Recorded runs: the NIS after the scenario's burn-in (the prior's transient).
  NoTruthMetrics no_truth;
  if (!c.output_columns.empty())
    no_truth = ComputeNoTruthMetrics(r.out, sc.model->FindMeasurement(sc.truth.measurement).outputs,
                                     sc.burn_in);
  const double mean_nis = sc.recorded ? no_truth.mean_nis : sum.mean_nis;
  const double* nis_bounds = sc.recorded ? no_truth.nis_bounds95 : sum.nis_bounds95;
  row.push_back(ran ? Full(sum.mean_nees) : "");
  row.push_back(ran ? Full(mean_nis) : "");
  row.push_back(ran ? InsideText(sum.mean_nees, sum.nees_bounds95) : "");
  row.push_back(ran ? InsideText(mean_nis, nis_bounds) : "");
  row.push_back(ran ? Full(sum.loglik) : "");
  if (!c.output_columns.empty()) AppendNoTruthMetrics(c, sc, ran, no_truth, &row);
  if (c.identification) AppendIdentification(c, sc, cb, r.id, &row);
  row.push_back(std::to_string(sum.steps));
  row.push_back(r.message);
  return FormatCsvRow(row);
}

// The timing.csv row of a combo's run.
std::string TimingRow(const StudyConfig& c, const ComboRun& r, const SimulationResult& truth) {
  const FilterSummary& sum = r.out.summary;
  std::vector<std::string> timing = r.key;
  // No filter ran when the truth or the tuning failed: no filter cost.
  const bool filtered = r.status != "truth_failed" && r.status != "tune_failed";
  timing.push_back(filtered ? Sig6(sum.us_per_step) : "");
  timing.push_back(filtered ? Sig6(sum.wall_s) : "");
  timing.push_back(Sig6(truth.wall_s));
  if (c.identification) timing.push_back(r.id.attempted ? Sig6(r.id.wall_s) : "");
  return FormatCsvRow(timing);
}

// The steps.csv rows of a combo's run: per-step errors, every `every` steps
// and the last.
std::string StepsRows(const RunContext& ctx, const ScenarioConfig& sc, const ComboRun& r) {
  std::vector<int> err_cols;
  for (const auto& col : ctx.config->state_columns) {
    const int i = Column(sc.model->states, col);
    err_cols.push_back(i >= 0 ? Column(r.out.columns, col + "_err") : -1);
  }
  const int nees_c = Column(r.out.columns, "nees"), nis_c = Column(r.out.columns, "nis");
  std::string text;
  for (size_t k = 0; k < r.out.rows.size(); ++k) {
    if (k % size_t(ctx.every) != 0 && k + 1 != r.out.rows.size()) continue;
    const auto& row = r.out.rows[k];
    std::vector<std::string> step = r.key;
    step.push_back(Sig10(row[0]));
    for (int col : err_cols) step.push_back(col >= 0 ? Sig6(row[col]) : "");
    step.push_back(nees_c >= 0 ? Sig6(row[nees_c]) : "");
    step.push_back(nis_c >= 0 ? Sig6(row[nis_c]) : "");
    text += FormatCsvRow(step);
  }
  return text;
}

// Run `run` of scenario `s`: every combo's filter on the run's data, as the
// text it adds to runs.csv, steps.csv and timing.csv (and its timeseries
// files, for the runs kept).
RunText RunOne(const RunContext& ctx, int s, int run) {
  const StudyConfig& c = *ctx.config;
  const ScenarioConfig& sc = c.scenarios[s];
  const uint64_t seed = DeriveSeed({c.study.seed, uint64_t(s), uint64_t(run)});

  SimulationResult truth;
  std::string truth_error;
  const FilterData data = RunData(sc, run, seed, &truth, &truth_error);

  RunText text;
  for (const Combo& cb : sc.combos) {
    const ComboRun r = RunCombo(c, sc, cb, run, seed, data, truth_error);
    if (r.status != "ok") ++text.failed;
    text.runs += RunsRow(c, sc, cb, seed, r);
    text.timing += TimingRow(c, r, truth);
    text.steps += StepsRows(ctx, sc, r);
    if (ctx.keep.count(run) && !r.out.rows.empty())
      WriteTimeseries(ctx, sc, run, r.key[1], r.key[2], data, r.out);
  }
  return text;
}

// ---------------------------------------------------------------------------

class Progress {
 public:
  Progress(long total, long resumed, bool enabled)
      : total_(total),
        done_(resumed),
        resumed_(resumed),
        enabled_(enabled && total > 0),
        tty_(::isatty(2) == 1),
        start_(std::chrono::steady_clock::now()),
        last_(start_) {}

  void Update(long done, bool final) {
    done_ = done;
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    const double since = std::chrono::duration<double>(now - last_).count();
    if (!final && since < (tty_ ? 0.2 : 5.0)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double rate = elapsed > 0 ? double(done_ - resumed_) / elapsed : 0.0;
    const double eta = rate > 0 ? double(total_ - done_) / rate : 0.0;
    char buf[160];
    if (tty_) {
      const int width = 30;
      const int filled = int(width * double(done_) / double(total_));
      std::string bar(filled, '=');
      if (filled < width) bar += '>' + std::string(width - filled - 1, ' ');
      std::snprintf(buf, sizeof buf, "\r[%s] %ld/%ld runs  %.1f runs/s  ETA %s   ", bar.c_str(),
                    done_, total_, rate, Duration(eta).c_str());
      std::cerr << buf << (final ? "\n" : "") << std::flush;
    } else {
      std::snprintf(buf, sizeof buf, "estlab study: %ld/%ld runs (%.0f %%), %.1f runs/s, ETA %s\n",
                    done_, total_, 100.0 * double(done_) / double(total_), rate,
                    Duration(eta).c_str());
      std::cerr << buf << std::flush;
    }
  }

 private:
  static std::string Duration(double s) {
    char buf[32];
    const long t = long(std::lround(s));
    if (t >= 3600)
      std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
    else if (t >= 60)
      std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
    else
      std::snprintf(buf, sizeof buf, "%lds", t);
    return buf;
  }
  long total_, done_, resumed_;
  bool enabled_, tty_;
  std::chrono::steady_clock::time_point start_, last_;
};

// Keeps only the rows of finished runs (and of runs < `runs`) in a row file.
void KeepFinished(const std::string& path, const std::vector<std::string>& cols,
                  const std::set<std::pair<std::string, long>>& finished) {
  RowFile f = ReadRowFile(path, cols);
  OutputFile out(path);
  out.stream() << FormatCsvRow(cols);
  for (const auto& r : f.rows)
    if (finished.count({r[0], std::stol(r[3])})) out.stream() << FormatCsvRow(r);
  out.Commit();
}

void AppendOrThrow(std::ofstream& file, const std::string& text, const std::string& path) {
  file << text;
  file.flush();
  if (!file) throw InputError("error while writing '" + path + "'");
}

}  // namespace

// Knuth's product of uniforms: exact, and fast for the small lambda of a
// measurement-noise model.
int PoissonCount(Rng& rng, double lambda) {
  if (!(lambda > 0)) return 0;
  const double limit = std::exp(-lambda);
  int k = 0;
  for (double p = rng.Uniform(); p > limit; p *= rng.Uniform()) ++k;
  return k;
}

std::string StudyManifestJson(const StudyConfig& c, const StudyState& state,
                              const std::vector<std::string>& merged_from) {
  JsonWriter j;
  j.BeginObject();
  j.Key("study").Value(c.study.name).Key("title").Value(c.title).Key("paper").Value(c.paper);
  j.Key("description").Value(c.study.description);
  j.Key("status").Value(state.status);
  j.Key("runs").Value(state.runs).Key("shard").Value(state.shard).Key("shards").Value(state.shards);
  j.Key("jobs").Value(state.jobs);
  j.Key("started").Value(state.started).Key("finished").Value(state.finished);
  j.Key("wall_s").Value(state.wall_s);
  j.Key("seed").Value(long(c.study.seed));
  j.Key("seed_rule")
      .Value(
          "truth of run i of scenario s: DeriveSeed({seed, s, i}); particle filter of that run: "
          "DeriveSeed({run seed, FNV1a(\"filter:\" name), FNV1a(\"noise:\" name)}); truth-x0 = "
          "sample: DeriveSeed({run seed, 0x7830})");
  j.Key("scenarios").BeginArray();
  for (size_t s = 0; s < c.scenarios.size(); ++s) {
    const ScenarioConfig& sc = c.scenarios[s];
    j.BeginObject().Key("index").Value(long(s)).Key("name").Value(sc.name);
    j.Key("model").Value(sc.model->name).Key("params").Value(sc.truth.params);
    j.Key("measurement").Value(sc.truth.measurement);
    j.Key("dt").Value(sc.truth.dt).Key("steps").Value(sc.steps);
    j.Key("truth").Value(sc.truth_description);
    j.Key("first_run_seed").Value(std::to_string(DeriveSeed({c.study.seed, uint64_t(s), 0})));
    j.Key("combos").BeginArray();
    for (const Combo& cb : sc.combos)
      j.Value(c.filters[cb.filter].name + "/" + c.noises[cb.noise].name);
    j.EndArray().EndObject();
  }
  j.EndArray();
  j.Key("config_path").Value(c.path).Key("config_hash").Value(HexHash(ConfigHash(c.text)));
  j.Key("config").Value(c.text);
  if (!merged_from.empty()) j.Key("merged_from").Value(merged_from);
  j.Key("estlab_version").Value(ESTLAB_VERSION).Key("git_commit").Value(ESTLAB_GIT_COMMIT);
  j.Key("sundials_version").Value(SUNDIALS_VERSION);
  j.Key("ceres_version").Value(CERES_VERSION_STRING);
  j.Key("eigen_version")
      .Value(std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
             std::to_string(EIGEN_MINOR_VERSION));
  j.Key("boost_version")
      .Value(std::to_string(BOOST_VERSION / 100000) + "." +
             std::to_string(BOOST_VERSION / 100 % 1000) + "." +
             std::to_string(BOOST_VERSION % 100));
  j.Key("compiler").Value(__VERSION__);
  char host[256] = "unknown";
  ::gethostname(host, sizeof host - 1);
  j.Key("host").Value(host);
  j.Key("hardware_threads").Value(long(std::thread::hardware_concurrency()));
  j.EndObject();
  return j.str() + "\n";
}

namespace {

// The end of this process's work: study.state and manifest.json say how it
// ended, and when every run is done the summary files are written.
StudyRunSummary Conclude(const StudyConfig& config, const std::string& dir, double previous_wall,
                         std::chrono::steady_clock::time_point wall_start, StudyState* state,
                         StudyRunSummary* summary) {
  summary->wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  state->wall_s = previous_wall + summary->wall_s;
  state->finished = NowUtc();
  state->status = summary->interrupted ? "interrupted" : "complete";
  WriteStudyState(dir, *state);
  if (!summary->interrupted) {
    summary->report = FinalizeStudy(config, dir);
    state->files = DigestResultFiles(dir);  // for merge to check the folder against
    WriteStudyState(dir, *state);
  }
  WriteTextFile(dir + "/manifest.json", StudyManifestJson(config, *state));
  return *summary;
}

}  // namespace

namespace {

// Step 1 of RunStudy: the results folder, locked by the caller, is new or
// holds results of this very study and shard to resume; study.state says
// "running" from here on. True when it resumes.
bool OpenResults(const StudyConfig& config, const StudyRunOptions& options, int runs, int jobs,
                 StudyState* state) {
  const std::string& dir = options.out_dir;
  const bool resuming = ReadStudyState(dir, state);
  if (resuming) {
    if (state->config_hash != ConfigHash(config.text))
      throw InputError("'" + dir + "' holds results of a different configuration (" + dir +
                       "/config.ini); use another --out or delete it");
    if (runs < state->runs && !options.force)
      throw InputError("'" + dir + "' holds " + std::to_string(state->runs) +
                       " runs per scenario; --runs " + std::to_string(runs) + " would drop runs " +
                       std::to_string(runs) + ".." + std::to_string(state->runs - 1) +
                       " from its results. Use another --out, or --force to keep only the first " +
                       std::to_string(runs));
    if (state->shard != options.shard || state->shards != options.shards)
      throw InputError("'" + dir + "' holds shard " + std::to_string(state->shard) + "/" +
                       std::to_string(state->shards) + ", not " + std::to_string(options.shard) +
                       "/" + std::to_string(options.shards));
  } else if (!FolderIsEmptyButLock(dir)) {
    throw InputError("'" + dir + "' exists and is not a study results folder (no study.state)");
  }
  if (!resuming) WriteTextFile(dir + "/config.ini", config.text);
  state->config_hash = ConfigHash(config.text);
  state->runs = runs;
  state->shard = options.shard;
  state->shards = options.shards;
  state->status = "running";
  state->jobs = jobs;
  state->config_path = fs::absolute(config.path).lexically_normal().string();
  if (!resuming || state->started.empty()) state->started = NowUtc();
  state->finished.clear();
  state->files.clear();  // the files change from here on
  WriteStudyState(dir, *state);
  return resuming;
}

struct RunTask {
  int scenario, run;
};

// Step 2: the runs of this shard still to do. Finished runs (every filter x
// noise row present in all three files, study_integrity.h) keep their rows;
// damaged ones are run again. *total counts the shard's runs, *finished the
// kept ones.
std::vector<RunTask> PendingRuns(const StudyConfig& config, const StudyRunOptions& options,
                                 int runs, long* total, long* finished) {
  const std::string& dir = options.out_dir;
  const RunCoverage coverage = CheckRunCoverage(config, dir, runs, options.shard, options.shards);
  if (coverage.damaged > 0)
    std::cerr << "estlab study: " << coverage.damaged << " finished run(s) in '" << dir
              << "' have rows missing or extra (" << coverage.damage.front()
              << "); running them again\n";
  KeepFinished(dir + "/runs.csv", RunsColumns(config), coverage.complete);
  KeepFinished(dir + "/steps.csv", StepsColumns(config), coverage.complete);
  KeepFinished(dir + "/timing.csv", TimingColumns(config), coverage.complete);
  std::vector<RunTask> tasks;
  *total = 0;
  for (size_t s = 0; s < config.scenarios.size(); ++s)
    for (int i = 0; i < ScenarioRuns(config.scenarios[s], runs); ++i) {
      if (i % options.shards != options.shard - 1) continue;
      ++*total;
      if (!coverage.complete.count({config.scenarios[s].name, i})) tasks.push_back({int(s), i});
    }
  *finished = long(coverage.complete.size());
  return tasks;
}

// The run files, appended to in run order.
struct RunFiles {
  explicit RunFiles(const std::string& dir)
      : dir(dir),
        runs(dir + "/runs.csv", std::ios::app | std::ios::binary),
        steps(dir + "/steps.csv", std::ios::app | std::ios::binary),
        timing(dir + "/timing.csv", std::ios::app | std::ios::binary) {
    if (!runs || !steps || !timing)
      throw InputError("cannot append to the run files in '" + dir + "'");
  }
  // runs.csv last: a run is finished once its rows are there.
  void Append(const RunText& r) {
    AppendOrThrow(steps, r.steps, dir + "/steps.csv");
    AppendOrThrow(timing, r.timing, dir + "/timing.csv");
    AppendOrThrow(runs, r.runs, dir + "/runs.csv");
  }
  std::string dir;
  std::ofstream runs, steps, timing;
};

// The pool's order (study_schedule.h): the tunings, costliest first, then
// the runs scenario by scenario, each scenario's costliest first (recorded
// runs of different lengths). Runs keep their scenarios' order so that the
// writer, which appends in run order, holds at most one scenario's finished
// runs: a study's results stream to disk.
std::vector<size_t> TaskOrder(const StudyConfig& c, const StudyTunings* tunings, size_t n_tune,
                              const std::vector<RunTask>& runs) {
  std::vector<double> tuning_cost(n_tune);
  for (size_t i = 0; i < n_tune; ++i) {
    const ScenarioConfig& sc = c.scenarios[size_t(tunings->ScenarioOf(i))];
    tuning_cost[i] = TuningCost(sc, sc.combos[size_t(tunings->ComboOf(i))]);
  }
  std::vector<size_t> order = LongestFirst(tuning_cost);
  for (size_t first = 0, end = 0; first < runs.size(); first = end) {
    std::vector<double> cost;
    for (end = first; end < runs.size() && runs[end].scenario == runs[first].scenario; ++end)
      cost.push_back(RunCost(c.scenarios[size_t(runs[end].scenario)], runs[end].run));
    for (size_t r : LongestFirst(cost)) order.push_back(n_tune + first + r);
  }
  return order;
}

// Step 3: one task pool (src/core/task_pool.h) for the pending tunings and
// the runs. A run waits only for the tunings of its own scenario; the pool
// starts the tunings first, then the runs (TaskOrder).
// The rows are appended in run order whatever finished first, so the files
// do not depend on jobs or on the order. Returns the runs written.
long RunTasks(const RunContext& ctx, StudyConfig* tuned, StudyTunings* tunings,
              const std::vector<RunTask>& runs, int jobs, const StudyRunOptions& options,
              Progress* progress, StudyRunSummary* summary) {
  const size_t n_tune = tunings ? tunings->Pending() : 0;
  std::vector<std::vector<size_t>> after(n_tune + runs.size());
  for (size_t r = 0; r < runs.size(); ++r)
    for (size_t i = 0; i < n_tune; ++i)
      if (tunings->ScenarioOf(i) == runs[r].scenario) after[n_tune + r].push_back(i);
  std::vector<std::optional<RunText>> results(runs.size());
  RunFiles files(ctx.dir);
  const size_t n_tasks = after.size();
  std::vector<double> wall(n_tasks, 0.0);  // each task's own wall time
  TaskPool pool(jobs, n_tasks,
                [&](size_t task, int) {
                  const auto t0 = std::chrono::steady_clock::now();
                  if (task < n_tune)
                    tunings->Tune(task, tuned);
                  else
                    results[task - n_tune] =
                        RunOne(ctx, runs[task - n_tune].scenario, runs[task - n_tune].run);
                  wall[task] =
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
                },
                {.after = after,
                 .order = TaskOrder(*ctx.config, tunings, n_tune, runs),
                 .stop = options.stop});
  long written = 0;
  for (size_t r = 0; r < runs.size(); ++r) {
    while (!pool.WaitFor(n_tune + r, std::chrono::milliseconds(200)) && !pool.Ended())
      progress->Update(summary->resumed_runs + written, false);
    if (!results[r]) break;  // stopped, or a task failed (Join rethrows)
    files.Append(*results[r]);
    summary->failed_filter_runs += results[r]->failed;
    results[r].reset();
    progress->Update(summary->resumed_runs + ++written, false);
  }
  pool.Join();
  for (size_t task = 0; task < n_tasks; ++task) {
    double chain = 0.0;  // the longest chain ending in this task (one level of waiting)
    for (size_t i : after[task]) chain = std::max(chain, wall[i]);
    summary->task_work_s += wall[task];
    summary->critical_path_s = std::max(summary->critical_path_s, chain + wall[task]);
  }
  return written;
}

// Step 4 (before Conclude): tuned.csv, from this process's tunings or, in a
// complete folder, the earlier one's; counts the failed ones. False when a
// tuning did not run (stopped).
bool RecordTunings(const StudyTunings* tunings, const std::string& dir, StudyRunSummary* summary) {
  if (tunings != nullptr) {
    const StudyTuningSummary t = tunings->Summary();
    summary->tunings = t.total;
    summary->reused_tunings = t.reused;
    if (t.interrupted) return false;
    if (!t.csv.empty()) WriteTextFile(dir + "/tuned.csv", t.csv);
  }
  if (fs::exists(dir + "/tuned.csv")) {
    const CsvText csv = ReadCsvText(dir + "/tuned.csv");
    const int status = csv.Column("status");
    for (const auto& row : csv.rows)
      summary->failed_tunings +=
          status >= 0 && size_t(status) < row.size() && row[status] == "failed";
  }
  return true;
}

}  // namespace

StudyRunSummary RunStudy(const StudyConfig& config, const StudyRunOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError(error);
  const auto wall_start = std::chrono::steady_clock::now();
  const std::string& dir = options.out_dir;
  const int runs = options.runs > 0 ? options.runs : config.study.runs;
  const int jobs = options.jobs > 0 ? options.jobs : config.study.jobs;
  if (fs::exists(dir) && !fs::is_directory(dir))
    throw InputError("'" + dir + "' exists and is not a folder");
  fs::create_directories(dir);
  const FolderLock lock(dir);  // a second process on the same --out fails here
  StudyState state;
  const bool resuming = OpenResults(config, options, runs, jobs, &state);
  const double previous_wall = resuming ? state.wall_s : 0.0;
  StudyRunSummary summary;
  const std::vector<RunTask> tasks =
      PendingRuns(config, options, runs, &summary.total_runs, &summary.resumed_runs);
  WriteTextFile(dir + "/manifest.json", StudyManifestJson(config, state));

  // Tuned noise settings go into a copy of the config, each saved in
  // DIR/tuning/ as it is found and reused on resume. A complete folder
  // (nothing to run, tuned.csv there) needs none.
  StudyConfig tuned_config = config;
  std::optional<StudyTunings> tunings;
  if (!tasks.empty() || !fs::exists(dir + "/tuned.csv")) {
    tunings.emplace(tuned_config,
                    StudyTuningOptions{.dir = dir, .progress = options.progress, .jobs = jobs});
    tunings->ApplyReused(&tuned_config);
  }
  RunContext ctx;
  ctx.config = &tuned_config;
  ctx.dir = dir;
  ctx.every = StepMetricsEvery(config);
  ctx.keep.insert(config.study.keep_runs.begin(), config.study.keep_runs.end());
  if (!ctx.keep.empty())  // the time-series folders, here rather than racing in the workers
    for (const auto& sc : config.scenarios)
      fs::create_directories(fs::path(dir) / "timeseries" / sc.name);
  Progress progress(summary.total_runs, summary.resumed_runs, options.progress);
  const long written = RunTasks(ctx, &tuned_config, tunings ? &*tunings : nullptr, tasks, jobs,
                                options, &progress, &summary);
  const bool tuned = RecordTunings(tunings ? &*tunings : nullptr, dir, &summary);
  summary.finished_runs = summary.resumed_runs + written;
  summary.interrupted = !tuned || summary.finished_runs < summary.total_runs;
  progress.Update(summary.finished_runs, true);
  return Conclude(config, dir, previous_wall, wall_start, &state, &summary);
}

}  // namespace estlab
