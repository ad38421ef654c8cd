// The common interface of estlab's filters.
//
// A filter tracks a belief about the state of `Model` and is driven one
// measurement time at a time:
//
//   filter.Initialize(x0, P0);
//   for each measurement time t_k:
//     if (k > 0) status = filter.Predict(t_{k-1}, t_k, Q);   // process model
//     filter.SetInput(u_k); filter.SetTime(t_k);            // seen by h(t, x, u)
//     if (z_k present) StepResult r = filter.Update(z_k, R); // measurement
//
// Q and R are arguments, not members, so adaptation (adaptive/) and tuning
// need no filter changes. A numerical failure (failed Cholesky, non-finite
// values, integrator failure) is a status, never an exception or a crash.
//
// Measurement type `Meas` is one of Model's measurement structs (kDim,
// kOutputs, kAngleOutputs, Eval<T>(x, params), or h(x, u) or h(t, x, u):
// models/model.h). Innovations of angle outputs are wrapped to (-pi, pi].
#ifndef ESTLAB_FILTERS_FILTER_H_
#define ESTLAB_FILTERS_FILTER_H_

#include <array>
#include <cmath>
#include <string>
#include <type_traits>

#include "models/model.h"
#include "src/core/types.h"
#include "src/ode/transition.h"

namespace estlab {

enum class FilterStatus {
  kOk = 0,
  kFactorizationFailed,  // a Cholesky factorisation (P, S, P-) failed
  kNonFinite,            // a NaN or inf appeared in the mean or covariance
  kTransitionFailed,     // the integrator failed (e.g. CVODES too much work)
};

const char* FilterStatusName(FilterStatus status);

// Largest state dimension of a filter that reports its Kalman gain
// (StepResult::gain has inline storage of this many rows).
inline constexpr int kMaxGainStates = 16;

// What one measurement update produced. log_likelihood is
// log N(innovation; 0, innovation_cov) = -1/2 (log det S + nu^T S^-1 nu + m log 2 pi);
// nis = nu^T S^-1 nu. For a particle filter, log_likelihood is
// log(sum_i w_i p(z | x_i)) with w_i the normalised weights before the update
// (= log((1/N) sum_i p(z | x_i)) right after resampling), and
// innovation/innovation_cov are the moments of the predicted measurement
// particles (plus R).
template <int M>
struct StepResult {
  Vec<double, M> innovation = Vec<double, M>::Zero();
  Mat<M, M> innovation_cov = Mat<M, M>::Identity();
  double log_likelihood = 0.0;
  double nis = 0.0;
  // The components of z the update used (missing.h); the others are NaN in
  // innovation and innovation_cov. NIS has this many degrees of freedom.
  int observed = M;
  FilterStatus status = FilterStatus::kOk;
  std::string message;  // set when status != kOk

  // For the adaptive rules: the Kalman gain K (n x M; 0 rows for filters
  // that have none) and the post-fit residual z - h(x+) (zero when unset;
  // NaN in a missing component of z, as the innovation).
  // The gain has inline storage for up to kMaxGainStates rows, so returning a
  // StepResult never touches the heap (issue "Performance").
  Eigen::Matrix<double, Eigen::Dynamic, M, Eigen::ColMajor, kMaxGainStates, M> gain;
  Vec<double, M> residual = Vec<double, M>::Zero();
};

template <DynamicModel Model, class Meas>
requires MeasurementOf<Meas, Model>
class Filter {
 public:
  static constexpr int kN = Model::kStateDim;
  static constexpr int kM = Meas::kDim;
  using State = Vec<double, kN>;
  using StateCov = Mat<kN, kN>;
  using Measurement = Vec<double, kM>;
  using MeasurementCov = Mat<kM, kM>;

  virtual ~Filter() = default;
  virtual std::string Name() const = 0;

  // Sets the prior (mean, covariance) at the current time.
  virtual void Initialize(const State& mean, const StateCov& cov) = 0;
  // Propagates the belief from t0 to t1 with process-noise covariance Q
  // (already for the step t1 - t0). The input is whatever the transition's
  // SetInput last received.
  virtual FilterStatus Predict(double t0, double t1, const StateCov& process_noise) = 0;
  // Corrects with measurement z and measurement-noise covariance R.
  virtual StepResult<kM> Update(const Measurement& z, const MeasurementCov& measurement_noise) = 0;

  // The input u: held over the next Predict, and seen by the next Update of
  // a measurement h(x, u) (the run loops set the input of row k before its
  // update; zero-order hold keeps it over [t_k, t_k+1)). InputOf<Model>: a
  // double for models with at most one input.
  void SetInput(const InputOf<Model>& u) { SetInputPath(u, u); }
  // The input at the next Predict's start (u0, also seen by an Update
  // before it) and end (u1): the prediction follows the line between them
  // (linear hold, src/ode/input_path.h). Filters with a Transition forward
  // both to it (transition->SetInput(u0, u1)); the LinearizedKf stores
  // them. The default ignores them (models without input).
  virtual void SetInputPath(const InputOf<Model>& /*u0*/, const InputOf<Model>& /*u1*/) {}
  // The time t_k of the next Update, seen by a measurement h(t, x, u)
  // (EvalMeasurement, models/model.h): the run loops set it with the input
  // of row k, before its update.
  void SetTime(double t) { time_ = t; }
  double time() const { return time_; }

  virtual const State& mean() const = 0;
  virtual const StateCov& cov() const = 0;
  virtual std::string last_error() const { return ""; }

  // For the RTS smoother (rts_smoother.h): C = Cov(x_{k-1}, x_k | z_{1:k-1})
  // of the last successful Predict, between the belief it started from and
  // the predicted state (KF: P Phi^T; EKF: P F^T; sigma points:
  // sum_i Wc_i (X_i - x)(X-_i - x-)^T). False for filters without one (the
  // particle filter) or before any Predict.
  virtual bool PredictCrossCov(StateCov* /*C*/) const { return false; }

  // For the degeneracy check of the run loop (filter_run_impl.h): the
  // effective sample size 1 / sum_i w_i^2 of the last Update's weights
  // (before any resampling) and the number of particles. False for filters
  // without particles, or before any Update.
  virtual bool EffectiveSampleSize(double* /*ess*/, int* /*particles*/) const { return false; }

  // Whether Update fills StepResult::residual, the post-fit residual
  // wrap(z - h(x+)): one more evaluation of h per update, needed only by the
  // adaptive rules (noise_adapter.h). On by default; the run loop
  // (filter_run_impl.h) turns it off unless the run adapts Q or R.
  void SetPostFitResidual(bool on) { post_fit_residual_ = on; }
  bool post_fit_residual() const { return post_fit_residual_; }

 private:
  double time_ = 0.0;
  bool post_fit_residual_ = true;
};

// Wraps the angle components (flags[i] true) of a residual to (-pi, pi], for
// any scalar T (WrapAngleT; T is named, not deduced, so that an Eigen
// expression converts: WrapResidual<M>(z - h) for double, <M, T> otherwise).
template <int D, class T = double, std::size_t K>
Vec<T, D> WrapResidual(std::type_identity_t<Vec<T, D>> r, const std::array<bool, K>& angle_flags) {
  for (int i = 0; i < D; ++i)
    if (angle_flags[i]) r(i) = WrapAngleT(r(i));
  return r;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_FILTER_H_
