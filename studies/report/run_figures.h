// The figures of one filter, smoother or tuned run, drawn with gnuplot as
// the study figures are (gnuplot_figure.h: NAME.dat, NAME.gp, NAME.png,
// NAME.svg; `cd DIR && gnuplot NAME.gp` redraws one). Used by
// `estlab filter --plot DIR`, `estlab smooth --plot DIR`, `estlab tune
// --plot DIR` and `estlab figures est.csv`.
//
//   estimates        one panel per state: the estimate with its +-2 sd band,
//                    the truth when the run had it (estimate - error), and
//                    the measurements of outputs named like the state
//   measurements     outputs not named like a state, one panel each
//   innovations      nu_k per output with +-2 sqrt(S_k) (filters only)
//   nis              NIS_k with the 95 % chi-square(m) bounds of one step
//                    and of the mean NIS (log scale)
//   autocorrelation  rho_l of the whitened innovations e_k = nu_k / sqrt(S_k)
//                    per output, lags 1..L, with the white-noise 95 % band
//                    +-1.96 / sqrt(K) (K updates)
//   convergence      the tuner's objective by iteration (when given)
//   free-simulation  per output the measurements with the free simulation
//                    (no filter, no noise) and below them the errors
//                    z - y with their RMSE (when given: tune --plot)
//
// Usage:
//   RunFigureInput in;
//   in.title = "pendulum: ukf on d.csv";
//   in.columns = out.columns; in.rows = out.rows;   // est.csv
//   in.meas_t = data.t; in.meas_z = data.z; in.outputs = {"theta"};
//   FiguresSummary f = DrawRunFigures(in, "plots", FiguresOptions{});
#ifndef ESTLAB_STUDIES_REPORT_RUN_FIGURES_H_
#define ESTLAB_STUDIES_REPORT_RUN_FIGURES_H_

#include <string>
#include <vector>

#include "studies/report/gnuplot_figure.h"

namespace estlab {

struct RunFigureInput {
  std::string title;
  // The rows of est.csv (or smoothed.csv) and their column names: t,
  // <state>_est, <state>_var [, nu_<output>, S_<output>, nis]
  // [, <state>_err].
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  // Units of the states ("" for none), by state name; may be empty.
  std::vector<std::pair<std::string, std::string>> state_units;
  // The measurements: times and rows x outputs values (NaN = missing).
  std::vector<std::string> outputs;
  std::vector<double> meas_t, meas_z;
  // The tuner's objective by iteration, from the start point (iteration 0;
  // convergence figure when not empty).
  std::vector<double> objective_history;
  std::string objective_name = "NLL";
  // The free simulation of the outputs at meas_t and its errors, rows x
  // outputs (output_error.h's WholeRecordSimulation), with its RMSE per
  // output and its title ("two-tanks: free simulation on v.csv from x0 =
  // (...)"): the free-simulation figure when sim_y is not empty.
  std::vector<double> sim_y, sim_e, sim_rmse;
  std::string sim_title;
};

// The lag-1..max_lag autocorrelations rho_l = c_l / c_0 of the finite values
// of e (c_l = (1/K) sum_{k} (e_k - mean)(e_{k+l} - mean), the biased
// estimator, whose white-noise band is +-1.96 / sqrt(K)). Empty when fewer
// than max_lag + 2 values or c_0 = 0.
std::vector<double> Autocorrelation(const std::vector<double>& e, int max_lag);

// Throws InputError when `dir` exists and is not a folder (checked before
// the run, so that a bad --plot costs no work).
void CheckFigureFolder(const std::string& dir);

// Writes the figures into `dir` (created when missing) and renders them
// unless options.render is false. Throws InputError when `dir` exists and is
// not a folder, or when the table has no t / <state>_est columns.
FiguresSummary DrawRunFigures(const RunFigureInput& in, const std::string& dir,
                              const FiguresOptions& options);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_RUN_FIGURES_H_
