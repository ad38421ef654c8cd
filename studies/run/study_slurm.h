// A study as a Slurm job array: `estlab study CONFIG --out OUT --slurm N`.
// Everything of the submission lives in OUT.slurm/ beside OUT:
//   OUT.slurm/array.sh      the array job: task K runs
//                           estlab study CONFIG --out OUT.slurm/shard-K --shard K/N
//   OUT.slurm/merge.sh      the merge job (afterok on the array):
//                           estlab merge OUT OUT.slurm/shard-1 ... shard-N
//   OUT.slurm/shard-K/      the shards' results folders
//   OUT.slurm/logs/         each task's and the merge's output
//   OUT.slurm/jobs.txt      the job ids of every submission
// Submitting the same command again submits only the shards that are not
// complete (a killed or cancelled task resumes its folder; finished shards
// are never rerun) and the merge; nothing when OUT is already merged. The
// merged OUT is byte-identical to a single-process run (runs.csv, steps.csv,
// summary.csv, time_metrics.csv), as for any sharded study.
//
// Usage:
//   SlurmOptions o;  o.shards = 10;  o.estlab = "/usr/local/bin/estlab";
//   SlurmPlan plan = PlanSlurm(config, "results/p003", o);   // writes the scripts
//   if (!o.dry_run) SubmitSlurm(&plan);    // sbatch; throws InputError on failure
//   StudyStatus st = ReadStudyStatus("results/p003");       // estlab study --status
#ifndef ESTLAB_STUDIES_RUN_STUDY_SLURM_H_
#define ESTLAB_STUDIES_RUN_STUDY_SLURM_H_

#include <string>
#include <vector>

#include "studies/config/study_config.h"

namespace estlab {

struct SlurmOptions {
  int shards = 1;           // array tasks
  int cpus_per_task = 0;    // 0 = the config's jobs
  std::string sbatch_opts;  // extra sbatch options, plain words (--partition=... --time=...)
  std::string estlab;       // absolute path of the estlab binary the jobs run
  std::string config_path;  // the study file (made absolute)
  bool dry_run = false;     // write the scripts, submit nothing

  bool IsValid(std::string* error) const;
};

// The merge's dependency on the array job before its id is known (a shell
// variable where the commands are shown for pasting).
inline constexpr const char* kArrayDependency = "--dependency=afterok:$ARRAY";

struct SlurmPlan {
  std::string folder;               // OUT.slurm
  std::string out;                  // OUT
  std::vector<int> pending_shards;  // shards to (re)run: not complete
  bool merged = false;              // OUT already holds the merged study
  std::string array_script, merge_script;
  // The sbatch commands, word by word (run without a shell; ShellJoin shows
  // them); the merge's dependency is the word kArrayDependency until the
  // array's id is known.
  std::vector<std::vector<std::string>> commands;
  std::string array_job, merge_job;  // job ids once submitted ("" = none)
};

// The shard folder of shard k.
std::string SlurmShardDir(const std::string& out, int k);

// Checks OUT and its OUT.slurm (another study's is refused), finds the
// pending shards and writes the scripts. Throws InputError.
SlurmPlan PlanSlurm(const StudyConfig& config, const std::string& out, const SlurmOptions& options);

// Runs the plan's sbatch commands: the array (when shards are pending), then
// the merge depending on it; records the ids in OUT.slurm/jobs.txt. Throws
// InputError with sbatch's message when a submission fails.
void SubmitSlurm(SlurmPlan* plan);

// `estlab study --status DIR`: the state of a results folder, or of the
// shards of a --slurm submission (DIR.slurm).
struct ShardStatus {
  int shard = 0;
  std::string status;  // complete | running | interrupted | not started
  long finished_runs = 0, total_runs = 0;
};
struct StudyStatus {
  std::string dir;
  // complete | running | interrupted | not started; a --slurm submission
  // whose merge has not written DIR yet: not merged.
  std::string status;
  long finished_runs = 0, total_runs = 0;
  std::vector<ShardStatus> shards;  // empty when DIR was not submitted with --slurm
  int complete_shards = 0;
  std::string last_jobs;  // the last line of DIR.slurm/jobs.txt
};
StudyStatus ReadStudyStatus(const std::string& dir);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_STUDY_SLURM_H_
