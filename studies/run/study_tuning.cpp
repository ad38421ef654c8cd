#include "studies/run/study_tuning.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

#include "src/core/hash.h"
#include "src/core/random.h"
#include "src/io/output_file.h"
#include "studies/results/study_results.h"
#include "studies/run/study_runner_parts.h"

namespace fs = std::filesystem;

namespace estlab {

using study_runner::DataFromTruth;
using study_runner::SampleX0;
using study_runner::Sig10;

std::string TuningFolder(const std::string& dir) { return dir + "/tuning"; }

namespace {

// The r_param column: one kind, or a kind per sensor group ("imu=full gps=scalar").
std::string RParamText(const TunerOptions& o) {
  if (o.r_param_groups.empty()) return NoiseParamName(o.r_param);
  std::string out;
  for (const auto& [group, kind] : o.r_param_groups) {
    if (!out.empty()) out += ' ';
    out += group;
    out += '=';
    out += NoiseParamName(kind);
  }
  return out;
}

constexpr uint64_t kTuneSeedTag = 0x74756E65ull;  // "tune"

std::string JoinValues(const std::vector<double>& v) {
  std::string out;
  for (double x : v) {
    if (!out.empty()) out += ' ';
    out += Sig10(x);
  }
  return out;
}

// "L=0.49;b=0.31": the model parameters fitted with the noise (params =
// tuned ...), "" when none.
std::string TunedParamsText(const TuneResult& r) {
  std::string out;
  for (size_t i = 0; i < r.param_names.size(); ++i)
    out += (i ? ";" : "") + r.param_names[i] + "=" + Sig10(r.param_values[i]);
  return out;
}

std::vector<std::string> TunedColumns() {
  return {"scenario",    "filter",    "noise",      "status",  "datasets", "updates",
          "nll_initial", "nll_tuned", "iterations", "q_param", "r_param",  "qc",
          "q",           "r",         "message",    "params"};
}

// One tuned combo: its tuned.csv row and what it changes in the spec.
struct TunedCombo {
  std::string row;      // tuned.csv line, with its newline
  std::string failure;  // "" when the tuning is usable
  bool q_white_accel = false;
  double qc = 0.0;
  std::vector<double> q, r, params;
};

struct ComboKey {
  int s, c;
  std::string scenario, filter, noise;
  std::string Label() const { return scenario + "/" + filter + "/" + noise; }
  std::string File(const std::string& dir) const {
    return TuningFolder(dir) + "/" + scenario + "." + filter + "." + noise + ".tuned";
  }
};

// --- DIR/tuning/SCENARIO.FILTER.NOISE.tuned: "key = value" lines, numbers
// %.17g (exact), text with \n and \\ escaped.

std::string Exact(const std::vector<double>& v) {
  std::string out;
  char buf[40];
  for (double x : v) {
    std::snprintf(buf, sizeof buf, "%.17g", x);
    if (!out.empty()) out += ' ';
    out.append(buf);
  }
  return out;
}

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '\n' || c == '\\') out += '\\';
    out += c == '\n' ? 'n' : c;
  }
  return out;
}

std::string Unescape(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) {
      out += s[i + 1] == 'n' ? '\n' : s[i + 1];
      ++i;
    } else {
      out += s[i];
    }
  }
  return out;
}

bool ParseValues(const std::string& text, std::vector<double>* out) {
  out->clear();
  std::istringstream in(text);
  for (std::string w; in >> w;) {
    char* end = nullptr;
    const double v = std::strtod(w.c_str(), &end);
    if (end != w.c_str() + w.size()) return false;
    out->push_back(v);
  }
  return true;
}

void SaveTuned(const std::string& dir, uint64_t hash, const ComboKey& key, const TunedCombo& t) {
  std::ostringstream o;
  o << "# estlab study: one tuned noise setting, reused when the study resumes; do not edit\n"
    << "config-hash = " << HashHex(hash) << "\nscenario = " << key.scenario
    << "\nfilter = " << key.filter << "\nnoise = " << key.noise
    << "\nfailure = " << Escape(t.failure) << "\nq-white-accel = " << (t.q_white_accel ? 1 : 0)
    << "\nqc = " << Exact({t.qc}) << "\nq = " << Exact(t.q) << "\nr = " << Exact(t.r)
    << "\nparams = " << Exact(t.params) << "\nrow = " << Escape(t.row) << "\n";
  WriteTextFile(key.File(dir), o.str());
}

// False when there is no saved result for `key` of this configuration (a
// damaged or foreign file is not one: it is tuned again and overwritten).
bool LoadTuned(const std::string& dir, uint64_t hash, const ComboKey& key, TunedCombo* t) {
  std::ifstream in(key.File(dir), std::ios::binary);
  if (!in) return false;
  std::map<std::string, std::string> kv;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find(" = ");
    if (eq == std::string::npos) return false;
    kv[line.substr(0, eq)] = line.size() > eq + 3 ? line.substr(eq + 3) : "";
  }
  for (const char* k : {"config-hash", "scenario", "filter", "noise", "failure", "q-white-accel",
                        "qc", "q", "r", "params", "row"})
    if (!kv.count(k)) return false;
  if (kv["config-hash"] != HashHex(hash) || kv["scenario"] != key.scenario ||
      kv["filter"] != key.filter || kv["noise"] != key.noise)
    return false;
  std::vector<double> qc;
  if (!ParseValues(kv["qc"], &qc) || qc.size() != 1 || !ParseValues(kv["q"], &t->q) ||
      !ParseValues(kv["r"], &t->r) || !ParseValues(kv["params"], &t->params))
    return false;
  t->qc = qc[0];
  t->q_white_accel = kv["q-white-accel"] == "1";
  t->failure = Unescape(kv["failure"]);
  t->row = Unescape(kv["row"]);
  return !t->row.empty() && t->row.back() == '\n';
}

void Apply(const TunedCombo& t, Combo* cb) {
  if (!t.failure.empty()) {
    cb->tune_failure = t.failure;
    return;
  }
  cb->spec.q_white_accel = t.q_white_accel;
  cb->spec.qc = t.qc;
  cb->spec.q = t.q;
  cb->spec.r = t.r;
  cb->spec.params = t.params;
}

// " (2 reused from DIR/tuning)", "" when none.
std::string ReusedNote(int reused, const std::string& dir) {
  if (reused == 0) return "";
  std::ostringstream o;
  o << " (" << reused << " reused from " << TuningFolder(dir) << ")";
  return o.str();
}

// --- Progress: a line per finished tuning, or one line in place on a
// terminal that also shows the running tuner's start and iteration.

class TuningProgress {
 public:
  TuningProgress(int total, int done, bool enabled)
      : total_(total), done_(done), enabled_(enabled), tty_(::isatty(2) == 1) {}

  void Iteration(const std::string& label, const TuneProgress& p) {
    if (!enabled_ || !tty_) return;
    std::lock_guard<std::mutex> lock(mutex_);
    std::ostringstream line;
    line << "\rtuning Q/R: " << done_ << "/" << total_ << " done  " << label << " ";
    if (p.starts > 0)
      line << "start " << p.start << "/" << p.starts;
    else
      line << p.phase;
    line << " iteration " << p.iteration << " " << p.objective << " " << Sig10(p.value) << "\x1b[K";
    std::cerr << line.str() << std::flush;
  }

  void Finished(const std::string& label, double wall_s, const std::string& status) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    if (!enabled_) return;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.1f s", wall_s);
    if (tty_)
      std::cerr << "\rtuning Q/R: " << done_ << "/" << total_ << " done  " << label << " " << status
                << " in " << buf << "\x1b[K" << (done_ == total_ ? "\n" : "") << std::flush;
    else
      std::cerr << "estlab study: tuned " << done_ << "/" << total_ << ": " << label << " "
                << status << " in " << buf << "\n";
  }

 private:
  std::mutex mutex_;
  int total_, done_;
  bool enabled_, tty_;
};

// Tunes one combo: its trajectories (or the scenario's tuning files), then
// the tuner.
TunedCombo TuneOne(const StudyConfig& config, const ComboKey& key, int jobs,
                   TuningProgress* progress) {
  const ScenarioConfig& sc = config.scenarios[key.s];
  const Combo& cb = sc.combos[key.c];
  std::vector<FilterData> datasets;
  std::string failure;
  if (sc.recorded) datasets = sc.tune_runs;
  for (int k = 0; k < cb.tune_datasets && failure.empty() && !sc.recorded; ++k) {
    SimulationSpec sim = sc.truth;
    sim.seed = DeriveSeed({config.study.seed, uint64_t(key.s), kTuneSeedTag, uint64_t(k)});
    if (sc.sample_x0) sim.x0 = SampleX0(sc, sim.seed);
    try {
      const SimulationResult truth = sc.model->simulate(sim);
      if (!truth.ok)
        failure = "tuning trajectory " + std::to_string(k) + ": " + truth.error;
      else
        datasets.push_back(
            DataFromTruth(sc, truth, "tuning trajectory " + std::to_string(k), sim.seed));
    } catch (const std::exception& e) {
      failure = "tuning trajectory " + std::to_string(k) + ": " + e.what();
    }
  }
  TuneResult r;
  if (failure.empty()) {
    TunerOptions options = cb.tuner;
    options.jobs = jobs;  // the gradient's passes (the result does not depend on it)
    const std::string label = key.Label();
    options.progress = [progress, label](const TuneProgress& p) { progress->Iteration(label, p); };
    try {
      r = sc.model->tune(cb.spec, options, datasets);
      if (!r.IsSolutionUsable()) failure = "tuning failed: " + r.message;
    } catch (const std::exception& e) {
      failure = std::string("tuning failed: ") + e.what();
    }
  }
  TunedCombo t;
  t.failure = failure;
  if (failure.empty()) {
    t.q_white_accel = r.tuned_spec.q_white_accel;
    t.qc = r.tuned_spec.qc;
    t.q = r.tuned_spec.q;
    t.r = r.tuned_spec.r;
    t.params = r.tuned_spec.params;
  }
  t.row = FormatCsvRow(
      {key.scenario, key.filter, key.noise, failure.empty() ? TuneStatusName(r.status) : "failed",
       std::to_string(cb.tune_datasets), std::to_string(r.updates), Sig10(r.nll_initial),
       Sig10(r.nll_tuned), std::to_string(r.iterations), NoiseParamName(cb.tuner.q_param),
       RParamText(cb.tuner), r.q_white_accel ? Sig10(r.qc) : "", JoinValues(r.q), JoinValues(r.r),
       failure, TunedParamsText(r)});
  return t;
}

}  // namespace

struct StudyTunings::State {
  std::vector<ComboKey> keys;
  std::vector<std::optional<TunedCombo>> results;  // per key, once tuned or reused
  std::vector<size_t> pending;                     // keys still to tune
  std::unique_ptr<TuningProgress> progress;
};

StudyTunings::StudyTunings(const StudyConfig& config, const StudyTuningOptions& options)
    : options_(options), hash_(ConfigHash(config.text)), state_(std::make_unique<State>()) {
  State& st = *state_;
  for (size_t s = 0; s < config.scenarios.size(); ++s)
    for (size_t c = 0; c < config.scenarios[s].combos.size(); ++c) {
      const Combo& cb = config.scenarios[s].combos[c];
      if (cb.tune && !cb.tune_per_run)  // per run: tuned by the runner, in each run
        st.keys.push_back({int(s), int(c), config.scenarios[s].name, config.filters[cb.filter].name,
                           config.noises[cb.noise].name});
    }
  st.results.resize(st.keys.size());
  int reused = 0;
  for (size_t j = 0; j < st.keys.size(); ++j) {
    TunedCombo t;
    if (!options.dir.empty() && LoadTuned(options.dir, hash_, st.keys[j], &t)) {
      st.results[j] = std::move(t);
      ++reused;
    } else {
      st.pending.push_back(j);
    }
  }
  if (!options.dir.empty() && !st.pending.empty())
    fs::create_directories(TuningFolder(options.dir));
  if (options.progress && !st.pending.empty())
    std::cerr << "estlab study: tuning Q/R of " << st.pending.size() << " 'tuned' noise setting(s)"
              << ReusedNote(reused, options.dir) << "...\n";
  st.progress = std::make_unique<TuningProgress>(int(st.keys.size()), reused, options.progress);
}

StudyTunings::~StudyTunings() = default;

size_t StudyTunings::Pending() const { return state_->pending.size(); }

int StudyTunings::ScenarioOf(size_t i) const { return state_->keys[state_->pending[i]].s; }
int StudyTunings::ComboOf(size_t i) const { return state_->keys[state_->pending[i]].c; }

void StudyTunings::ApplyReused(StudyConfig* config) const {
  const State& st = *state_;
  for (size_t j = 0; j < st.keys.size(); ++j)
    if (st.results[j]) Apply(*st.results[j], &config->scenarios[st.keys[j].s].combos[st.keys[j].c]);
}

void StudyTunings::Tune(size_t i, StudyConfig* config) {
  State& st = *state_;
  const size_t j = st.pending[i];
  const ComboKey& key = st.keys[j];
  const auto t0 = std::chrono::steady_clock::now();
  TunedCombo t = TuneOne(*config, key, options_.jobs, st.progress.get());
  if (!options_.dir.empty()) SaveTuned(options_.dir, hash_, key, t);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  st.progress->Finished(key.Label(), wall, t.failure.empty() ? "tuned" : "failed");
  Apply(t, &config->scenarios[key.s].combos[key.c]);
  st.results[j] = std::move(t);
}

StudyTuningSummary StudyTunings::Summary() const {
  const State& st = *state_;
  StudyTuningSummary summary;
  summary.total = int(st.keys.size());
  summary.reused = summary.total - int(st.pending.size());
  if (st.keys.empty()) return summary;
  summary.csv = FormatCsvRow(TunedColumns());
  for (size_t j = 0; j < st.keys.size(); ++j) {
    if (!st.results[j]) {
      summary.interrupted = true;
      continue;
    }
    summary.csv += st.results[j]->row;
  }
  for (size_t j : st.pending) summary.tuned += st.results[j] ? 1 : 0;
  if (summary.interrupted) summary.csv.clear();
  return summary;
}

}  // namespace estlab
