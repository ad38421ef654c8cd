// Runs a Monte Carlo study: for every scenario s and run i, one truth
// trajectory with seed DeriveSeed({study seed, s, i}), then every filter x
// noise combination on the same measurements. Runs go to worker threads that
// take run indices from an atomic counter; results are written in run order,
// one run at a time (flushed), so the output never depends on the number of
// threads and an interrupted study resumes where it stopped.
//
// Usage:
//   StudyConfig config = LoadStudyConfig("studies/paper002_pendulum_mc.ini");
//   StudyRunOptions options;
//   options.out_dir = "results/paper002";
//   options.jobs = 2;
//   StudyRunSummary summary = RunStudy(config, options);
//   if (summary.interrupted) ...;   // runs.csv holds the finished runs
//
// Sharding: shard k of N runs the runs with i % N == k - 1, for every scenario,
// into its own folder; MergeStudies (study_merge.h) joins the folders.
//
// WARNING: a folder that already holds results of a different configuration
// (or another shard) is refused; runs already in runs.csv are never redone,
// so delete the folder to start over.
#ifndef ESTLAB_STUDIES_RUN_STUDY_RUNNER_H_
#define ESTLAB_STUDIES_RUN_STUDY_RUNNER_H_

#include <atomic>
#include <string>

#include <vector>

#include "src/core/random.h"
#include "studies/config/study_config.h"
#include "studies/results/study_results.h"

namespace estlab {

struct StudyRunOptions {
  std::string out_dir;
  int runs = 0;  // 0 = the config's runs
  int jobs = 0;  // 0 = the config's jobs
  int shard = 1, shards = 1;
  bool progress = true;  // progress on stderr
  // Resuming a folder with fewer runs than it holds drops the runs beyond
  // the new count from its results: refused unless force.
  bool force = false;
  // When non-null and nonzero: take no new runs, finish and write the
  // running ones, return with interrupted = true.
  const std::atomic<int>* stop = nullptr;

  bool IsValid(std::string* error) const;
};

struct StudyRunSummary {
  long total_runs = 0;          // scenario x run pairs of this shard
  long resumed_runs = 0;        // found finished in runs.csv at the start
  long finished_runs = 0;       // finished now (including resumed)
  long failed_filter_runs = 0;  // filter x noise results with status != ok
  int tunings = 0;              // 'tuned' scenario x filter x noise combinations
  int reused_tunings = 0;       // of them found in DIR/tuning/ (study_tuning.h)
  int failed_tunings = 0;       // of them status "failed" in tuned.csv (exit 1)
  bool interrupted = false;
  double wall_s = 0.0;
  // The task pool's work (src/core/task_pool.h) in this process: the sum of
  // the tunings' and runs' own wall times, and its critical path, the
  // longest chain (a tuning, then a run that waits for it). No --jobs
  // finishes faster than critical_path_s, so task_work_s /
  // max(critical_path_s, task_work_s / J) bounds the speed-up at J jobs.
  double task_work_s = 0.0;
  double critical_path_s = 0.0;
  std::string report;  // report.md text when complete
};

// Throws InputError when the folder cannot be used (see the warning above).
StudyRunSummary RunStudy(const StudyConfig& config, const StudyRunOptions& options);

// One Poisson(lambda) count from rng (meas-noise = poisson; exposed for tests).
int PoissonCount(Rng& rng, double lambda);

// manifest.json of a results folder: the configuration, seeds, library
// versions, host and times (written by RunStudy and MergeStudies).
std::string StudyManifestJson(const StudyConfig& config, const StudyState& state,
                              const std::vector<std::string>& merged_from = {});

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_STUDY_RUNNER_H_
