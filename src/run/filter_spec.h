// What `estlab filter` (and the tuner and studies) ask a model's filter
// runner to do, in plain runtime types so that this header stays light.
#ifndef ESTLAB_RUN_FILTER_SPEC_H_
#define ESTLAB_RUN_FILTER_SPEC_H_

#include <cstdint>
#include <string>
#include <vector>

#include "src/filters/filter_options.h"
#include "src/ode/transition.h"

namespace estlab {

enum class FilterKind { kKf, kEkf, kUkf, kCkf, kGhkf, kPf };
// Parses kf | ekf | iekf | ukf | ckf | ghkf | pf (iekf = ekf with iterations);
// throws InputError.
FilterKind ParseFilterKind(const std::string& name);
const char* FilterKindName(FilterKind kind);

struct FilterSpec {
  std::vector<double> params;  // model parameters in registry order
  std::string measurement;
  FilterKind kind = FilterKind::kUkf;
  TransitionOptions transition;

  std::vector<double> x0;  // n
  std::vector<double> p0;  // n x n, row-major

  // Process noise: a fixed matrix, or qc times the white-noise-acceleration
  // shape [[dt^3/3, dt^2/2], [dt^2/2, dt]] on each (position, rate) pair.
  bool q_white_accel = false;
  double qc = 0.0;
  std::vector<double> q;  // n x n, row-major
  std::vector<double> r;  // m x m, row-major

  // KF: operating point (empty = prior mean), EKF: iterations (> 1 = IEKF).
  std::vector<double> linearize_at;
  int iterations = 1;
  // Sigma-point rules.
  double alpha = 1e-3, beta = 2.0, kappa = 0.0;
  int gh_order = 3;
  bool sigma_redraw = true;  // --sigma-update redraw (default) | propagate
  double jitter = 0.0;
  // Particle filter.
  int particles = 1000;
  std::string resample = "systematic";
  double ess_threshold = 0.5;
  uint64_t seed = 1;

  AdaptSpec adapt;

  double input = 0.0;  // constant input when the data has no 'u' column
  bool has_t0 = false;
  double t0 = 0.0;
  bool full_cov = false;  // write every covariance entry, not just the diagonal
  // Divergence guard: stop when trace(P) exceeds this.
  double max_cov_trace = 1e12;
};

// Measurements (and optional truth and input) on a time grid.
struct FilterData {
  std::string path;
  std::vector<double> t;
  std::vector<long> lines;  // source line of each row, for messages
  int m = 0;
  std::vector<double> z;  // rows x m, NaN = missing (no update)
  bool has_truth = false;
  std::vector<double> truth;  // rows x n
  bool has_input = false;
  std::vector<double> u;
};

struct FilterSummary {
  std::string filter;
  std::vector<std::string> states;
  std::vector<double> rmse, mae;  // per state; empty without truth
  double loglik = 0.0;
  long updates = 0;
  long steps = 0;  // rows processed
  double mean_nis = 0.0;
  double nis_bounds95[2] = {0.0, 0.0};
  double mean_nees = 0.0;
  double nees_bounds95[2] = {0.0, 0.0};
  double wall_s = 0.0;
  double us_per_step = 0.0;
  bool ok = true;
  std::string status = "ok";
  std::string message;
  long adapt_clips = 0;  // adaptive: eigenvalue clips applied to keep Q, R SPD
  std::vector<double> final_q, final_r;
};

struct FilterRunOutput {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  FilterSummary summary;
};

// Two-sided 95 % bounds of the K-step time average of a d-dimensional
// chi-square statistic: K * mean ~ chi2(K d).
void ChiSquareBounds95(long steps, int dim, double bounds[2]);

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_SPEC_H_
