// Output-error estimation and free-simulation errors: the standard method
// for input-driven identification and the baseline the multi-arm benchmark's
// authors used, in the same tool as the prediction-error fit of
// `estlab tune --estimate-param` (adaptive/physical_params.h).
//
// A free simulation runs without noise and without filtering, at the data's
// times, with the data's input held over each interval (zero-order hold,
// src/sim/simulation.h), and its outputs are compared with the recorded z_k
// (angle outputs wrapped; a missing z_k is left out: it adds nothing to the
// squared error and does not count in N, the RMSE or sigma):
//
//   e_kj = wrap(z_kj - h_j(x_sim(t_k))),   RMSE_j = sqrt(mean_k e_kj^2)
//
// Where it starts, per run:
//   - windows of H seconds, each from the recorded state at its first row
//     (the data's state columns, with their --column maps), when the data
//     carry every state and no initial state is estimated (evenly sampled
//     data only); on chaotic motion only short windows are meaningful;
//   - else the whole record from x0 at the first row: the spec's x0 (the
//     prior mean, --x0), with the states named in estimate_x0 estimated
//     (one x0 shared by the runs, or each run's own with x0_per_file).
//
// Output-error least squares: theta (the parameters, scaled and bounded as
// in the ML fit, adaptive/theta_scale.h, then the estimated x0 components on
// their natural scale, unbounded) minimises 1/2 sum e_kj^2 over every run
// (Ceres Levenberg-Marquardt, the Jacobian by central differences of the
// simulations, relative step 1e-6). Standard errors from
// sigma^2 (J^T J)^-1, sigma^2 = sum e^2 / (N - p), with the identifiability
// report of adaptive/identifiability.h on J^T J / sigma^2. `converged` only
// when Ceres converged and the final cost is at most the initial one.
//
// Usage:
//   OutputErrorResult r = FitOutputError(model, spec, estimate, runs, {.horizon = 0.5});
//   std::vector<double> rmse = FreeSimulationRmse(model, r.fitted_spec, validation, 0.5);
//   std::vector<double> whole = WholeRecordRmse(model, r.fitted_spec, validation, x0);
//   FreeSimulation sim = WholeRecordSimulation(model, r.fitted_spec, validation, x0);  // y, e
#ifndef ESTLAB_STUDIES_RUN_OUTPUT_ERROR_H_
#define ESTLAB_STUDIES_RUN_OUTPUT_ERROR_H_

#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/registry/registry.h"

namespace estlab {

struct OutputErrorOptions {
  double horizon = 0.5;  // s; the window length
  int max_iterations = 100;
  double theta_step = 1e-6;   // central differences in theta
  double bound_width = 20.0;  // log parameters within initial +- this (adaptive/theta_scale.h)
  std::vector<std::string> estimate_x0;  // states whose initial value is estimated
  bool x0_per_file = false;              // each run its own x0 (two runs or more)
  bool IsValid(std::string* error) const;
};

struct OutputErrorResult {
  bool ok = false;
  std::string message;  // Ceres' termination, or why it failed
  bool converged = false;
  std::string start;               // where the simulations start, in words
  std::vector<std::string> names;  // theta names ("log L", "b", "x0 h1", "x0[2] h1")
  std::vector<bool> is_log;
  std::vector<double> theta_initial, theta, std_errors;  // theta scale
  std::vector<std::string> param_names;
  std::vector<double> param_initial, param_values, param_std_errors;  // natural scale
  std::vector<bool> at_bound;
  // The estimated initial states: their names, and per run (one row shared
  // by every run unless x0_per_file) the whole x0 and the standard errors
  // (NaN for the states not estimated).
  std::vector<std::string> x0_names;
  std::vector<std::vector<double>> x0, x0_std_errors;
  std::vector<std::string> identifiability;
  long residuals = 0;  // N: the measured (finite) z cells
  long windows = 0;
  // Errors of output j are weighted by w_j = sqrt(R_11 / R_jj) from the
  // spec's R (1 for a single output, or without a positive diagonal R), so
  // that outputs count by their noise; the cost and sigma are of w e, in the
  // first output's units.
  std::vector<double> output_weights;
  double cost_initial = 0.0, cost = 0.0;  // 1/2 sum (w e)^2
  double residual_sd = 0.0;               // sigma = sqrt(sum (w e)^2 / (N - p))
  std::vector<double> residual_sds;       // per output: sigma / w_j, its own units
  std::vector<double> rmse;               // per output, at the fit
  int iterations = 0;
  double wall_s = 0.0;
  FilterSpec fitted_spec;  // spec with the fitted parameters (and the first run's x0)
};

// Throws InputError for data it cannot use, bad parameters or states.
OutputErrorResult FitOutputError(const ModelEntry& model, const FilterSpec& spec,
                                 const std::vector<EstimatedParam>& estimate,
                                 const std::vector<FilterData>& runs,
                                 const OutputErrorOptions& options);

// Whether `d` has two rows or more, evenly sampled (every step within
// 1e-6 of the mean step): what windows of a horizon need.
bool EvenlySampled(const FilterData& d);

// RMSE per output of the free simulation of `spec` over windows of
// `horizon` seconds from the recorded states; NaN when a simulation fails.
// Throws InputError when `data` lacks state columns or is unevenly sampled.
std::vector<double> FreeSimulationRmse(const ModelEntry& model, const FilterSpec& spec,
                                       const FilterData& data, double horizon);

// The free simulation of `spec` over the whole record from x0 at its first
// row (one simulation, the input held as everywhere): the simulated outputs
// y and the errors e = wrap(z - y) (0 where z is missing), rows x outputs,
// outputs fastest, and the RMSE per output over the rows where z is finite
// (NaN for an output never measured). ok false, with why, when the
// simulation fails or no z cell is finite.
struct FreeSimulation {
  bool ok = false;
  std::string why;
  std::vector<double> y, e, rmse;
};
FreeSimulation WholeRecordSimulation(const ModelEntry& model, const FilterSpec& spec,
                                     const FilterData& data, const std::vector<double>& x0);

// RMSE per output of WholeRecordSimulation's errors; NaN when the
// simulation fails.
std::vector<double> WholeRecordRmse(const ModelEntry& model, const FilterSpec& spec,
                                    const FilterData& data, const std::vector<double>& x0);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_OUTPUT_ERROR_H_
