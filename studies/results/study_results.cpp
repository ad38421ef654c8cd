#include "studies/results/study_results.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

#include "src/core/hash.h"
#include "src/core/types.h"
#include "src/io/folder_lock.h"
#include "src/io/output_file.h"

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

}  // namespace

// "%.10g": summary values for people and plots (still deterministic).
std::string FormatResultNumber(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "" : (v > 0 ? "inf" : "-inf");
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

namespace {

std::string Num(double v) { return FormatResultNumber(v); }

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

void CanonicalizeRunFiles(const StudyConfig& config, const std::string& dir) {
  Canonicalize(config, dir + "/runs.csv", RunsColumns(config));
  Canonicalize(config, dir + "/steps.csv", StepsColumns(config));
  Canonicalize(config, dir + "/timing.csv", TimingColumns(config));
}

}  // namespace estlab
