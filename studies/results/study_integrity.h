// Whether a study results folder holds what it says it holds:
//   - the run files agree with each other (CheckRunCoverage): every run of
//     the folder's shard has one runs.csv and one timing.csv row per filter x
//     noise setting, and the steps.csv rows its `steps` column implies;
//   - no file changed after the study finished (DigestResultFiles): a
//     checksum (64-bit FNV-1a, not cryptographic: it catches damage, not
//     tampering) and byte size of every result file, kept in study.state.
// A resume redoes the runs whose rows are incomplete (a deleted steps.csv
// included); `estlab merge` refuses a shard with either kind of damage,
// naming the shard and the problem.
//
// Usage:
//   RunCoverage c = CheckRunCoverage(config, dir, runs, shard, shards);
//   if (c.damaged > 0) ...   // c.complete: the runs that are whole
//   state.files = DigestResultFiles(dir);   // when the study is complete
#ifndef ESTLAB_STUDIES_RESULTS_STUDY_INTEGRITY_H_
#define ESTLAB_STUDIES_RESULTS_STUDY_INTEGRITY_H_

#include <set>
#include <string>
#include <utility>
#include <vector>

#include "studies/config/study_config.h"
#include "studies/results/study_results.h"

namespace estlab {

// steps.csv holds every `every`-th row of a run and its last: the config's
// step-metrics-every, else about 100 rows for the longest scenario.
int StepMetricsEvery(const StudyConfig& config);

// The rows steps.csv holds for a run of `steps` rows: k = 0, every,
// 2 every, ... and k = steps - 1.
long ExpectedStepRows(long steps, int every);

struct RunCoverage {
  // (scenario, run) of the shard whose rows are whole in all three files.
  std::set<std::pair<std::string, long>> complete;
  // Runs of the shard with rows in runs.csv for every setting but missing
  // or extra rows in runs.csv, steps.csv or timing.csv (damage, not an
  // interruption), and a sentence for each of the first few, naming the
  // file and the run.
  long damaged = 0;
  std::vector<std::string> damage;
  // Rows of runs the shard does not have (another shard's, beyond --runs,
  // an unknown scenario or setting): a sentence for each of the first few.
  std::vector<std::string> foreign;
};

// Reads DIR's runs.csv, steps.csv and timing.csv (streamed; memory grows
// with the number of runs, not rows) for the runs 0..runs-1 of every
// scenario with run % shards == shard - 1. A run interrupted before its
// runs.csv rows were all written is simply not complete (no problem).
RunCoverage CheckRunCoverage(const StudyConfig& config, const std::string& dir, int runs, int shard,
                             int shards);

// Checksums of DIR's result files: config.ini, runs.csv, steps.csv,
// timing.csv, tuned.csv and timeseries/..., those that exist, by path.
std::vector<FileDigest> DigestResultFiles(const std::string& dir);

// "" when DIR's files match `recorded`, else what differs ("steps.csv is
// missing", "runs.csv changed after the study finished (...)").
std::string CompareDigests(const std::string& dir, const std::vector<FileDigest>& recorded);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RESULTS_STUDY_INTEGRITY_H_
