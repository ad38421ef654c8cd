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
// The measurement Jacobian H = dh/dx is exact (AD of Meas::Eval). The
// equations (EKF and IEKF) are in src/filters/ekf_step.h, shared with the
// tuner's likelihood; this class owns the belief and the transition call.
//
// WARNING: the filter does not own the transition; it must outlive the
// filter, and its input is the one set by SetInput (on either object).
#ifndef ESTLAB_FILTERS_EKF_H_
#define ESTLAB_FILTERS_EKF_H_

#include <exception>
#include <memory>
#include <string>

#include "src/filters/ekf_step.h"
#include "src/filters/filter.h"
#include "src/filters/filter_options.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/linearize.h"
#include "src/ode/transition.h"

namespace estlab {

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
  void SetInputPath(const InputOf<Model>& u0, const InputOf<Model>& u1) override {
    transition_->SetInput(u0, u1);
  }

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
    const StateCov P_pred = EkfPredictCovariance<kN>(F, P_, Q);  // F P F^T + Q
    if (!BeliefFinite<kN>(x_pred, P_pred))
      return Fail(FilterStatus::kNonFinite, "predicted mean or covariance is not finite");
    this->SetPredicted(x_pred, P_pred, P_ * F.transpose());  // C = P F^T
    return FilterStatus::kOk;
  }

  StepResult<kM> Update(const Measurement& z, const MeasurementCov& R) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk)
      return FailResult(ready, error_);
    GaussianUpdate<double, kN, kM> u;
    std::string why;
    const FilterStatus status = EkfUpdate<Model, Meas>(
        x_, P_, z, R, this->time(), transition_->input(), params_, options_.iterations, &u, &why);
    if (status != FilterStatus::kOk) return FailResult(status, why);
    StepResult<kM> result;
    SetInnovation<kM>(u.nu, u.S, u.L, MissingMask<kM>(z), &result);
    x_ = u.x;
    P_ = u.P;
    result.gain = u.K;
    // post-fit residual eps = wrap(z - h(x+))
    if (this->post_fit_residual())
      result.residual =
          WrapResidual<kM>(z - MeasurementAndJacobian<Model, Meas>(
                                   this->time(), x_, transition_->input(), params_, nullptr),
                           Meas::kAngleOutputs);
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

// The filter that FilterSpec::filter = EkfOptions runs (MakeFilter,
// src/run/filter_run_impl.h, visits the options with this overload).
template <class Model, class Meas>
std::unique_ptr<Filter<Model, Meas>> MakeFilterFor(const EkfOptions& options,
                                                   Transition<Model>* transition,
                                                   const typename Model::Params& params) {
  return std::make_unique<Ekf<Model, Meas>>(transition, params, options);
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_EKF_H_
