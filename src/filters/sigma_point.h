// Sigma-point Kalman filters: unscented (UKF), cubature (CKF) and
// Gauss-Hermite (GHKF) - one class, the point rule is an option
// (sigma_rules.h).
//
// Usage:
//   auto transition = MakeTransition<models::DoublePendulum>(params, transition_options);
//   SigmaPointOptions options;                 // scaled UKF, alpha = 1e-3, beta = 2
//   options.update = SigmaPointOptions::Update::kPropagate;   // paper 003's code
//   options.jitter = 1e-3;                                    // paper 003's code
//   SigmaPointFilter<models::DoublePendulum, models::DoublePendulum::Full> ukf(
//       transition.get(), params, options);
//   ukf.Initialize(x0, P0);
//   ukf.Predict(t0, t1, Q);
//   StepResult<4> r = ukf.Update(z, R);
//
// The equations (draw, predicted moments, update) are in
// src/filters/sigma_point_step.h, shared with the tuner's likelihood; this
// class owns the belief, the point storage and the transition call. Means of
// a point set are plain weighted sums (no wrapping inside the set), so a wide
// prior on an angle state is handled like any other.
//
// WARNING: kPropagate reuses points whose spread does not contain Q (see
// SigmaPointOptions); the filter does not own the transition.
#ifndef ESTLAB_FILTERS_SIGMA_POINT_H_
#define ESTLAB_FILTERS_SIGMA_POINT_H_

#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/sigma_point_step.h"
#include "src/filters/sigma_rules.h"
#include "src/ode/transition.h"

namespace estlab {

template <class Model, class Meas>
class SigmaPointFilter final : public FilterCommon<Model, Meas> {
 public:
  using Base = FilterCommon<Model, Meas>;
  using Base::kM;
  using Base::kN;
  using typename Base::Measurement;
  using typename Base::MeasurementCov;
  using typename Base::State;
  using typename Base::StateCov;
  using Params = typename Model::Params;
  using StatePoints = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  using MeasurementPoints = Eigen::Matrix<double, kM, Eigen::Dynamic>;
  static_assert(kN <= kMaxGainStates, "StepResult::gain holds at most kMaxGainStates rows");

  // Throws InputError for a null transition or invalid options. All point
  // storage is allocated here, once.
  SigmaPointFilter(Transition<Model>* transition, const Params& params,
                   const SigmaPointOptions& options)
      : transition_(transition), params_(params), options_(options) {
    if (transition_ == nullptr) throw InputError("SigmaPointFilter needs a transition");
    set_ = MakeSigmaPointSet(kN, options);  // validates the options
    const Eigen::Index count = set_.unit_points.cols();
    points_.resize(kN, count);
    propagated_.resize(kN, count);
    measurement_points_.resize(kM, count);
  }

  std::string Name() const override {
    switch (options_.rule) {
      case SigmaRule::kUnscented:
        return "ukf";
      case SigmaRule::kCubature:
        return "ckf";
      case SigmaRule::kGaussHermite:
        return "ghkf";
    }
    return "sigma-point";
  }

  void Initialize(const State& mean, const StateCov& cov) override {
    this->SetPrior(mean, cov);
    have_propagated_ = false;
  }
  void SetInputPath(const InputOf<Model>& u0, const InputOf<Model>& u1) override {
    transition_->SetInput(u0, u1);
  }

  FilterStatus Predict(double t0, double t1, const StateCov& Q) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk) return ready;
    have_propagated_ = false;
    // X_i = x + L xi_i,  L L^T = P + jitter I
    if (!DrawPoints("P + jitter I", /*add_jitter=*/true)) return FilterStatus::kFactorizationFailed;
    // X-_i = Phi(X_i), all points in one call (no virtual call per point)
    try {
      transition_->StepPoints(points_, t0, t1, &propagated_);
    } catch (const std::exception& e) {
      return Fail(FilterStatus::kTransitionFailed, std::string("transition failed: ") + e.what());
    }
    State x_pred;
    StateCov P_pred;
    SigmaPredictMoments<kN>(set_, propagated_, Q, &x_pred, &P_pred);
    if (!BeliefFinite<kN>(x_pred, P_pred))
      return Fail(FilterStatus::kNonFinite, "predicted mean or covariance is not finite");
    // The cross-covariance with the prior is formed only when asked for
    // (PredictCrossCov, the smoothers): the points it needs are kept.
    prior_mean_ = x_;
    this->SetPredicted(x_pred, P_pred);
    have_propagated_ = true;
    return FilterStatus::kOk;
  }

  StepResult<kM> Update(const Measurement& z, const MeasurementCov& R) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk)
      return FailResult(ready, error_);
    // Y_i: the propagated points, or new ones from (x-, P-).
    const bool redraw = options_.update == SigmaPointOptions::Update::kRedraw || !have_propagated_;
    // Y_i = x- + L- xi_i, L- L-^T = P- (the jitter is already in P-).
    if (redraw && !DrawPoints("P-", /*add_jitter=*/false))
      return FailResult(FilterStatus::kFactorizationFailed, error_);
    const StatePoints& Y = redraw ? points_ : propagated_;
    have_propagated_ = false;
    GaussianUpdate<double, kN, kM> u;
    std::string why;
    const FilterStatus status =
        SigmaUpdate<Model, Meas>(set_, Y, &measurement_points_, x_, P_, z, R, this->time(),
                                 transition_->input(), params_, &u, &why);
    if (status != FilterStatus::kOk) return FailResult(status, why);
    StepResult<kM> result;
    SetInnovation<kM>(u.nu, u.S, u.L, MissingMask<kM>(z), &result);
    x_ = u.x;
    P_ = u.P;
    result.gain = u.K;
    // post-fit residual eps = wrap(z - h(x+))
    if (this->post_fit_residual())
      result.residual = WrapResidual<kM>(
          z - EvalMeasurement<Model, Meas, double>(this->time(), x_, transition_->input(), params_),
          Meas::kAngleOutputs);
    return result;
  }

  // C = sum_i Wc_i (X_i - x)(X-_i - x-)^T of the last Predict, from its
  // points; false after an Update (which may redraw them) or before any
  // Predict.
  bool PredictCrossCov(StateCov* C) const override {
    if (!have_propagated_) return false;
    *C = WeightedCrossCov<kN, kN>(points_, prior_mean_, propagated_, x_, set_.cov_weights);
    return true;
  }

  // Number of points of the rule, and the points of the last Predict/Update.
  Eigen::Index num_points() const { return set_.unit_points.cols(); }
  const Eigen::MatrixXd& unit_points() const { return set_.unit_points; }
  const Eigen::VectorXd& mean_weights() const { return set_.mean_weights; }
  const Eigen::VectorXd& cov_weights() const { return set_.cov_weights; }

 private:
  using Base::error_;
  using Base::Fail;
  using Base::FailResult;
  using Base::P_;
  using Base::x_;

  // points_ = x + L xi_i with L L^T = P (+ jitter I when add_jitter).
  bool DrawPoints(const char* what, bool add_jitter) {
    if (DrawSigmaPoints<kN>(set_, x_, P_, add_jitter, &points_)) return true;
    Fail(FilterStatus::kFactorizationFailed,
         std::string("Cholesky of ") + what + " failed (not positive definite)");
    return false;
  }

  Transition<Model>* transition_;
  Params params_;
  SigmaPointOptions options_;
  SigmaPointSet set_;
  StatePoints points_;      // X_i (or Y_i after a redraw)
  StatePoints propagated_;  // X-_i = Phi(X_i)
  MeasurementPoints measurement_points_;
  State prior_mean_ = State::Zero();  // x of the last Predict's start
  bool have_propagated_ = false;      // points_ and propagated_ are the last Predict's
};

// The filter that FilterSpec::filter = SigmaPointOptions runs (MakeFilter,
// src/run/filter_run_impl.h, visits the options with this overload).
template <class Model, class Meas>
std::unique_ptr<Filter<Model, Meas>> MakeFilterFor(const SigmaPointOptions& options,
                                                   Transition<Model>* transition,
                                                   const typename Model::Params& params) {
  return std::make_unique<SigmaPointFilter<Model, Meas>>(transition, params, options);
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_SIGMA_POINT_H_
