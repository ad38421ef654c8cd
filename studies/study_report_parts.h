// Pieces shared by the parts of report.md (study_report.cpp, and
// study_report_recorded.cpp for scenarios on recorded data). Internal to
// studies/.
#ifndef ESTLAB_STUDIES_STUDY_REPORT_PARTS_H_
#define ESTLAB_STUDIES_STUDY_REPORT_PARTS_H_

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "studies/study_report.h"

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

// The section on the scenarios that run on recorded data: which metrics were
// available without truth, the table of those metrics and the hand vs
// tuned comparison on them. Nothing when no scenario is recorded.
void RecordedDataSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t);

}  // namespace estlab::study_report

#endif  // ESTLAB_STUDIES_STUDY_REPORT_PARTS_H_
