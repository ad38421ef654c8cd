#include "studies/results/study_integrity.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>

#include "src/core/hash.h"

namespace fs = std::filesystem;

namespace estlab {

int StepMetricsEvery(const StudyConfig& config) {
  if (config.study.step_metrics_every > 0) return config.study.step_metrics_every;
  int max_steps = 1;
  for (const auto& sc : config.scenarios) max_steps = std::max(max_steps, sc.steps + 1);
  return (max_steps + 99) / 100;
}

long ExpectedStepRows(long steps, int every) {
  if (steps <= 0) return 0;
  const long sampled = (steps - 1) / every + 1;  // k = 0, every, ... <= steps - 1
  return sampled + ((steps - 1) % every != 0 ? 1 : 0);
}

namespace {

constexpr size_t kMaxProblemsPerKind = 3;

// Row counts of one file per (run, filter x noise setting) of a scenario.
struct ScenarioCounts {
  int combos = 0;
  long runs = 0;
  std::map<std::pair<std::string, std::string>, int> combo;  // (filter, noise) -> index
  std::vector<uint32_t> runs_rows, timing_rows, steps_rows;  // [run * combos + combo]
  std::vector<long> steps;                                   // runs.csv's steps column
};

class Coverage {
 public:
  Coverage(const StudyConfig& config, int runs, int shard, int shards)
      : config_(config), shard_(shard), shards_(shards) {
    for (const ScenarioConfig& sc : config.scenarios) {
      ScenarioCounts& c = counts_[sc.name];
      c.combos = int(sc.combos.size());
      c.runs = ScenarioRuns(sc, runs);
      for (size_t i = 0; i < sc.combos.size(); ++i)
        c.combo[{config.filters[sc.combos[i].filter].name,
                 config.noises[sc.combos[i].noise].name}] = int(i);
      const size_t cells = size_t(c.runs) * size_t(c.combos);
      c.runs_rows.assign(cells, 0);
      c.timing_rows.assign(cells, 0);
      c.steps_rows.assign(cells, 0);
      c.steps.assign(cells, -1);
    }
  }

  // Counts a row (scenario, filter, noise, run, ...) of `file`; returns the
  // cell, or -1 for a row of a run this shard does not have (a problem).
  long Count(const std::string& file, const std::vector<std::string>& r, ScenarioCounts** out) {
    const auto s = counts_.find(r[0]);
    if (s == counts_.end()) return Foreign(file, r, "a scenario this study does not have");
    ScenarioCounts& c = s->second;
    const auto cb = c.combo.find({r[1], r[2]});
    if (cb == c.combo.end()) return Foreign(file, r, "a filter x noise setting it does not have");
    char* end = nullptr;
    const long run = std::strtol(r[3].c_str(), &end, 10);
    if (r[3].empty() || *end != '\0' || run < 0 || run >= c.runs || run % shards_ != shard_ - 1)
      return Foreign(file, r,
                     "a run this folder's shard " + std::to_string(shard_) + "/" +
                         std::to_string(shards_) + " does not have");
    *out = &c;
    return run * c.combos + cb->second;
  }

  void Finish(RunCoverage* result, int every) {
    for (const ScenarioConfig& sc : config_.scenarios) {
      const ScenarioCounts& c = counts_[sc.name];
      for (long run = shard_ - 1; run < c.runs; run += shards_) {
        bool finished = true;  // every setting has its runs.csv row
        for (int k = 0; k < c.combos; ++k) finished &= c.runs_rows[size_t(run * c.combos + k)] > 0;
        if (!finished) continue;  // interrupted or not run: not damage
        std::string damage;
        for (int k = 0; k < c.combos && damage.empty(); ++k) {
          const size_t i = size_t(run * c.combos + k);
          const std::string what = "run " + std::to_string(run) + " of " + sc.name + " (" +
                                   config_.filters[sc.combos[k].filter].name + "/" +
                                   config_.noises[sc.combos[k].noise].name + ")";
          const long expected = ExpectedStepRows(c.steps[i], every);
          if (c.runs_rows[i] != 1)
            damage = "runs.csv has " + std::to_string(c.runs_rows[i]) + " rows of " + what;
          else if (c.timing_rows[i] != 1)
            damage = "timing.csv has " + std::to_string(c.timing_rows[i]) + " rows of " + what +
                     ", not 1";
          else if (long(c.steps_rows[i]) != expected)
            damage = "steps.csv has " + std::to_string(c.steps_rows[i]) + " rows of " + what +
                     ", its " + std::to_string(c.steps[i]) + " steps make " +
                     std::to_string(expected);
        }
        if (damage.empty()) {
          result->complete.insert({sc.name, run});
        } else {
          if (result->damaged++ < long(kMaxProblemsPerKind)) result->damage.push_back(damage);
        }
      }
    }
    if (result->damaged > long(kMaxProblemsPerKind))
      result->damage.push_back("... and " +
                               std::to_string(result->damaged - long(kMaxProblemsPerKind)) +
                               " more damaged runs");
    result->foreign = foreign_problems_;
    if (foreign_ > long(kMaxProblemsPerKind))
      result->foreign.push_back("... and " + std::to_string(foreign_ - long(kMaxProblemsPerKind)) +
                                " more rows of runs the folder should not hold");
  }

 private:
  long Foreign(const std::string& file, const std::vector<std::string>& r, const std::string& why) {
    if (foreign_++ < long(kMaxProblemsPerKind))
      foreign_problems_.push_back(file + " has a row of " + r[0] + "/" + r[1] + "/" + r[2] +
                                  " run " + r[3] + ", " + why);
    return -1;
  }

  const StudyConfig& config_;
  int shard_, shards_;
  std::map<std::string, ScenarioCounts> counts_;
  long foreign_ = 0;
  std::vector<std::string> foreign_problems_;
};

}  // namespace

RunCoverage CheckRunCoverage(const StudyConfig& config, const std::string& dir, int runs, int shard,
                             int shards) {
  Coverage coverage(config, runs, shard, shards);
  const std::vector<std::string> runs_cols = RunsColumns(config);
  const size_t steps_col =
      size_t(std::find(runs_cols.begin(), runs_cols.end(), "steps") - runs_cols.begin());
  bool dropped = false;
  ScenarioCounts* c = nullptr;
  ForEachRow(dir + "/runs.csv", runs_cols, &dropped, [&](const std::vector<std::string>& r) {
    const long i = coverage.Count("runs.csv", r, &c);
    if (i < 0) return;
    ++c->runs_rows[size_t(i)];
    c->steps[size_t(i)] = std::strtol(r[steps_col].c_str(), nullptr, 10);
  });
  ForEachRow(dir + "/timing.csv", TimingColumns(config), &dropped,
             [&](const std::vector<std::string>& r) {
               const long i = coverage.Count("timing.csv", r, &c);
               if (i >= 0) ++c->timing_rows[size_t(i)];
             });
  ForEachRow(dir + "/steps.csv", StepsColumns(config), &dropped,
             [&](const std::vector<std::string>& r) {
               const long i = coverage.Count("steps.csv", r, &c);
               if (i >= 0) ++c->steps_rows[size_t(i)];
             });
  RunCoverage result;
  coverage.Finish(&result, StepMetricsEvery(config));
  return result;
}

namespace {

FileDigest Digest(const std::string& dir, const std::string& path) {
  FileDigest d;
  d.path = path;
  d.fnv = Fnv1a64("");
  std::ifstream in(dir + "/" + path, std::ios::binary);
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    const size_t n = size_t(in.gcount());
    d.fnv = Fnv1a64(std::string_view(buf.data(), n), d.fnv);
    d.bytes += n;
  }
  return d;
}

}  // namespace

std::vector<FileDigest> DigestResultFiles(const std::string& dir) {
  std::vector<std::string> paths;
  for (const char* f : {"config.ini", "runs.csv", "steps.csv", "timing.csv", "tuned.csv"})
    if (fs::is_regular_file(fs::path(dir) / f)) paths.push_back(f);
  const fs::path ts = fs::path(dir) / "timeseries";
  if (fs::is_directory(ts))
    for (const auto& e : fs::recursive_directory_iterator(ts))
      if (e.is_regular_file()) paths.push_back(fs::relative(e.path(), dir).string());
  std::sort(paths.begin(), paths.end());
  std::vector<FileDigest> out;
  for (const auto& p : paths) out.push_back(Digest(dir, p));
  return out;
}

std::string CompareDigests(const std::string& dir, const std::vector<FileDigest>& recorded) {
  for (const FileDigest& f : recorded) {
    if (!fs::is_regular_file(fs::path(dir) / f.path)) return f.path + " is missing";
    const FileDigest now = Digest(dir, f.path);
    if (now.bytes != f.bytes)
      return f.path + " has " + std::to_string(now.bytes) + " bytes, " + std::to_string(f.bytes) +
             " when the study finished (cut off or changed)";
    if (now.fnv != f.fnv)
      return f.path + " changed after the study finished (checksum " + HashHex(now.fnv) +
             ", then " + HashHex(f.fnv) + ")";
  }
  return "";
}

}  // namespace estlab
