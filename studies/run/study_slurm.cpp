#include "studies/run/study_slurm.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "src/core/types.h"
#include "src/io/folder_lock.h"
#include "src/io/output_file.h"
#include "src/io/shell.h"
#include "studies/results/study_results.h"
#include "studies/run/study_merge.h"
#include "studies/run/study_runner_parts.h"

namespace fs = std::filesystem;

namespace estlab {

bool SlurmOptions::IsValid(std::string* error) const {
  if (shards < 1 || shards > 100000)
    return *error = "--slurm: the number of shards must be in 1..100000", false;
  if (cpus_per_task < 0 || cpus_per_task > 1024) return *error = "--jobs must be in 1..1024", false;
  if (estlab.empty() || !fs::path(estlab).is_absolute())
    return *error = "the estlab binary's path must be absolute", false;
  if (config_path.empty()) return *error = "no study file", false;
  std::vector<std::string> words;
  std::string why;
  if (!SplitWords(sbatch_opts, &words, &why)) return *error = "--slurm-opts: " + why, false;
  for (const auto& [what, path] :
       {std::pair<const char*, const std::string&>{"the study file", config_path},
        {"the estlab binary", estlab}}) {
    const size_t at = FindControlCharacter(path);
    if (at != std::string::npos)
      return *error = std::string(what) + " '" + path + "' holds a control character at " +
                      std::to_string(at + 1) + "; Slurm scripts cannot carry it",
             false;
  }
  return true;
}

namespace {

using study_runner::NowUtc;

std::string SlurmFolder(const std::string& out) {
  fs::path p = fs::absolute(out).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  return p.string() + ".slurm";
}

std::string AbsoluteOut(const std::string& out) {
  fs::path p = fs::absolute(out).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  return p.string();
}

// Refuses an OUT the scripts and sbatch cannot carry as given: a control
// character (a newline would end a script line) or '%' (sbatch's --output
// reads it as a pattern). Spaces, quotes, '$' and non-ASCII are quoted.
void CheckOutPath(const std::string& given, const std::string& absolute) {
  const size_t at = FindControlCharacter(absolute);
  if (at != std::string::npos)
    throw InputError("--out '" + given + "' holds a control character (newline, tab, ...) at " +
                     std::to_string(at + 1) + " of '" + absolute +
                     "'; a Slurm script cannot carry it: choose another folder name");
  if (absolute.find('%') != std::string::npos)
    throw InputError("--out '" + given + "': '" + absolute +
                     "' holds '%', which sbatch --output reads as a pattern: choose another "
                     "folder name");
}

// "1,3,4" for sbatch --array.
std::string ArraySpec(const std::vector<int>& shards) {
  std::string out;
  for (int k : shards) {
    if (!out.empty()) out += ',';
    out += std::to_string(k);
  }
  return out;
}

std::string ArrayScript(const StudyConfig& config, const SlurmPlan& plan, const SlurmOptions& o) {
  const int cpus = o.cpus_per_task > 0 ? o.cpus_per_task : config.study.jobs;
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Written by: estlab study " << ShellQuote(o.config_path) << " --out "
    << ShellQuote(plan.out) << " --slurm " << o.shards << "\n"
    << "# Task K runs shard K/" << o.shards << " into " << plan.folder << "/shard-K.\n"
    << "#SBATCH --job-name=estlab-" << config.study.name << "\n"
    << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "# Its log: --output on the sbatch command line (a path here is not quoted).\n"
    << "set -euo pipefail\n"
    << "K=${SLURM_ARRAY_TASK_ID}\n"
    << "status=0\n"
    << ShellQuote(o.estlab) << " study " << ShellQuote(o.config_path) << " --out "
    << ShellQuote(plan.folder + "/shard-") << "\"$K\" --shard \"$K/" << o.shards
    << "\" --jobs \"${SLURM_CPUS_PER_TASK:-" << cpus << "}\" --quiet || status=$?\n"
    << "# 1 with the shard complete: a noise tuning failed (its tuned.csv says\n"
    << "# why), a result like any other, so the merge still runs.\n"
    << "if [ \"$status\" -eq 1 ] && grep -qx 'status = complete' "
    << ShellQuote(plan.folder + "/shard-") << "\"$K\"/study.state; then exit 0; fi\n"
    << "exit \"$status\"\n";
  return s.str();
}

std::string MergeScript(const StudyConfig& config, const SlurmPlan& plan, const SlurmOptions& o) {
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Written by: estlab study " << ShellQuote(o.config_path) << " --out "
    << ShellQuote(plan.out) << " --slurm " << o.shards << "\n"
    << "#SBATCH --job-name=estlab-" << config.study.name << "-merge\n"
    << "#SBATCH --cpus-per-task=1\n"
    << "set -euo pipefail\n"
    << "exec " << ShellQuote(o.estlab) << " merge " << ShellQuote(plan.out);
  for (int k = 1; k <= o.shards; ++k) s << " " << ShellQuote(SlurmShardDir(plan.out, k));
  s << "\n";
  return s.str();
}

// The shard's state: complete, running (its lock held), interrupted (a state
// file, no process), not started.
std::string ShardState(const std::string& dir, StudyState* state) {
  if (!ReadStudyState(dir, state)) return "not started";
  if (state->status == "complete") return "complete";
  return FolderLockHeld(dir) ? "running" : "interrupted";
}

}  // namespace

std::string SlurmShardDir(const std::string& out, int k) {
  return SlurmFolder(out) + "/shard-" + std::to_string(k);
}

SlurmPlan PlanSlurm(const StudyConfig& config, const std::string& out, const SlurmOptions& o) {
  std::string error;
  if (!o.IsValid(&error)) throw InputError(error);
  SlurmPlan plan;
  plan.out = AbsoluteOut(out);
  plan.folder = SlurmFolder(out);
  CheckOutPath(out, plan.folder);
  const std::string config_copy = plan.folder + "/config.ini";
  if (fs::exists(plan.folder)) {
    if (ReadWholeFile(config_copy) != config.text)
      throw InputError("'" + plan.folder + "' holds the submission of another study (" +
                       config_copy + "); use another --out or delete both folders");
  }
  StudyState merged;
  if (ReadStudyState(plan.out, &merged)) {
    if (merged.config_hash != ConfigHash(config.text))
      throw InputError("'" + out + "' holds results of a different configuration");
    plan.merged = merged.status == "complete";
  } else if (fs::exists(plan.out) &&
             !(fs::is_directory(plan.out) && FolderIsEmptyButLock(plan.out))) {
    throw InputError("'" + out + "' exists and is not a study results folder");
  }
  for (int k = 1; k <= o.shards; ++k) {
    StudyState s;
    const std::string state = ShardState(SlurmShardDir(out, k), &s);
    if (state != "not started" && s.shards != o.shards)
      throw InputError("'" + SlurmShardDir(out, k) + "' holds shard " + std::to_string(s.shard) +
                       "/" + std::to_string(s.shards) + ", not of " + std::to_string(o.shards) +
                       " shards; submit with --slurm " + std::to_string(s.shards) + " or delete '" +
                       plan.folder + "'");
    if (state == "running")
      throw InputError("'" + SlurmShardDir(out, k) +
                       "' is running (its lock is held); wait for it, or scancel its job");
    if (state != "complete") plan.pending_shards.push_back(k);
  }
  if (plan.merged) return plan;
  fs::create_directories(plan.folder + "/logs");
  WriteTextFile(config_copy, config.text);
  plan.array_script = plan.folder + "/array.sh";
  plan.merge_script = plan.folder + "/merge.sh";
  WriteTextFile(plan.array_script, ArrayScript(config, plan, o));
  WriteTextFile(plan.merge_script, MergeScript(config, plan, o));
  std::vector<std::string> extra;  // the user's words, after ours so that they win
  std::string why;
  SplitWords(o.sbatch_opts, &extra, &why);  // IsValid checked them
  if (!plan.pending_shards.empty()) {
    std::vector<std::string> array = {"sbatch", "--parsable",
                                      "--array=" + ArraySpec(plan.pending_shards),
                                      "--output=" + plan.folder + "/logs/shard-%a.out"};
    array.insert(array.end(), extra.begin(), extra.end());
    array.push_back(plan.array_script);
    plan.commands.push_back(array);
  }
  std::vector<std::string> merge = {"sbatch", "--parsable"};
  if (!plan.pending_shards.empty()) {
    merge.push_back(kArrayDependency);
    merge.push_back("--kill-on-invalid-dep=yes");
  }
  merge.push_back("--output=" + plan.folder + "/logs/merge.out");
  merge.insert(merge.end(), extra.begin(), extra.end());
  merge.push_back(plan.merge_script);
  plan.commands.push_back(merge);
  return plan;
}

namespace {

// Runs one sbatch command (no shell); returns the job id ("123" of
// "123;cluster" on its stdout). Warnings on its stderr do not matter when
// it answers an id; anything else is a failure with both in the message.
std::string Sbatch(const std::vector<std::string>& command) {
  std::string out, err;
  const int status = RunProgram(command, &out, &err);
  const std::string first = out.substr(0, out.find('\n'));
  const std::string id = first.substr(0, first.find(';'));
  if (status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos) {
    const std::string said = out + err;
    throw InputError("sbatch failed (exit " + std::to_string(status) + "): " +
                     (said.empty() ? "no output" : said) + "\n  command: " + ShellJoin(command));
  }
  return id;
}

}  // namespace

void SubmitSlurm(SlurmPlan* plan) {
  if (plan->merged) return;
  size_t next = 0;
  if (!plan->pending_shards.empty()) plan->array_job = Sbatch(plan->commands[next++]);
  std::vector<std::string> merge = plan->commands[next];
  for (std::string& word : merge)  // our word only: a path may hold "$ARRAY"
    if (word == kArrayDependency) word = "--dependency=afterok:" + plan->array_job;
  plan->merge_job = Sbatch(merge);
  std::ofstream jobs(plan->folder + "/jobs.txt", std::ios::app);
  jobs << NowUtc() << " array " << (plan->array_job.empty() ? "-" : plan->array_job) << " shards "
       << (plan->pending_shards.empty() ? "-" : ArraySpec(plan->pending_shards)) << " merge "
       << plan->merge_job << "\n";
  if (!jobs) throw InputError("cannot write '" + plan->folder + "/jobs.txt'");
}

StudyStatus ReadStudyStatus(const std::string& dir) {
  StudyStatus st;
  st.dir = dir;
  StudyState state;
  st.status = ShardState(dir, &state);
  const std::string folder = SlurmFolder(dir);
  // The configuration: the folder's own, or the submission's copy.
  std::string config_text = ReadWholeFile(dir + "/config.ini");
  std::string config_path = state.config_path;
  if (config_text.empty()) config_text = ReadWholeFile(folder + "/config.ini");
  if (config_text.empty())
    throw InputError("'" + dir + "' is not a study results folder (no study.state), and '" +
                     folder + "' holds no --slurm submission");
  const StudyConfig config = ParseStudyConfig(
      config_text,
      !config_path.empty() && fs::exists(config_path) ? config_path : folder + "/config.ini");
  auto runs_of = [&](int runs, int shard, int shards) {
    long n = 0;
    for (const auto& sc : config.scenarios)
      for (long i = shard - 1; i < ScenarioRuns(sc, runs); i += shards) ++n;
    return n;
  };
  if (st.status != "not started") {
    st.total_runs = runs_of(state.runs, state.shard, state.shards);
    st.finished_runs = CountFinishedRuns(config, dir);
  }
  int shards = 0;
  while (fs::exists(folder) && fs::exists(SlurmShardDir(dir, shards + 1))) ++shards;
  // Shards not started have no folder; the array script names N.
  // (The last " --slurm " of its first two lines, "#!/bin/bash" and the
  // "# Written by" comment: a path may hold the text.)
  const std::string array = ReadWholeFile(folder + "/array.sh");
  const std::string first = array.substr(0, array.find('\n', array.find('\n') + 1));
  const auto at = first.rfind(" --slurm ");
  if (at != std::string::npos) shards = std::max(shards, std::atoi(first.c_str() + at + 9));
  for (int k = 1; k <= shards; ++k) {
    ShardStatus s;
    s.shard = k;
    StudyState ss;
    s.status = ShardState(SlurmShardDir(dir, k), &ss);
    s.total_runs = runs_of(s.status == "not started" ? config.study.runs : ss.runs, k, shards);
    if (s.status != "not started")
      s.finished_runs = CountFinishedRuns(config, SlurmShardDir(dir, k));
    st.complete_shards += s.status == "complete";
    st.shards.push_back(s);
  }
  if (st.status == "not started" && !st.shards.empty()) st.status = "not merged";
  std::istringstream jobs(ReadWholeFile(folder + "/jobs.txt"));
  for (std::string line; std::getline(jobs, line);)
    if (!line.empty()) st.last_jobs = line;
  return st;
}

}  // namespace estlab
