// The end of a study (or of a merge): the run files of a results folder put
// into canonical order (CanonicalizeRunFiles, study_results.h), then the
// files computed from them, over the runs whose status is ok:
//
//   DIR/summary.csv         per scenario x filter x noise and metric: mean,
//                           spread, intervals (ComputeStats)
//   DIR/time_metrics.csv    per group and time: RMSE over runs, mean NEES/NIS
//                           with bounds
//   DIR/identification.csv  with tune-per-run settings (study_report.h)
//   DIR/report.md           StudyReportMarkdown (study_report.h)
//
// The run files are streamed, never held whole: memory does not grow with
// the number of runs.
//
// Usage:
//   FinalizeStudy(config, "results/paper002");   // after the last run
//   const MetricStats s = ComputeStats({0.12, 0.15, 0.11});   // s.mean, s.ci95_lo, ...
#ifndef ESTLAB_STUDIES_REPORT_STUDY_FINALIZE_H_
#define ESTLAB_STUDIES_REPORT_STUDY_FINALIZE_H_

#include <string>
#include <vector>

#include "studies/config/study_config.h"

namespace estlab {

// Per-group statistics of one metric over the runs whose status is ok.
struct MetricStats {
  long n = 0;
  double mean = 0, std = 0, var = 0;
  double ci95_lo = 0, ci95_hi = 0;                           // mean -+ 1.96 std / sqrt(n)
  double p2_5 = 0, median = 0, p97_5 = 0, min = 0, max = 0;  // linear interpolation
};
MetricStats ComputeStats(std::vector<double> values);

// Sorts the run files of DIR into canonical order (scenario, run, filter,
// noise), then writes summary.csv, time_metrics.csv and report.md. Returns
// the report text.
std::string FinalizeStudy(const StudyConfig& config, const std::string& dir);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_STUDY_FINALIZE_H_
