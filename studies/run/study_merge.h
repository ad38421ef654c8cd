// Shards of one study joined into one results folder (`estlab merge`), and
// how far a folder's runs have got (`estlab study --status`, study_slurm.h).
//
// Usage:
//   MergeStudies("results/all", {"results/s1", "results/s2"});
//   const long done = CountFinishedRuns(config, "results/s1");
#ifndef ESTLAB_STUDIES_RUN_STUDY_MERGE_H_
#define ESTLAB_STUDIES_RUN_STUDY_MERGE_H_

#include <string>
#include <vector>

#include "studies/config/study_config.h"

namespace estlab {

// Joins complete shard folders of one study into `out` (which must not
// exist or be empty). Throws InputError on mismatched or incomplete shards.
void MergeStudies(const std::string& out, const std::vector<std::string>& shard_dirs);

// Number of finished runs (all filter x noise rows present) in DIR/runs.csv.
long CountFinishedRuns(const StudyConfig& config, const std::string& dir);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_STUDY_MERGE_H_
