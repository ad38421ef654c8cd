#include "studies/report/study_finalize.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "src/io/output_file.h"
#include "src/run/filter_spec.h"
#include "studies/report/study_report.h"
#include "studies/results/study_results.h"

namespace fs = std::filesystem;

namespace estlab {

MetricStats ComputeStats(std::vector<double> v) {
  MetricStats s;
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  s.n = long(v.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (v.empty()) {
    s.mean = s.std = s.var = s.ci95_lo = s.ci95_hi = nan;
    s.p2_5 = s.median = s.p97_5 = s.min = s.max = nan;
    return s;
  }
  double sum = 0.0;
  for (double x : v) sum += x;
  s.mean = sum / double(s.n);
  double ss = 0.0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.var = s.n > 1 ? ss / double(s.n - 1) : 0.0;
  s.std = std::sqrt(s.var);
  const double half = 1.96 * s.std / std::sqrt(double(s.n));
  s.ci95_lo = s.mean - half;
  s.ci95_hi = s.mean + half;
  std::sort(v.begin(), v.end());
  auto quantile = [&](double p) {  // linear interpolation between order statistics
    const double h = p * double(s.n - 1);
    const size_t lo = size_t(std::floor(h));
    const size_t hi = std::min(lo + 1, v.size() - 1);
    return v[lo] + (h - double(lo)) * (v[hi] - v[lo]);
  };
  s.p2_5 = quantile(0.025);
  s.median = quantile(0.5);
  s.p97_5 = quantile(0.975);
  s.min = v.front();
  s.max = v.back();
  return s;
}

namespace {

double ToDouble(const std::string& s) {
  if (s.empty()) return std::numeric_limits<double>::quiet_NaN();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() ? v : std::numeric_limits<double>::quiet_NaN();
}

// "%.10g": summary values for people and plots (still deterministic).
std::string Num(double v) { return FormatResultNumber(v); }

int ColumnIndex(const std::vector<std::string>& cols, const std::string& name) {
  const auto it = std::find(cols.begin(), cols.end(), name);
  return it == cols.end() ? -1 : int(it - cols.begin());
}

std::string GroupKey(const std::string& s, const std::string& f, const std::string& n) {
  return s + "/" + f + "/" + n;
}

// Which runs of each group finished with status ok (group -> flag per run
// index), for picking the ok runs' rows out of steps.csv.
struct OkRuns {
  std::map<std::string, std::vector<char>> flags;

  bool Has(const std::string& g, long run) const {
    const auto it = flags.find(g);
    return it != flags.end() && run >= 0 && size_t(run) < it->second.size() &&
           it->second[size_t(run)];
  }
  void Mark(const std::string& g, long run) {
    std::vector<char>& f = flags[g];
    if (run >= 0) {
      if (f.size() <= size_t(run)) f.resize(size_t(run) + 1, 0);
      f[size_t(run)] = 1;
    }
  }
};

// Adds one runs.csv row to its group: the row counts, and a run with status
// ok adds its index and its value of every metric.
void AddRunRow(const std::vector<std::string>& runs_cols, long expected_runs,
               const std::vector<std::string>& r, StudyTables* tables, OkRuns* ok_runs) {
  const std::string g = GroupKey(r[0], r[1], r[2]);
  GroupValues& gv = tables->groups[g];
  ++gv.runs;
  if (r[5] == "tune_failed") ++gv.tune_failed;
  if (r[5] != "ok") return;
  const long run = std::stol(r[3]);
  ok_runs->Mark(g, run);
  ++gv.ok;
  // Exact capacity (one value per run), not the doubling slack: memory
  // grows by what the runs hold and no more (tests/perf/study_memory_test.cpp).
  if (gv.run_index.empty()) gv.run_index.reserve(size_t(expected_runs));
  gv.run_index.push_back(run);
  for (size_t j = 6; j + 1 < runs_cols.size(); ++j) {
    if (runs_cols[j] == "steps") continue;
    // The identification columns of settings not tuned per run are empty:
    // not kept (only their statistics are used, never aligned with runs).
    if (r[j].empty() && runs_cols[j].rfind("id_", 0) == 0) continue;
    std::vector<double>& v = gv.values[runs_cols[j]];
    if (v.empty()) v.reserve(size_t(expected_runs));
    v.push_back(ToDouble(r[j]));
  }
}

// Per-group values of every metric, runs with status ok only (runs.csv),
// the tuner results (tuned.csv) and every run's timings (timing.csv).
StudyTables ReadStudyTables(const StudyConfig& config, const std::string& dir, long expected_runs,
                            OkRuns* ok_runs) {
  const auto runs_cols = RunsColumns(config);
  bool dropped = false;
  StudyTables tables;
  ForEachRow(dir + "/runs.csv", runs_cols, &dropped, [&](const std::vector<std::string>& r) {
    AddRunRow(runs_cols, expected_runs, r, &tables, ok_runs);
  });
  if (fs::exists(dir + "/tuned.csv")) tables.tuned = ReadCsvText(dir + "/tuned.csv");
  ForEachRow(dir + "/timing.csv", TimingColumns(config), &dropped,
             [&](const std::vector<std::string>& r) {
               GroupValues& gv = tables.groups[GroupKey(r[0], r[1], r[2])];
               gv.us_per_step.push_back(ToDouble(r[4]));
               gv.filter_wall_s.push_back(ToDouble(r[5]));
               if (config.identification && !r[7].empty())
                 gv.identify_wall_s.push_back(ToDouble(r[7]));
             });
  return tables;
}

// The metrics summary.csv gives for every combo of a scenario.
std::vector<std::string> SummaryMetrics(const ScenarioConfig& sc) {
  std::vector<std::string> metrics;
  for (const auto& st : sc.model->states) metrics.push_back("rmse_" + st);
  for (const auto& st : sc.model->states) metrics.push_back("mae_" + st);
  for (const char* m : {"mean_nees", "mean_nis", "nees_in95", "nis_in95", "loglik"})
    metrics.push_back(m);
  if (sc.recorded) {
    for (const char* m : {"nll_per_step", "nis_lo95", "nis_hi95"}) metrics.push_back(m);
    for (const auto& o : sc.model->FindMeasurement(sc.truth.measurement).outputs)
      metrics.push_back("pred_rmse_" + o);
  }
  return metrics;
}

// The identification metrics summary.csv adds for a combo tuned per run.
void AddIdentificationMetrics(const ScenarioConfig& sc, std::vector<std::string>* metrics) {
  for (const auto& id : IdentificationFitColumns()) metrics->push_back(id);
  for (const auto& st : sc.model->states) metrics->push_back("id_q_" + st);
  for (const auto& o : sc.model->FindMeasurement(sc.truth.measurement).outputs)
    metrics->push_back("id_r_" + o);
}

// summary.csv: per group and metric, the statistics over the ok runs.
void WriteSummaryCsv(const StudyConfig& config, const std::string& dir, StudyTables* tables) {
  OutputFile out(dir + "/summary.csv");
  out.stream() << "scenario,filter,noise,metric,runs,n,mean,std,var,ci95_lo,ci95_hi,p2_5,"
                  "median,p97_5,min,max\n";
  for (const ScenarioConfig& sc : config.scenarios) {
    const std::vector<std::string> metrics = SummaryMetrics(sc);
    for (const Combo& cb : sc.combos) {
      const std::string& f = config.filters[cb.filter].name;
      const std::string& n = config.noises[cb.noise].name;
      const auto it = tables->groups.find(GroupKey(sc.name, f, n));
      if (it == tables->groups.end()) continue;
      std::vector<std::string> combo_metrics = metrics;
      if (cb.tune_per_run) AddIdentificationMetrics(sc, &combo_metrics);
      for (const auto& metric : combo_metrics) {
        const MetricStats s = ComputeStats(it->second.values[metric]);
        out.stream() << FormatCsvRow({sc.name, f, n, metric, std::to_string(it->second.runs),
                                      std::to_string(s.n), Num(s.mean), Num(s.std), Num(s.var),
                                      Num(s.ci95_lo), Num(s.ci95_hi), Num(s.p2_5), Num(s.median),
                                      Num(s.p97_5), Num(s.min), Num(s.max)});
      }
    }
  }
  out.Commit();
}

// One group's sums at one time over the ok runs, for time_metrics.csv.
struct TimeAcc {
  long n = 0, n_nees = 0, n_nis = 0;
  std::vector<double> sq;
  double nees = 0, nis = 0;
};
using TimeAccs = std::map<std::string, std::map<double, TimeAcc>>;  // group -> t -> sums

// Streams steps.csv and sums, per group and time over the ok runs, the
// squared errors of every state column, the NEES and the NIS.
TimeAccs AccumulateSteps(const StudyConfig& config, const std::string& dir, const OkRuns& ok_runs) {
  const auto steps_cols = StepsColumns(config);
  const int t_col = 4;
  const int nees_col = ColumnIndex(steps_cols, "nees");
  const int nis_col = ColumnIndex(steps_cols, "nis");
  TimeAccs acc;
  const size_t ns = config.state_columns.size();
  bool dropped = false;
  ForEachRow(dir + "/steps.csv", steps_cols, &dropped, [&](const std::vector<std::string>& r) {
    const std::string g = GroupKey(r[0], r[1], r[2]);
    if (!ok_runs.Has(g, std::stol(r[3]))) return;
    TimeAcc& a = acc[g][ToDouble(r[t_col])];
    if (a.sq.empty()) a.sq.assign(ns, 0.0);
    ++a.n;
    for (size_t i = 0; i < ns; ++i) {
      const double e = ToDouble(r[t_col + 1 + i]);
      if (std::isfinite(e)) a.sq[i] += e * e;
    }
    const double nees = ToDouble(r[nees_col]), nis = ToDouble(r[nis_col]);
    if (std::isfinite(nees)) a.nees += nees, ++a.n_nees;
    if (std::isfinite(nis)) a.nis += nis, ++a.n_nis;
  });
  return acc;
}

// The time_metrics.csv row of one group (`key`: scenario, filter, noise) at
// time t: the RMSE of every state column, the mean NEES and NIS and their bounds.
std::vector<std::string> TimeMetricsRow(const StudyConfig& config, const ScenarioConfig& sc,
                                        const std::vector<std::string>& key, double t,
                                        const TimeAcc& a) {
  const int nx = int(sc.model->states.size());
  const int nz = int(sc.model->FindMeasurement(sc.truth.measurement).outputs.size());
  std::vector<std::string> row = {key[0], key[1], key[2], Num(t), std::to_string(a.n)};
  for (size_t i = 0; i < config.state_columns.size(); ++i) {
    const bool has = std::find(sc.model->states.begin(), sc.model->states.end(),
                               config.state_columns[i]) != sc.model->states.end();
    row.push_back(has && sc.has_truth ? Num(std::sqrt(a.sq[i] / double(a.n))) : "");
  }
  // Bounds of the average over N runs at one time: N * mean ~ chi2(N dim).
  double b[2];
  ChiSquareBounds95(a.n_nees, nx, b);
  row.push_back(a.n_nees ? Num(a.nees / double(a.n_nees)) : "");
  row.push_back(Num(b[0]));
  row.push_back(Num(b[1]));
  ChiSquareBounds95(a.n_nis, nz, b);
  row.push_back(a.n_nis ? Num(a.nis / double(a.n_nis)) : "");
  row.push_back(Num(b[0]));
  row.push_back(Num(b[1]));
  return row;
}

// time_metrics.csv: per group and time, over the ok runs.
void WriteTimeMetricsCsv(const StudyConfig& config, const std::string& dir, const TimeAccs& acc) {
  OutputFile out(dir + "/time_metrics.csv");
  std::vector<std::string> header = {"scenario", "filter", "noise", "t", "n"};
  for (const auto& st : config.state_columns) header.push_back("rmse_" + st);
  for (const char* c : {"mean_nees", "nees_lo95", "nees_hi95", "mean_nis", "nis_lo95", "nis_hi95"})
    header.push_back(c);
  out.stream() << FormatCsvRow(header);
  for (const ScenarioConfig& sc : config.scenarios) {
    for (const Combo& cb : sc.combos) {
      const std::string& f = config.filters[cb.filter].name;
      const std::string& n = config.noises[cb.noise].name;
      const auto it = acc.find(GroupKey(sc.name, f, n));
      if (it == acc.end()) continue;
      for (const auto& [t, a] : it->second)
        out.stream() << FormatCsvRow(TimeMetricsRow(config, sc, {sc.name, f, n}, t, a));
    }
  }
  out.Commit();
}

}  // namespace

std::string FinalizeStudy(const StudyConfig& config, const std::string& dir) {
  // The run files are streamed, never held whole: a study's memory must not
  // grow with its number of runs (tests/perf/study_memory_test.cpp).
  CanonicalizeRunFiles(config, dir);

  StudyState state;
  ReadStudyState(dir, &state);
  const long expected_runs = std::max(1L, long(state.runs));
  OkRuns ok_runs;
  StudyTables tables = ReadStudyTables(config, dir, expected_runs, &ok_runs);
  WriteSummaryCsv(config, dir, &tables);
  WriteTimeMetricsCsv(config, dir, AccumulateSteps(config, dir, ok_runs));

  const std::string identification = IdentificationCsv(config, tables);
  if (!identification.empty()) WriteTextFile(dir + "/identification.csv", identification);
  const std::string report = StudyReportMarkdown(config, tables, state);
  WriteTextFile(dir + "/report.md", report);
  return report;
}

}  // namespace estlab
