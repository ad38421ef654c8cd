// What `estlab filter` (and the tuner and studies) ask a model's filter
// runner to do, in plain runtime types so that this header stays light.
#ifndef ESTLAB_RUN_FILTER_SPEC_H_
#define ESTLAB_RUN_FILTER_SPEC_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "src/filters/filter_options.h"
#include "src/ode/transition.h"
#include "src/run/filter_kinds.h"

namespace estlab {

struct FilterSpec {
  std::vector<double> params;  // model parameters in registry order
  std::string measurement;
  TransitionOptions transition;
  // The filter kind and its options (filter_kinds.h); default: the UKF.
  FilterKindOptions filter = SigmaPointOptions{};
  FilterKind kind() const { return KindOf(filter); }
  bool iterated() const {
    const auto* ekf = std::get_if<EkfOptions>(&filter);
    return ekf != nullptr && ekf->iterations > 1;
  }

  std::vector<double> x0;  // n
  // `x0 = first-sample`: each dataset's prior mean is its first measured
  // value of every state that an output of the same name measures, the
  // others x0's (0) (FirstSampleX0, first_sample.h).
  bool x0_first_sample = false;
  std::vector<double> p0;  // n x n, row-major

  // Process noise: a fixed matrix, or qc times the white-noise-acceleration
  // shape [[dt^3/3, dt^2/2], [dt^2/2, dt]] on each (position, rate) pair.
  bool q_white_accel = false;
  double qc = 0.0;
  std::vector<double> q;  // n x n, row-major
  std::vector<double> r;  // m x m, row-major

  AdaptSpec adapt;  // sigma-point filters only

  // The constant input (one value per model input) when the data have no
  // input columns; empty = 0 for every input.
  std::vector<double> input;
  bool has_t0 = false;
  double t0 = 0.0;
  bool full_cov = false;  // write every covariance entry, not just the diagonal
  // Divergence guard: stop when trace(P) exceeds this.
  double max_cov_trace = 1e12;

  // `estlab smooth`: the rows carry the smoothed estimates of the filter's
  // smoother (smoother_recorder.h); the particle smoother draws
  // smoother_trajectories backward trajectories.
  bool smooth = false;
  int smoother_trajectories = 100;
};

// Measurements (and optional truth and input) on a time grid.
struct FilterData {
  std::string path;
  std::vector<double> t;
  std::vector<long> lines;  // source line of each row, for messages
  int m = 0;
  std::vector<double> z;  // rows x m, NaN = missing (the observed components update)
  bool has_truth = false;
  std::vector<double> truth;  // rows x n
  int nu = 0;                 // input columns (0: none, the spec's constant input)
  std::vector<double> u;      // rows x nu: u_k held over [t_k, t_k+1)
};

struct FilterSummary {
  std::string filter;
  std::vector<std::string> states;
  std::vector<double> rmse, mae;  // per state; empty without truth
  std::vector<long> truth_rows;   // per state: the rows with finite truth
  double loglik = 0.0;
  long updates = 0;
  long steps = 0;  // rows processed
  double mean_nis = 0.0;
  double nis_bounds95[2] = {0.0, 0.0};
  // Per sensor group (a measurement with kGroups, models/model.h): the NIS
  // of the group's observed components, nu_g' S_gg^-1 nu_g, over the updates
  // that observed any of them; bounds with the observed components' count.
  struct GroupNis {
    std::string group;
    long updates = 0;
    double mean_nis = 0.0;
    double nis_bounds95[2] = {0.0, 0.0};
  };
  std::vector<GroupNis> group_nis;
  double mean_nees = 0.0;
  double nees_bounds95[2] = {0.0, 0.0};
  // Seconds: wall_s the whole run (set-up, the filter loop, the rows'
  // output, the smoother's pass); loop_s the filter loop alone (predict,
  // update, each step's record), and us_per_step = 1e6 loop_s / steps;
  // read_s and write_s the command's reading of the data and writing of
  // --out (0 when not set: a run from the library).
  double wall_s = 0.0;
  double loop_s = 0.0;
  double us_per_step = 0.0;
  double read_s = 0.0, write_s = 0.0;
  bool ok = true;
  std::string status = "ok";
  std::string message;
  long adapt_clips = 0;    // adaptive: eigenvalue clips applied to keep Q, R SPD
  std::vector<double> x0;  // the prior mean used (x0 = first-sample: this file's)
  // Particle filters (degeneracy.h): the particle count, the smallest and
  // the mean effective sample size over the updates, how many updates
  // collapsed, and whether the run was degenerate (status "degenerate",
  // message with the step, time and hints; ok stays true because every
  // number was computed, but `estlab filter` exits 1 without
  // --allow-degenerate).
  int particles = 0;
  double min_ess = 0.0, mean_ess = 0.0;
  long collapsed_updates = 0;
  bool degenerate = false;
  std::vector<double> final_q, final_r;
  // `estlab smooth`: the forward filter's summary (this one's rmse, mae and
  // NEES are the smoother's; its likelihood and NIS are the filter's).
  std::shared_ptr<const FilterSummary> forward;
};

struct FilterRunOutput {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  FilterSummary summary;
};

// The IsValid of spec.filter's options for a model with `state_dim` states
// (IsValidFor), of the transition options and of the noise adaptation
// (sigma-point filters only), with *error set when false. Every message
// starts with the option key it is about ("alpha: must be > 0 ...").
bool IsValidFilterOptions(const FilterSpec& spec, int state_dim, std::string* error);

// The smoother of a filter's Name(): rts, erts, iekf-rts, urts, ckf-rts,
// ghkf-rts, pf-bs.
std::string SmootherName(const std::string& filter_name);
// The inverse: "ukf" for "urts"; "" when `name` is no smoother's.
std::string FilterOfSmoother(const std::string& name);

// Two-sided 95 % bounds of the K-step time average of a d-dimensional
// chi-square statistic: K * mean ~ chi2(K d).
void ChiSquareBounds95(long steps, int dim, double bounds[2]);
// The same with `dof` degrees of freedom over the K steps in all (the NIS
// of updates with missing components: the observed ones per step).
void ChiSquareMeanBounds95(long steps, long dof, double bounds[2]);

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_SPEC_H_
