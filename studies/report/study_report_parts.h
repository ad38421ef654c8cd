// Pieces shared by the parts of report.md (study_report.cpp, and
// study_report_recorded.cpp for scenarios on recorded data). Internal to
// studies/report/.
#ifndef ESTLAB_STUDIES_REPORT_STUDY_REPORT_PARTS_H_
#define ESTLAB_STUDIES_REPORT_STUDY_REPORT_PARTS_H_

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "studies/report/study_finalize.h"
#include "studies/report/study_report.h"

namespace estlab::study_report {

// `digits` significant digits; "–" for NaN.
inline std::string Sig(double v, int digits = 4) {
  if (std::isnan(v)) return "–";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

inline std::string GroupKey(const std::string& s, const std::string& f, const std::string& n) {
  return s + "/" + f + "/" + n;
}

inline const GroupValues* FindGroup(const StudyTables& t, const std::string& key) {
  const auto it = t.groups.find(key);
  return it == t.groups.end() ? nullptr : &it->second;
}

// The per-run values of a metric of the group (mse_STATE: each run's RMSE squared).
std::vector<double> Values(const GroupValues* g, const std::string& metric);

// "0.1734 ± 0.045 [0.1646, 0.1822]"
std::string MeanCell(const MetricStats& s);

// A filter x noise setting of a scenario.
struct FilterNoise {
  std::string filter, noise;
};

// The score of x against ref: the mean over the states of x's mean RMSE
// divided by ref's, so that ref scores 1 and states in different units weigh
// alike. NaN when either has no finished run.
double ScoreAgainst(const StudyTables& t, const ScenarioConfig& sc, const FilterNoise& x,
                    const FilterNoise& ref);
// The per-run differences of the scores of a and b (each run's RMSEs divided
// by ref's mean RMSE, averaged over the states) over the runs where a and b
// finished every state: their mean and 95 % CI is the paired comparison.
MetricStats PairedScoreDifference(const StudyTables& t, const ScenarioConfig& sc,
                                  const FilterNoise& a, const FilterNoise& b,
                                  const FilterNoise& ref);

// The section on the scenarios that run on recorded data: which metrics were
// available without truth, the table of those metrics and the hand vs
// tuned comparison on them. Nothing when no scenario is recorded.
void RecordedDataSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t);

// The noise-identification comparison (study_report_identification.cpp):
// per scenario with a truth, every filter x noise setting ranked by its
// score against the scenario's reference (the first filter's oracle), with
// the identified Q/R's errors, failures and cost; a ranking over the
// scenarios; a sentence for each result that reverses common wisdom.
// Nothing unless the study has tune-per-run settings.
void NoiseIdentificationSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t);

}  // namespace estlab::study_report

#endif  // ESTLAB_STUDIES_REPORT_STUDY_REPORT_PARTS_H_
