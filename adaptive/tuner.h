// Offline tuning of the process- and measurement-noise covariances Q and R by
// maximum innovation likelihood (the "LikelihoodTuner"), in plain runtime
// types so that the registry and the CLI can include this header cheaply.
// The templates are in adaptive/likelihood.h and adaptive/tuner_impl.h.
//
//   NLL(theta) = 1/2 sum_datasets sum_{k >= burn_in} [ log det S_k
//                + nu_k^T S_k^-1 nu_k + m log 2 pi ]
//
// with nu_k, S_k the innovations and their covariances of a linearised KF,
// an EKF (IEKF) or a sigma-point filter (UKF, CKF, GHKF) run with Q(theta),
// R(theta) over fixed-step (Euler, semi-implicit Euler, RK4; exact AD
// gradient) or CVODES transitions (exact gradient from forward sensitivities
// in theta, src/ode/cvodes_theta_flow.h). theta holds
// log-variances, so every Q(theta), R(theta) is positive (semi-)definite by
// construction.
//
// Usage:
//   FilterSpec spec = ...;                // the filter and the initial Q, R
//   TunerOptions options;
//   options.q_param = NoiseParam::kWhiteAccel;
//   options.r_param = NoiseParam::kDiag;
//   options.starts = 4;
//   std::vector<FilterData> data = {LoadFilterData(...), ...};
//   TuneResult result = FindModel("pendulum").tune(spec, options, data);
//   if (result.IsSolutionUsable()) use(result.q, result.r);
//
// Parameterisations (chosen separately for Q and R), theta per matrix:
//   diag         theta_i = log D_ii                         (n parameters)
//   full         log-Cholesky: D = L L^T, theta = [log L_00^2, L_10,
//                log L_11^2, L_20, L_21, log L_22^2, ...]   (n(n+1)/2)
//   white-accel  theta = log qc, Q = qc [[dt^3/3, dt^2/2], [dt^2/2, dt]] on
//                every (position, rate) pair, dt of each step (Q only)  (1)
//   scalar       theta = log s, D = s I                     (1)
//   fixed        not tuned: the initial matrix              (0)
// The diagonal entries of `full` are log L_ii^2 (not log L_ii) so that they
// are log-variances like `diag` and the same bounds and spread apply.
//
// WARNING: the standard errors come from the curvature of the NLL at the
// optimum (the inverse observed Fisher information). They are meaningful only
// when the optimum is interior and the model is right; a parameter at a bound
// or with a flat likelihood is reported with a large or infinite SE.
#ifndef ESTLAB_ADAPTIVE_TUNER_H_
#define ESTLAB_ADAPTIVE_TUNER_H_

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/estimators.h"
#include "src/run/filter_spec.h"

namespace estlab {

enum class NoiseParam { kDiag, kFull, kWhiteAccel, kScalar, kFixed };
// Parses diag | full | white-accel | scalar | fixed; throws InputError.
NoiseParam ParseNoiseParam(const std::string& name, const std::string& option);
const char* NoiseParamName(NoiseParam param);

// A physical parameter of the model estimated together with Q and R
// (`estlab tune --estimate-param`, prediction-error maximum likelihood). A
// parameter constrained > 0 is optimised as log p, any other as p itself.
struct EstimatedParam {
  std::string name;  // as in the model's parameter table
  // Bounds on the natural scale; NaN: from the constraint (>= 0 gives a
  // lower bound 0) and, on the log scale, the initial value +- bound_width.
  double lower = std::numeric_limits<double>::quiet_NaN();
  double upper = std::numeric_limits<double>::quiet_NaN();
  // Gaussian prior N(mean, sd^2) on the natural scale: adds
  // 1/2 ((p - mean) / sd)^2 to the NLL (sd > 0 when has_prior).
  bool has_prior = false;
  double prior_mean = 0.0, prior_sd = 0.0;
};

// What TunerOptions::progress reports after each iteration.
struct TuneProgress {
  const char* phase = "";         // "start" (ml), "em", "als", "ml from EM's solution"
  int start = 0, starts = 0;      // the multi-start's start (1-based) of how many; 0 for EM, ALS
  int iteration = 0;              // 1, 2, ... within this start
  const char* objective = "NLL";  // what `value` is: "NLL", or "cost" (least squares)
  double value = 0.0;
  double change = 0.0;  // value minus the previous iteration's
};

struct TunerOptions {
  NoiseParam q_param = NoiseParam::kDiag;
  NoiseParam r_param = NoiseParam::kDiag;
  // R per sensor group (ml only): every group of the measurement once, R
  // block-diagonal (adaptive/noise_param.h, CovarianceBlock). Empty: r_param
  // over all of R.
  std::vector<std::pair<std::string, NoiseParam>> r_param_groups;
  // The estimator (adaptive/estimators.h) and, for ml, its solver.
  Estimator estimator = Estimator::kMl;
  MlSolver solver = MlSolver::kLbfgs;

  // Updates skipped at the start of every dataset (the prior's transient).
  int burn_in = 0;

  // Multi-start: start 0 is the initial guess; starts 1..starts-1 are a
  // Latin hypercube in [theta0 - spread, theta0 + spread] on the log
  // parameters (off-diagonal Cholesky entries keep their initial value),
  // drawn from Rng(seed).
  // The physical parameters are spread too: uniformly within their bounds
  // when both are finite (on the log scale for a > 0 parameter), else within
  // theta0 +- spread (log scale) or theta0 +- max(|theta0|, 1e-3) * spread / 2
  // (natural scale), clamped into the bounds. Starts run on `jobs` threads,
  // each with its own filter; the result does not depend on jobs.
  int starts = 1;
  double start_spread = 2.0;
  uint64_t seed = 1;
  int jobs = 1;

  // Bounds on the log parameters. Empty: theta0 +- bound_width (e^20 ~ 5e8
  // in variance). One value: the same for every log parameter. Otherwise one
  // per parameter (off-diagonal Cholesky entries included; use +-inf for no
  // bound). Off-diagonal Cholesky entries are unbounded by default.
  double bound_width = 20.0;
  std::vector<double> log_lower, log_upper;

  // Before each start, minimise the NLL over a common scale of Q and R
  // (every log parameter + s, off-diagonal Cholesky entries * e^(s/2)) on a
  // grid s = -8..8 refined by golden section. From guesses far off in overall
  // scale (an overconfident filter) L-BFGS otherwise tends to drive single
  // variances into the flat valley log q -> -inf.
  bool scale_search = true;

  int max_iterations = 200;
  // CVODES work per trial point (--integrator cvodes): on average at most
  // this many internal steps per integrated interval over the evaluation
  // (plus 10^4 steps of slack; five times as many for a stiff model, whose
  // BDF restarts at every interval take more), and 100 times that in any
  // one interval. A trial point that needs more (absurd noise values can
  // make the filter's state race) is infeasible, like a failing filter: the
  // optimiser steps back; a start that needs more fails, saying so.
  long max_integrator_steps = 200;
  double function_tolerance = 1e-12;  // relative change of the NLL
  double gradient_tolerance = 1e-8;   // max-norm of the gradient (L-BFGS)
  double parameter_tolerance = 1e-10;

  // Standard errors: Hessian by central differences of the exact gradient
  // with this step in theta.
  bool compute_std_errors = true;
  double hessian_step = 1e-4;
  // A log parameter whose SE exceeds this is "poorly identified".
  double poorly_identified_se = 1.0;

  // Physical parameters estimated with Q and R (their initial values are the
  // spec's params). Empty: Q and R only.
  std::vector<EstimatedParam> estimate;
  // Initial states estimated with them (the filter's prior mean; its
  // covariance stays the spec's P0): the states named, one x0 shared by
  // every dataset, or with x0_per_file each dataset its own
  // (adaptive/initial_states.h). Estimators whose row says x0 only.
  std::vector<std::string> estimate_x0;
  bool x0_per_file = false;

  // EM (Estimator::kEm): stop when |NLL_i - NLL_{i-1}| <= em_tolerance * |NLL_i|
  // (max_iterations EM iterations at most); then, with em_compare_ml, run
  // the L-BFGS form from EM's solution so that the report gives both
  // optima (they agree on a linear model; the gap shows the E-step's
  // approximation on a nonlinear one).
  double em_tolerance = 1e-9;
  bool em_compare_ml = true;
  // Called after every iteration of the optimiser (each start of the
  // multi-start, EM, ALS) with where it is (the CLI prints it on a
  // terminal). May be empty.
  std::function<void(const TuneProgress&)> progress;

  // ALS (Estimator::kAls): the lags 0 .. als_lags - 1 of the innovation
  // autocovariances fitted; burn_in updates of the suboptimal filter are
  // left out of them.
  int als_lags = 10;

  // The least-squares form's log-determinant residual sqrt(log det S_k + c):
  // c = log_det_margin * m - min_k log det S_k at the start point (>= 0).
  double log_det_margin = 10.0;

  bool IsValid(std::string* error) const;
};

// How a fit ended (adaptive/tune_verdict.h decides it). Only kConverged is a
// success: the optimiser met a tolerance, the final NLL is no worse than the
// initial guess's, the Hessian of the NLL is positive (semi-)definite on the
// directions not held at a bound (no direction curves downwards) and no
// parameter ended against a bound of the search box. Every other status is
// a failure the CLI reports with exit 1 (no --out file unless --keep-best).
enum class TuneStatus {
  kConverged,        // a verified local minimum
  kNoConvergence,    // iteration limit or line-search trouble; best point kept
  kAllStartsFailed,  // the filter failed (diverged) at every start point
  kNotAMinimum,      // the NLL curves downwards along a free direction (a saddle)
  kWorseThanStart,   // the final NLL is above the initial guess's
  kAtBound,          // a parameter ended against its search box, not its constraint
  kUnverified,       // the Hessian at the end point is not finite (the filter fails
                     // within a finite-difference step): no minimum can be verified
};
const char* TuneStatusName(TuneStatus status);

// One start of the multi-start: theta_start is the start point (initial guess
// or Latin hypercube) and nll_start its NLL (start 1: nll_start ==
// nll_initial). The common-scale pre-search then shifts Q and R by e^s
// (scale_shift): the optimiser begins at theta_scaled with NLL nll_scaled
// (<= nll_start), the first value of its trace.
struct TuneStart {
  std::vector<double> theta_start, theta_scaled, theta_end;
  double scale_shift = 0.0;  // s of the common-scale pre-search (0 when off)
  // +inf when the filter failed there.
  double nll_start = 0.0, nll_scaled = 0.0, nll_end = 0.0;
  int iterations = 0;
  bool ok = false;         // the optimiser ran and its end point is admissible
  bool converged = false;  // its tolerances were met
  std::string termination;
  // The optimiser's path: theta_scaled, then every accepted iterate, and
  // the NLL at each (trace[0] = nll_scaled).
  std::vector<std::vector<double>> trace_theta;
  std::vector<double> trace;
};

struct TuneResult {
  TuneStatus status = TuneStatus::kAllStartsFailed;
  std::string message;
  std::string estimator;  // "ml" | "em" | "als": what was used
  std::string solver;     // ml: "lbfgs" | "least-squares"; else ""

  // The log parameters: names ("log q_theta", "log qc", "log r_sin_theta",
  // "L_q(omega,theta)", ...), values at the initial guess and the optimum,
  // standard errors (+inf when the Hessian is not positive definite) and the
  // "poorly identified by this data" flags (SE > poorly_identified_se for log
  // parameters; for an off-diagonal Cholesky entry L_ij, SE > sqrt(D_ii)).
  std::vector<std::string> names;
  std::vector<bool> is_log;
  std::vector<double> theta_initial, theta;
  std::vector<double> std_errors;
  std::vector<bool> poorly_identified;
  // At or near a bound (AtBound, tuner_impl.h): the estimate and its SE
  // are the search box's, not the data's.
  std::vector<bool> at_bound;
  bool hessian_positive_definite = false;

  // Which entries of theta are physical parameters (the last ones, after Q's
  // and R's), and those parameters on their natural scale: the estimate, its
  // standard error (delta method for log p: SE_p = p SE_log) and the
  // initial value. An infinite SE has its reason in `identifiability`.
  std::vector<bool> is_physical;
  std::vector<std::string> param_names;
  std::vector<double> param_initial, param_values, param_std_errors;
  // The estimated initial states (TunerOptions::estimate_x0): their names,
  // and per row (one shared by every dataset, or one per dataset) the whole
  // x0 at the start and at the estimate, and the standard errors (NaN for
  // the states not estimated). Empty when no x0 is estimated.
  std::vector<std::string> x0_names;
  std::vector<std::vector<double>> x0_initial, x0, x0_std_errors;

  // The correlation matrix of theta (k x k, row-major; NaN where a
  // parameter is not identifiable), the eigenvalues of the observed Fisher
  // information H (ascending), and one sentence per direction the data do
  // not pin down (an eigenvalue below identifiable_ratio * max or with an SE
  // along it above 10 log units), naming the combination they do pin down.
  std::vector<double> correlation;
  std::vector<double> fisher_eigenvalues;
  std::vector<std::string> identifiability;

  // Tuned noise. Q and R row-major (n x n, m x m); for white-accel Q is
  // qc * Q_wa(dt_ref) at the median step dt_ref of the first dataset.
  NoiseParam q_param = NoiseParam::kDiag, r_param = NoiseParam::kDiag;
  std::vector<std::pair<std::string, NoiseParam>> r_param_groups;  // as in the options
  bool q_white_accel = false;
  double qc = 0.0;
  double dt_ref = 0.0;
  std::vector<double> q, r;
  // The tuned filter spec: the input spec with q / qc / r replaced (and
  // the estimated parameters, and x0 by the first row's estimate).
  FilterSpec tuned_spec;

  double nll_initial = 0.0;  // at the initial guess (+inf if the filter failed)
  double nll_tuned = 0.0;
  long updates = 0;  // innovations in the NLL (after burn-in)
  int iterations = 0;
  std::string termination;  // Ceres' message for the best start
  double wall_s = 0.0;
  std::vector<TuneStart> starts;
  int best_start = -1;

  // EM (Estimator::kEm): the exact NLL at the initial guess and after every
  // iteration, the wall time of each iteration, how many iterations raised
  // the NLL (0 on a linear model, where EM is monotone), and the NLL that
  // the L-BFGS form reaches from EM's solution (NaN when not run).
  std::vector<double> nll_history;
  std::vector<double> iteration_wall_s;
  int nll_increases = 0;
  double nll_ml_from_em = std::numeric_limits<double>::quiet_NaN();

  // The best start's trace (TuneStart::trace): the NLL at its scaled start
  // and at every accepted iterate, each an admissible point.
  std::vector<double> trace;

  bool IsSolutionUsable() const { return status != TuneStatus::kAllStartsFailed; }
  bool IsConverged() const { return status == TuneStatus::kConverged; }
};

// Tunes the noise of `spec` (its q / qc / r are the initial guess) on the
// datasets. Throws InputError for bad input (unsupported filter or
// integrator, dataset shorter than burn-in, an all-missing measurement
// column, bounds, wrong parameterisation). A failing filter is a status.
// Defined in adaptive/tuner_impl.h, instantiated per model in
// adaptive/tune_<model>.cpp, reached through ModelEntry::tune.
// Whether the tuner can fit Q, R of `spec` with `options` for a model with
// state_dim states: the options are valid, the filter's own options are
// (filter_options.h of src/run), and the filter is a Gaussian one without
// online adaptation. Checked before any data is read (studies check their
// configurations with it); *error says why not.
bool IsTunable(const FilterSpec& spec, const TunerOptions& options, int state_dim,
               std::string* error);

template <class Model>
TuneResult TuneModel(const FilterSpec& spec, const TunerOptions& options,
                     const std::vector<FilterData>& datasets);

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNER_H_
