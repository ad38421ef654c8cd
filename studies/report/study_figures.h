// Figures of a finished study, drawn with gnuplot. For each figure the
// folder DIR/figures gets NAME.dat (the numbers, whitespace-separated, one
// block per filter x noise), NAME.gp (the script: `cd DIR/figures && gnuplot
// NAME.gp` redraws it) and the rendered NAME.png and NAME.svg.
//
// Per scenario:
//   SCEN_estimate_runR_FILTER_NOISE  estimate vs truth with the +-2 sd band (kept run R)
//   SCEN_rmse_time                   RMSE over time across the runs, per state
//   SCEN_nees_nis                    mean NEES and NIS over time with 95 % bounds
//   SCEN_rmse_means                  mean RMSE per filter x noise with 95 % CI of the mean
// and on recorded data (no truth: no RMSE figures, NIS without NEES):
//   SCEN_pred_rmse_means             one-step prediction RMSE per output, 95 % CI
//   SCEN_nll_means                   innovation NLL per step, 95 % CI
// and with tune-per-run noise settings (study_figures_identification.h):
//   SCEN_score_cost                  score against the oracle vs cost per run
//   SCEN_id_error                    identified Q's and R's errors over the runs
//
// Usage:
//   FiguresSummary f = DrawStudyFigures("results/paper002", FiguresOptions{});
#ifndef ESTLAB_STUDIES_REPORT_STUDY_FIGURES_H_
#define ESTLAB_STUDIES_REPORT_STUDY_FIGURES_H_

#include <string>
#include <vector>

#include "studies/report/gnuplot_figure.h"

namespace estlab {

// Throws InputError when DIR is not a finished study folder.
FiguresSummary DrawStudyFigures(const std::string& dir, const FiguresOptions& options);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_STUDY_FIGURES_H_
