#include "studies/study_results.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "src/core/hash.h"
#include "src/core/types.h"
#include "src/io/folder_lock.h"
#include "src/io/output_file.h"
#include "studies/study_report.h"
#include "studies/study_runner.h"

namespace fs = std::filesystem;

namespace estlab {

std::vector<std::string> RunsColumns(const StudyConfig& config) {
  std::vector<std::string> c = {"scenario", "filter", "noise", "run", "seed", "status"};
  for (const auto& s : config.state_columns) c.push_back("rmse_" + s);
  for (const auto& s : config.state_columns) c.push_back("mae_" + s);
  for (const char* m : {"mean_nees", "mean_nis", "nees_in95", "nis_in95", "loglik"}) c.push_back(m);
  // Studies with recorded scenarios: the metrics that need no truth.
  if (!config.output_columns.empty()) {
    for (const char* m : {"nll_per_step", "nis_lo95", "nis_hi95"}) c.push_back(m);
    for (const auto& o : config.output_columns) c.push_back("pred_rmse_" + o);
  }
  if (config.identification)
    for (const auto& id : IdentificationColumns(config)) c.push_back(id);
  c.push_back("steps");
  c.push_back("message");
  return c;
}

std::vector<std::string> IdentificationFitColumns() {
  return {"id_q_err", "id_r_err", "id_iterations", "id_converged", "id_at_bound"};
}

std::vector<std::string> IdentificationColumns(const StudyConfig& config) {
  std::vector<std::string> c = IdentificationFitColumns();
  for (const auto& s : config.state_columns) c.push_back("id_q_" + s);
  for (const auto& o : config.identification_outputs) c.push_back("id_r_" + o);
  return c;
}

std::vector<std::string> StepsColumns(const StudyConfig& config) {
  std::vector<std::string> c = {"scenario", "filter", "noise", "run", "t"};
  for (const auto& s : config.state_columns) c.push_back("err_" + s);
  c.push_back("nees");
  c.push_back("nis");
  return c;
}

std::vector<std::string> TimingColumns(const StudyConfig& config) {
  std::vector<std::string> c = {"scenario",    "filter",        "noise",       "run",
                                "us_per_step", "filter_wall_s", "truth_wall_s"};
  if (config.identification) c.push_back("identify_wall_s");
  return c;
}

namespace {

// Splits one CSV line; fields may be double-quoted with "" for a quote.
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> fields;
  std::string cur;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  fields.push_back(cur);
  return fields;
}

std::string Join(const std::vector<std::string>& v, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}

double ToDouble(const std::string& s) {
  if (s.empty()) return std::numeric_limits<double>::quiet_NaN();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() ? v : std::numeric_limits<double>::quiet_NaN();
}

// "%.10g": summary values for people and plots (still deterministic).
std::string Num(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "" : (v > 0 ? "inf" : "-inf");
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

}  // namespace

std::string FormatCsvRow(const std::vector<std::string>& fields) {
  std::string out;
  for (size_t i = 0; i < fields.size(); ++i) {
    if (i) out += ',';
    const std::string& f = fields[i];
    if (f.find_first_of(",\"\n") == std::string::npos) {
      out += f;
    } else {
      out += '"';
      for (char c : f) {
        if (c == '\n') c = ' ';
        if (c == '"') out += '"';
        out += c;
      }
      out += '"';
    }
  }
  return out + "\n";
}

int CsvText::Column(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return int(i);
  return -1;
}

CsvText ReadCsvText(const std::string& path) {
  if (!fs::exists(path)) throw InputError("cannot read '" + path + "'");
  CsvText t;
  std::istringstream in(ReadWholeFile(path));
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (header) {
      t.columns = SplitCsv(line);
      header = false;
    } else if (!line.empty()) {
      t.rows.push_back(SplitCsv(line));
      if (t.rows.back().size() != t.columns.size())
        throw InputError(path + ": row " + std::to_string(t.rows.size() + 1) + " has " +
                         std::to_string(t.rows.back().size()) + " fields, the header " +
                         std::to_string(t.columns.size()));
    }
  }
  return t;
}

namespace {

// Calls visit(fields) for every complete row of a results file, as
// ReadRowFile reads it (header checked; a last line without a newline and rows
// of the wrong width are dropped, *dropped set) but one line at a time, so
// that memory does not grow with the file.
template <class Visit>
void StreamRowFile(const std::string& path, const std::vector<std::string>& columns, bool* dropped,
                   Visit&& visit) {
  *dropped = false;
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (in.eof()) {  // no newline: an interrupted write
      *dropped = true;
      break;
    }
    std::vector<std::string> fields = SplitCsv(line);
    if (header) {
      if (fields != columns)
        throw InputError(path + ": header differs from this study's (" + Join(columns, ",") +
                         "); it belongs to another study or version");
      header = false;
      continue;
    }
    if (fields.size() != columns.size()) {
      *dropped = true;
      continue;
    }
    visit(fields);
  }
}

}  // namespace

RowFile ReadRowFile(const std::string& path, const std::vector<std::string>& columns) {
  RowFile f;
  if (!fs::exists(path)) return f;
  f.existed = true;
  StreamRowFile(path, columns, &f.dropped_partial,
                [&](std::vector<std::string>& fields) { f.rows.push_back(std::move(fields)); });
  return f;
}

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void ForEachRow(const std::string& path, const std::vector<std::string>& columns, bool* dropped,
                const std::function<void(const std::vector<std::string>&)>& visit) {
  StreamRowFile(path, columns, dropped, visit);
}

// ---------------------------------------------------------------------------

StudyConfig LoadResultsConfig(const std::string& dir, const StudyState& state) {
  const std::string copy = dir + "/config.ini";
  const bool original_folder =
      !state.config_path.empty() && fs::is_directory(fs::path(state.config_path).parent_path());
  return ParseStudyConfig(ReadWholeFile(copy), original_folder ? state.config_path : copy);
}

void WriteStudyState(const std::string& dir, const StudyState& s) {
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(s.config_hash));
  std::ostringstream out;
  out << "# estlab study state: used to resume and merge; do not edit\n"
      << "config-hash = " << hash << "\nruns = " << s.runs << "\nshard = " << s.shard << "/"
      << s.shards << "\nstatus = " << s.status << "\nstarted = " << s.started
      << "\nfinished = " << s.finished << "\nwall-s = " << Num(s.wall_s) << "\njobs = " << s.jobs
      << "\n";
  if (!s.config_path.empty()) out << "config-path = " << s.config_path << "\n";
  for (const FileDigest& f : s.files)
    out << "file = " << f.bytes << " " << HashHex(f.fnv) << " " << f.path << "\n";
  WriteTextFile(dir + "/study.state", out.str());
}

bool ReadStudyState(const std::string& dir, StudyState* s) {
  const std::string path = dir + "/study.state";
  if (!fs::exists(path)) return false;
  std::istringstream in(ReadWholeFile(path));
  std::string line;
  std::map<std::string, std::string> kv;
  std::vector<std::string> files;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto eq = line.find(" = ");
    if (eq == std::string::npos) continue;
    if (line.compare(0, eq, "file") == 0)
      files.push_back(line.substr(eq + 3));
    else
      kv[line.substr(0, eq)] = line.substr(eq + 3);
  }
  try {
    s->config_hash = std::stoull(kv.at("config-hash"), nullptr, 16);
    s->runs = std::stoi(kv.at("runs"));
    const std::string shard = kv.at("shard");
    s->shard = std::stoi(shard.substr(0, shard.find('/')));
    s->shards = std::stoi(shard.substr(shard.find('/') + 1));
    s->status = kv["status"];
    s->started = kv["started"];
    s->finished = kv["finished"];
    s->wall_s = kv["wall-s"].empty() ? 0.0 : std::stod(kv["wall-s"]);
    s->jobs = kv["jobs"].empty() ? 1 : std::stoi(kv["jobs"]);
    s->config_path = kv["config-path"];
    s->files.clear();
    for (const std::string& f : files) {  // "BYTES FNV PATH"
      const size_t a = f.find(' '), b = f.find(' ', a + 1);
      if (a == std::string::npos || b == std::string::npos) throw InputError("file line");
      s->files.push_back({f.substr(b + 1), std::stoull(f.substr(0, a)),
                          std::stoull(f.substr(a + 1, b - a - 1), nullptr, 16)});
    }
  } catch (const std::exception&) {
    throw InputError(path + ": damaged study state file");
  }
  return true;
}

// ---------------------------------------------------------------------------

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

struct Indexes {
  std::map<std::string, int> scenario, filter, noise;
  explicit Indexes(const StudyConfig& c) {
    for (size_t i = 0; i < c.scenarios.size(); ++i) scenario[c.scenarios[i].name] = int(i);
    for (size_t i = 0; i < c.filters.size(); ++i) filter[c.filters[i].name] = int(i);
    for (size_t i = 0; i < c.noises.size(); ++i) noise[c.noises[i].name] = int(i);
  }
};

// A row's place in the canonical order: (scenario, run, filter, noise)
// indexes, compared lexicographically. Throws InputError for a row of a
// scenario, filter or noise the study does not have.
using CanonicalKey = std::array<long, 4>;
CanonicalKey RowKey(const Indexes& idx, const std::string& path,
                    const std::vector<std::string>& r) {
  const auto s = idx.scenario.find(r[0]);
  const auto f = idx.filter.find(r[1]);
  const auto n = idx.noise.find(r[2]);
  if (s == idx.scenario.end() || f == idx.filter.end() || n == idx.noise.end())
    throw InputError(path + ": row for " + r[0] + "/" + r[1] + "/" + r[2] +
                     " which this study does not have");
  return {s->second, std::stol(r[3]), f->second, n->second};
}

// Sorts rows (scenario, filter, noise, run, ...) into canonical order,
// keeping the order of rows with equal keys.
void SortCanonical(const StudyConfig& c, const std::string& path,
                   std::vector<std::vector<std::string>>* rows) {
  const Indexes idx(c);
  std::vector<CanonicalKey> keys;
  keys.reserve(rows->size());
  for (const auto& r : *rows) keys.push_back(RowKey(idx, path, r));
  std::vector<size_t> order(rows->size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t x, size_t y) { return keys[x] < keys[y]; });
  std::vector<std::vector<std::string>> sorted;
  sorted.reserve(rows->size());
  for (size_t i : order) sorted.push_back(std::move((*rows)[i]));
  *rows = std::move(sorted);
}

void WriteRowFile(const std::string& path, const std::vector<std::string>& columns,
                  const std::vector<std::vector<std::string>>& rows) {
  OutputFile out(path);
  out.stream() << FormatCsvRow(columns);
  for (const auto& r : rows) out.stream() << FormatCsvRow(r);
  out.Commit();
}

int ColumnIndex(const std::vector<std::string>& cols, const std::string& name) {
  const auto it = std::find(cols.begin(), cols.end(), name);
  return it == cols.end() ? -1 : int(it - cols.begin());
}

std::string GroupKey(const std::string& s, const std::string& f, const std::string& n) {
  return s + "/" + f + "/" + n;
}

}  // namespace

namespace {

// Puts a results file into canonical order (SortCanonical). The runner
// appends runs in that order, so usually one streaming pass finds the file
// already canonical and complete and leaves it alone; otherwise (shards
// merged, an interrupted write) the file is read, sorted and rewritten.
void Canonicalize(const StudyConfig& c, const std::string& path,
                  const std::vector<std::string>& columns) {
  if (!fs::exists(path)) {
    WriteRowFile(path, columns, {});
    return;
  }
  const Indexes idx(c);
  CanonicalKey last = {-1, -1, -1, -1};
  bool sorted = true, dropped = false;
  StreamRowFile(path, columns, &dropped, [&](const std::vector<std::string>& r) {
    const CanonicalKey key = RowKey(idx, path, r);
    if (key < last) sorted = false;
    last = key;
  });
  if (sorted && !dropped) return;
  RowFile rows = ReadRowFile(path, columns);
  SortCanonical(c, path, &rows.rows);
  WriteRowFile(path, columns, rows.rows);
}

}  // namespace

long CountFinishedRuns(const StudyConfig& config, const std::string& dir) {
  const RowFile runs = ReadRowFile(dir + "/runs.csv", RunsColumns(config));
  const Indexes idx(config);
  std::map<std::pair<std::string, std::string>, size_t> count;
  for (const auto& r : runs.rows) ++count[{r[0], r[3]}];
  long finished = 0;
  for (const auto& [key, n] : count) {
    const auto s = idx.scenario.find(key.first);
    if (s != idx.scenario.end() && n == config.scenarios[s->second].combos.size()) ++finished;
  }
  return finished;
}

namespace {

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
  StreamRowFile(dir + "/runs.csv", runs_cols, &dropped, [&](const std::vector<std::string>& r) {
    AddRunRow(runs_cols, expected_runs, r, &tables, ok_runs);
  });
  if (fs::exists(dir + "/tuned.csv")) tables.tuned = ReadCsvText(dir + "/tuned.csv");
  StreamRowFile(dir + "/timing.csv", TimingColumns(config), &dropped,
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
  StreamRowFile(dir + "/steps.csv", steps_cols, &dropped, [&](const std::vector<std::string>& r) {
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
  Canonicalize(config, dir + "/runs.csv", RunsColumns(config));
  Canonicalize(config, dir + "/steps.csv", StepsColumns(config));
  Canonicalize(config, dir + "/timing.csv", TimingColumns(config));

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
