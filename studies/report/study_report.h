// report.md of a study: per scenario the accuracy and consistency tables, the
// paper's numbers beside ours, and a plain sentence on each claim.
//
// Intervals: "mean ± sd" gives the spread over runs; "[lo, hi]" is the 95 %
// confidence interval of the mean, mean ± 1.96 sd / sqrt(n) (summary.csv also
// has the 2.5 / 97.5 percentiles of the runs). A claim "METRIC: A < B" is
// judged on the means; it is called significant when the 95 % interval of the
// paired per-run difference A - B excludes zero (both filters saw the same
// measurements in each run, so the pairing removes the shared noise).
#ifndef ESTLAB_STUDIES_REPORT_STUDY_REPORT_H_
#define ESTLAB_STUDIES_REPORT_STUDY_REPORT_H_

#include <map>
#include <string>
#include <vector>

#include "studies/config/study_config.h"
#include "studies/results/study_results.h"

namespace estlab {

struct GroupValues {
  long runs = 0;                                      // rows in runs.csv
  long ok = 0;                                        // rows with status ok
  std::vector<long> run_index;                        // of the ok rows, aligned with `values`
  std::map<std::string, std::vector<double>> values;  // metric -> per ok run
  std::vector<double> us_per_step;                    // every run (timing.csv)
  std::vector<double> filter_wall_s;                  // every run (timing.csv)
  std::vector<double> identify_wall_s;                // tune-per-run: every run's tuner time
  long tune_failed = 0;                               // rows with status tune_failed
};

struct StudyTables {
  std::map<std::string, GroupValues> groups;  // "scenario/filter/noise"
  CsvText tuned;                              // tuned.csv (empty without `tuned` noise settings)
};

std::string StudyReportMarkdown(const StudyConfig& config, const StudyTables& tables,
                                const StudyState& state);

// identification.csv of a study with tune-per-run settings ("" without):
// per scenario x filter x noise its score against the scenario's reference
// with the paired 95 % CI, the NEES consistency, the identified Q/R's
// relative errors (median, 2.5 and 97.5 percentiles), the rates of failed,
// unconverged and at-bound tunings, iterations and the mean wall time per
// run of identification + filter (the cost: not reproducible to the byte,
// unlike runs.csv). report.md's noise-identification section and the
// score-vs-cost figure are drawn from the same rows.
std::string IdentificationCsv(const StudyConfig& config, const StudyTables& tables);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_STUDY_REPORT_H_
