// Output-error estimation and free-simulation errors: the baseline the
// multi-arm benchmark's authors used, in the same tool as the prediction-
// error fit of `estlab tune --estimate-param` (adaptive/physical_params.h).
//
// Free simulation over a horizon H: each recorded run is cut into windows of
// H seconds; each window is simulated without noise and without filtering
// from the recorded state at its first row (the data's state columns, with
// their --column maps), and the simulated outputs h(x_sim(t_k)) are compared
// with the recorded z_k (angle outputs wrapped):
//
//   e_kj = wrap(z_kj - h_j(x_sim(t_k))),   RMSE_j = sqrt(mean_k e_kj^2)
//
// Output-error least squares: the estimated parameters minimise
// 1/2 sum e_kj^2 over every window of every run (Ceres Levenberg-Marquardt;
// parameters scaled and bounded as in the ML fit, adaptive/theta_scale.h;
// the Jacobian by central
// differences of the simulations, step 1e-6 in theta). Standard errors
// from sigma^2 (J^T J)^-1, sigma^2 = sum e^2 / (N - p), with the
// identifiability report of adaptive/identifiability.h on J^T J / sigma^2.
// On chaotic motion only short windows are meaningful: a long horizon
// amplifies any parameter error exponentially.
//
// Usage:
//   OutputErrorResult r = FitOutputError(model, spec, estimate, runs, {.horizon = 0.5});
//   std::vector<double> rmse = FreeSimulationRmse(model, r.fitted_spec, validation, 0.5);
//
// WARNING: the data must be evenly sampled and carry every state as a column
// (the window starts); models with an input are not supported.
#ifndef ESTLAB_STUDIES_OUTPUT_ERROR_H_
#define ESTLAB_STUDIES_OUTPUT_ERROR_H_

#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/registry/registry.h"

namespace estlab {

struct OutputErrorOptions {
  double horizon = 0.5;  // s; the window length
  int max_iterations = 100;
  double theta_step = 1e-6;  // central differences in theta
  double bound_width = 20.0;  // log parameters within initial +- this (adaptive/theta_scale.h)
  bool IsValid(std::string* error) const;
};

struct OutputErrorResult {
  bool ok = false;
  std::string message;  // Ceres' termination, or why it failed
  bool converged = false;
  std::vector<std::string> names;  // theta names ("log L", "b")
  std::vector<bool> is_log;
  std::vector<double> theta_initial, theta, std_errors;  // theta scale
  std::vector<std::string> param_names;
  std::vector<double> param_initial, param_values, param_std_errors;  // natural scale
  std::vector<bool> at_bound;
  std::vector<std::string> identifiability;
  long residuals = 0;  // N, outputs x rows
  long windows = 0;
  double residual_sd = 0.0;  // sigma
  std::vector<double> rmse;  // per output, at the fit
  int iterations = 0;
  double wall_s = 0.0;
  FilterSpec fitted_spec;  // spec with the fitted parameters
};

// Throws InputError for data it cannot use (see WARNING) or bad parameters.
OutputErrorResult FitOutputError(const ModelEntry& model, const FilterSpec& spec,
                                 const std::vector<EstimatedParam>& estimate,
                                 const std::vector<FilterData>& runs,
                                 const OutputErrorOptions& options);

// RMSE per output of the free simulation of `spec` over windows of
// `horizon` seconds; NaN when a simulation fails. Throws InputError as above.
std::vector<double> FreeSimulationRmse(const ModelEntry& model, const FilterSpec& spec,
                                       const FilterData& data, double horizon);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_OUTPUT_ERROR_H_
