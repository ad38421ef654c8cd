// Extended Kalman filter, and the iterated EKF (IEKF) as an option.
//
// Usage:
//   auto transition = MakeTransition<models::Pendulum>(params, transition_options);
//   EkfOptions options;            // options.iterations = 3 for the IEKF
//   Ekf<models::Pendulum, models::Pendulum::Sin> ekf(transition.get(), params, options);
//   ekf.Initialize(x0, P0);
//   ekf.Predict(t0, t1, Q);        // x- = Phi(x), P- = F P F^T + Q
//   StepResult<1> r = ekf.Update(z, R);
//
// The process Jacobian F = dPhi/dx is whatever transition->StepWithJacobian
// returns: the exact derivative of the discrete map for the fixed-step
// integrators (AD through the steps), CVODES forward sensitivities otherwise.
// The measurement Jacobian H = dh/dx is exact (AD of Meas::Eval).
//
// Update (i = 0 .. iterations-1, x_0 = x-, Bell & Cathey 1993):
//   H_i = dh/dx(x_i),  S_i = H_i P- H_i^T + R,  K_i = P- H_i^T S_i^-1
//   x_{i+1} = x- + K_i (wrap(z - h(x_i)) - H_i (x- - x_i))
//   x+ = x_iterations,  P+ = (I - K H) P- (I - K H)^T + K R K^T  (last K, H)
// With iterations = 1 this is the EKF. The innovation nu = wrap(z - h(x-)), S,
// the log-likelihood and NIS are reported at the prior (i = 0), so they are
// the EKF's whatever the number of iterations.
//
// WARNING: the filter does not own the transition; it must outlive the
// filter, and its input is the one set by SetInput (on either object).
#ifndef ESTLAB_FILTERS_EKF_H_
#define ESTLAB_FILTERS_EKF_H_

#include <exception>
#include <string>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
#include "src/filters/linearize.h"
#include "src/ode/transition.h"

namespace estlab {

struct EkfOptions {
  // 1 = EKF; > 1 = iterated EKF with this many Gauss-Newton iterations.
  int iterations = 1;

  bool IsValid(std::string* error) const;
};

template <class Model, class Meas>
class Ekf final : public FilterCommon<Model, Meas> {
 public:
  using Base = FilterCommon<Model, Meas>;
  using Base::kM;
  using Base::kN;
  using typename Base::Measurement;
  using typename Base::MeasurementCov;
  using typename Base::State;
  using typename Base::StateCov;
  using Params = typename Model::Params;
  static_assert(kN <= kMaxGainStates, "StepResult::gain holds at most kMaxGainStates rows");

  // Throws InputError for a null transition or invalid options.
  Ekf(Transition<Model>* transition, const Params& params, const EkfOptions& options)
      : transition_(transition), params_(params), options_(options) {
    std::string error;
    if (transition_ == nullptr) throw InputError("Ekf needs a transition");
    if (!options.IsValid(&error)) throw InputError(error);
  }

  std::string Name() const override { return options_.iterations > 1 ? "iekf" : "ekf"; }
  void Initialize(const State& mean, const StateCov& cov) override { this->SetPrior(mean, cov); }
  void SetInput(double u) override { transition_->SetInput(u); }

  FilterStatus Predict(double t0, double t1, const StateCov& Q) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk) return ready;
    // x- = Phi(x),  F = dPhi/dx (x)
    Mat<kN, kN> F;
    State x_pred;
    try {
      x_pred = transition_->StepWithJacobian(x_, t0, t1, &F);
    } catch (const std::exception& e) {
      return Fail(FilterStatus::kTransitionFailed, std::string("transition failed: ") + e.what());
    }
    // P- = F P F^T + Q
    StateCov P_pred = F * P_ * F.transpose() + Q;
    Symmetrize(&P_pred);
    if (!BeliefFinite(x_pred, P_pred))
      return Fail(FilterStatus::kNonFinite, "predicted mean or covariance is not finite");
    x_ = x_pred;
    P_ = P_pred;
    return FilterStatus::kOk;
  }

  StepResult<kM> Update(const Measurement& z, const MeasurementCov& R) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk)
      return FailResult(ready, error_);
    const State x_prior = x_;
    Mat<kM, kN> H;
    MeasurementCov S;
    Eigen::LLT<MeasurementCov> llt;
    Mat<kN, kM> K;
    // i = 0:  nu = wrap(z - h(x-)),  S = H P- H^T + R,  K = P- H^T S^-1
    const Measurement nu = WrapResidual<kM>(
        z - MeasurementAndJacobian<Model, Meas>(x_prior, params_, &H), Meas::kAngleOutputs);
    if (!KalmanGain<kN, kM>(H, P_, R, &S, &llt, &K))
      return FailResult(FilterStatus::kFactorizationFailed,
                        "Cholesky of the innovation covariance S = H P H^T + R failed");
    StepResult<kM> result;
    SetInnovation(nu, S, llt, &result);
    State x_iter = x_prior + K * nu;  // x_1 = x- + K_0 nu
    for (int i = 1; i < options_.iterations; ++i) {
      // x_{i+1} = x- + K_i (wrap(z - h(x_i)) - H_i (x- - x_i))
      const Measurement r = WrapResidual<kM>(
          z - MeasurementAndJacobian<Model, Meas>(x_iter, params_, &H), Meas::kAngleOutputs);
      if (!KalmanGain<kN, kM>(H, P_, R, &S, &llt, &K))
        return FailResult(
            FilterStatus::kFactorizationFailed,
            "Cholesky of S = H P H^T + R failed in IEKF iteration " + std::to_string(i));
      x_iter = x_prior + K * (r - H * WrapResidual<kN>(x_prior - x_iter, Model::kAngleStates));
    }
    // P+ = (I - K H) P- (I - K H)^T + K R K^T with the last K, H
    const StateCov P_post = JosephUpdate<kN, kM>(P_, K, H, R);
    if (!BeliefFinite(x_iter, P_post))
      return FailResult(FilterStatus::kNonFinite, "updated mean or covariance is not finite");
    x_ = x_iter;
    P_ = P_post;
    result.gain = K;
    // post-fit residual eps = wrap(z - h(x+))
    result.residual = WrapResidual<kM>(
        z - MeasurementAndJacobian<Model, Meas>(x_, params_, nullptr), Meas::kAngleOutputs);
    return result;
  }

 private:
  using Base::error_;
  using Base::Fail;
  using Base::FailResult;
  using Base::P_;
  using Base::x_;

  Transition<Model>* transition_;
  Params params_;
  EkfOptions options_;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_EKF_H_
