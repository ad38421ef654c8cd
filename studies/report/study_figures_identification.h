// The figures of a study's noise identification (identification.csv, written
// by FinalizeStudy when the study has tune-per-run settings), per scenario:
//
//   SCEN_score_cost   score against the oracle [95 % CI] vs the mean cost per
//                     run (identification + filter, log scale), one point per
//                     setting and filter kind
//   SCEN_id_error     relative Frobenius error of the identified Q and R,
//                     median with the 2.5-97.5 % range over the runs (log scale)
//
// Usage (study_figures.cpp):
//   IdentificationFigures(dir + "/identification.csv", dir + "/figures", term, &scripts);
#ifndef ESTLAB_STUDIES_REPORT_STUDY_FIGURES_IDENTIFICATION_H_
#define ESTLAB_STUDIES_REPORT_STUDY_FIGURES_IDENTIFICATION_H_

#include <string>
#include <vector>

namespace estlab {

// Nothing when `csv` does not exist; appends the scripts' paths.
void IdentificationFigures(const std::string& csv, const std::string& folder,
                           const std::string& term, std::vector<std::string>* scripts);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_STUDY_FIGURES_IDENTIFICATION_H_
