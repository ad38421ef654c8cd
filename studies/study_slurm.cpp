#include "studies/study_slurm.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "src/core/types.h"
#include "src/io/folder_lock.h"
#include "src/io/output_file.h"
#include "src/io/shell.h"
#include "studies/study_results.h"
#include "studies/study_runner_parts.h"

namespace fs = std::filesystem;

namespace estlab {

bool SlurmOptions::IsValid(std::string* error) const {
  if (shards < 1 || shards > 100000)
    return *error = "--slurm: the number of shards must be in 1..100000", false;
  if (cpus_per_task < 0 || cpus_per_task > 1024) return *error = "--jobs must be in 1..1024", false;
  if (estlab.empty() || !fs::path(estlab).is_absolute())
    return *error = "the estlab binary's path must be absolute", false;
  if (config_path.empty()) return *error = "no study file", false;
  if (sbatch_opts.find_first_of("\n\r") != std::string::npos)
    return *error = "--slurm-opts: one line, please", false;
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
    << "#SBATCH --output=" << plan.folder << "/logs/shard-%a.out\n"
    << "set -euo pipefail\n"
    << "K=${SLURM_ARRAY_TASK_ID}\n"
    << "exec " << ShellQuote(o.estlab) << " study " << ShellQuote(o.config_path) << " --out "
    << ShellQuote(plan.folder + "/shard-") << "\"$K\" --shard \"$K/" << o.shards
    << "\" --jobs \"${SLURM_CPUS_PER_TASK:-" << cpus << "}\" --quiet\n";
  return s.str();
}

std::string MergeScript(const StudyConfig& config, const SlurmPlan& plan, const SlurmOptions& o) {
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Written by: estlab study " << ShellQuote(o.config_path) << " --out "
    << ShellQuote(plan.out) << " --slurm " << o.shards << "\n"
    << "#SBATCH --job-name=estlab-" << config.study.name << "-merge\n"
    << "#SBATCH --cpus-per-task=1\n"
    << "#SBATCH --output=" << plan.folder << "/logs/merge.out\n"
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
  const std::string extra = o.sbatch_opts.empty() ? "" : " " + o.sbatch_opts;
  if (!plan.pending_shards.empty())
    plan.commands.push_back("sbatch --parsable --array=" + ArraySpec(plan.pending_shards) + extra +
                            " " + ShellQuote(plan.array_script));
  plan.commands.push_back(
      "sbatch --parsable" +
      std::string(plan.pending_shards.empty()
                      ? ""
                      : " --dependency=afterok:$ARRAY --kill-on-invalid-dep=yes") +
      extra + " " + ShellQuote(plan.merge_script));
  return plan;
}

namespace {

// Runs one sbatch command; returns the job id ("123" of "123;cluster").
std::string Sbatch(const std::string& command) {
  std::string output;
  const int status = RunShell(command, &output);
  std::string id = output.substr(0, output.find_first_of(";\n"));
  if (status != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    throw InputError("sbatch failed (exit " + std::to_string(status) +
                     "): " + (output.empty() ? "no output" : output) + "\n  command: " + command);
  return id;
}

}  // namespace

void SubmitSlurm(SlurmPlan* plan) {
  if (plan->merged) return;
  size_t next = 0;
  if (!plan->pending_shards.empty()) plan->array_job = Sbatch(plan->commands[next++]);
  std::string merge = plan->commands[next];
  const auto at = merge.find("$ARRAY");
  if (at != std::string::npos) merge.replace(at, 6, plan->array_job);
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
  const std::string array = ReadWholeFile(folder + "/array.sh");
  const auto at = array.find(" --slurm ");
  if (at != std::string::npos) shards = std::max(shards, std::atoi(array.c_str() + at + 9));
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
