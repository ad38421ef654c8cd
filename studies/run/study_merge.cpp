// MergeStudies (study_merge.h): the shard folders of one study joined into
// one. Every shard is checked before anything is written: its study.state
// (same configuration, runs and shard count, complete), its files against
// the checksums recorded when it finished, and its runs (exactly those of
// its shard, each whole: study_integrity.h). OUT is built in a temporary
// folder beside it (".estlab-<pid>-<n>.tmp", removed on failure, and by the
// next merge there if this process is killed) and renamed into place, so an
// OUT is either complete or absent.
#include "studies/run/study_merge.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <utility>

#include "src/core/types.h"
#include "src/io/folder_lock.h"
#include "src/io/output_file.h"
#include "src/io/temp_files.h"
#include "studies/report/study_finalize.h"
#include "studies/results/study_integrity.h"
#include "studies/results/study_results.h"
#include "studies/run/study_runner.h"

namespace fs = std::filesystem;

namespace estlab {

namespace {

std::string ShardName(const std::string& dir, const StudyState& s) {
  return "shard '" + dir + "' (" + std::to_string(s.shard) + "/" + std::to_string(s.shards) + ")";
}

// The states of the shard folders, checked to be the complete shards of one
// study, each once, none missing.
std::vector<StudyState> ReadShardStates(const std::vector<std::string>& dirs) {
  std::vector<StudyState> states(dirs.size());
  for (size_t i = 0; i < dirs.size(); ++i)
    if (!ReadStudyState(dirs[i], &states[i]))
      throw InputError("merge: '" + dirs[i] + "' is not a study results folder (no study.state)");
  const StudyState& first = states[0];
  std::set<int> seen;
  for (size_t i = 0; i < dirs.size(); ++i) {
    const StudyState& s = states[i];
    if (s.config_hash != first.config_hash || s.runs != first.runs || s.shards != first.shards)
      throw InputError("merge: '" + dirs[i] +
                       "' is a different study (config, runs or shard count differ from '" +
                       dirs[0] + "')");
    if (!seen.insert(s.shard).second)
      throw InputError("merge: shard " + std::to_string(s.shard) + "/" + std::to_string(s.shards) +
                       " given twice ('" + dirs[i] + "')");
    if (s.status != "complete")
      throw InputError("merge: '" + dirs[i] + "' is " + s.status +
                       "; run its study command again to finish it");
  }
  if (int(seen.size()) != first.shards) {
    std::string missing;
    for (int k = 1; k <= first.shards; ++k)
      if (!seen.count(k)) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
    throw InputError("merge: shard(s) " + missing + " of " + std::to_string(first.shards) +
                     " missing");
  }
  return states;
}

// Throws InputError naming the shard and its first problem: a file changed
// since it finished, or runs missing, damaged or not its own.
void CheckShard(const StudyConfig& config, const std::string& dir, const StudyState& s) {
  const std::string name = "merge: " + ShardName(dir, s);
  if (s.files.empty())
    throw InputError(name +
                     ": no checksums (finished by an older estlab): run its study "
                     "command again (estlab study CONFIG --out " +
                     dir + " --shard " + std::to_string(s.shard) + "/" + std::to_string(s.shards) +
                     ") to record them");
  const std::string changed = CompareDigests(dir, s.files);
  if (!changed.empty())
    throw InputError(name + ": " + changed + "; run its study command again into a new folder");
  const RunCoverage c = CheckRunCoverage(config, dir, s.runs, s.shard, s.shards);
  if (!c.foreign.empty()) throw InputError(name + ": " + c.foreign.front());
  if (!c.damage.empty()) throw InputError(name + ": " + c.damage.front());
  for (const ScenarioConfig& sc : config.scenarios)
    for (long run = s.shard - 1; run < ScenarioRuns(sc, s.runs); run += s.shards)
      if (!c.complete.count({sc.name, run}))
        throw InputError(name + ": run " + std::to_string(run) + " of " + sc.name +
                         " is missing from runs.csv");
}

// Writes the merged study into `dir` (an empty folder).
void WriteMerged(const std::string& dir, const StudyConfig& config, const std::string& config_text,
                 const std::vector<std::string>& shard_dirs,
                 const std::vector<StudyState>& states) {
  std::vector<std::vector<std::string>> runs, steps, timing;
  double wall = 0.0;
  for (size_t i = 0; i < shard_dirs.size(); ++i) {
    const auto add = [&](const std::string& name, const std::vector<std::string>& cols,
                         std::vector<std::vector<std::string>>* rows) {
      RowFile f = ReadRowFile(shard_dirs[i] + "/" + name, cols);
      for (auto& r : f.rows) rows->push_back(std::move(r));
    };
    add("runs.csv", RunsColumns(config), &runs);
    add("steps.csv", StepsColumns(config), &steps);
    add("timing.csv", TimingColumns(config), &timing);
    wall += states[i].wall_s;
    const fs::path ts = fs::path(shard_dirs[i]) / "timeseries";
    if (fs::exists(ts))
      fs::copy(ts, fs::path(dir) / "timeseries",
               fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  }
  WriteTextFile(dir + "/config.ini", config_text);
  // Tuned Q/R: every shard tuned the same way (own seeds); keep one copy.
  const std::string tuned = ReadWholeFile(shard_dirs[0] + "/tuned.csv");
  for (const auto& d : shard_dirs)
    if (ReadWholeFile(d + "/tuned.csv") != tuned)
      throw InputError("merge: " + d + "/tuned.csv differs from " + shard_dirs[0] + "/tuned.csv");
  if (!tuned.empty()) WriteTextFile(dir + "/tuned.csv", tuned);
  const auto write_rows = [&](const std::string& name, const std::vector<std::string>& cols,
                              const std::vector<std::vector<std::string>>& rows) {
    OutputFile out(dir + "/" + name);
    out.stream() << FormatCsvRow(cols);
    for (const auto& r : rows) out.stream() << FormatCsvRow(r);
    out.Commit();
  };
  write_rows("runs.csv", RunsColumns(config), runs);
  write_rows("steps.csv", StepsColumns(config), steps);
  write_rows("timing.csv", TimingColumns(config), timing);
  StudyState merged = states[0];
  merged.shard = merged.shards = 1;
  merged.status = "complete";
  merged.wall_s = wall;
  merged.files.clear();
  for (const auto& s : states) {
    merged.started = std::min(merged.started, s.started);
    merged.finished = std::max(merged.finished, s.finished);
  }
  WriteStudyState(dir, merged);
  FinalizeStudy(config, dir);
  merged.files = DigestResultFiles(dir);
  WriteStudyState(dir, merged);
  WriteTextFile(dir + "/manifest.json", StudyManifestJson(config, merged, shard_dirs));
}

// rename(2): atomic; onto an existing folder only when that is empty.
void Rename(const std::string& from, const std::string& to, const std::string& refused) {
  if (std::rename(from.c_str(), to.c_str()) == 0) return;
  if (errno == ENOTEMPTY || errno == EEXIST) throw InputError(refused);
  throw InputError("merge: cannot rename '" + from + "' to '" + to + "': " + std::strerror(errno));
}

// Renames the finished folder `tmp` to `out`, which is absent or an empty
// folder (holding at most the lock file, whose lock the caller holds).
void CommitFolder(const std::string& tmp, const std::string& out, const std::string& shown) {
  const std::string refused = "merge: '" + shown + "' exists and is not an empty folder";
  std::error_code ec;
  if (fs::exists(out, ec)) {
    if (!fs::is_directory(out) || !FolderIsEmptyButLock(out)) throw InputError(refused);
    fs::remove(fs::path(out) / FolderLock::kFileName, ec);
    Rename(tmp, out, refused);
    return;
  }
  Rename(tmp, out, refused);
}

}  // namespace

void MergeStudies(const std::string& out, const std::vector<std::string>& shard_dirs) {
  if (shard_dirs.empty()) throw InputError("merge: no shard folders given");
  if (fs::exists(out) && !(fs::is_directory(out) && FolderIsEmptyButLock(out)))
    throw InputError("merge: '" + out + "' exists and is not an empty folder");
  const std::vector<StudyState> states = ReadShardStates(shard_dirs);
  const std::string config_text = ReadWholeFile(shard_dirs[0] + "/config.ini");
  const StudyConfig config = LoadResultsConfig(shard_dirs[0], states[0]);
  if (ConfigHash(config_text) != states[0].config_hash)
    throw InputError("merge: " + shard_dirs[0] + "/config.ini does not match its study.state");
  for (size_t i = 0; i < shard_dirs.size(); ++i) CheckShard(config, shard_dirs[i], states[i]);
  // An existing (empty) OUT is locked for the whole merge: a second merge
  // into it fails at once, naming this one's PID.
  std::optional<FolderLock> lock;
  if (fs::is_directory(out)) lock.emplace(out);

  fs::path target = fs::absolute(out).lexically_normal();
  if (!target.has_filename()) target = target.parent_path();  // "out/"
  const fs::path parent = target.parent_path();
  fs::create_directories(parent);
  RemoveStaleTempFiles(parent.string());  // folders of merges that were killed
  const std::string tmp = TempPathBeside((parent / "x").string());
  fs::create_directory(tmp);
  try {
    WriteMerged(tmp, config, config_text, shard_dirs, states);
    CommitFolder(tmp, target.string(), out);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
}

long CountFinishedRuns(const StudyConfig& config, const std::string& dir) {
  const RowFile runs = ReadRowFile(dir + "/runs.csv", RunsColumns(config));
  std::map<std::string, size_t> scenario;  // name -> index in config.scenarios
  for (size_t i = 0; i < config.scenarios.size(); ++i) scenario[config.scenarios[i].name] = i;
  std::map<std::pair<std::string, std::string>, size_t> count;
  for (const auto& r : runs.rows) ++count[{r[0], r[3]}];
  long finished = 0;
  for (const auto& [key, n] : count) {
    const auto s = scenario.find(key.first);
    if (s != scenario.end() && n == config.scenarios[s->second].combos.size()) ++finished;
  }
  return finished;
}

}  // namespace estlab
