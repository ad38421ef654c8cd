// Linear(ised) Kalman filter: the continuous model linearised ONCE about an
// operating point (x*, u*), discretised exactly with a zero-order hold on the
// input (as MATLAB c2d), and run as a standard Kalman filter (paper 004's KF).
//
// Usage:
//   KfOptions options;
//   options.operating_point = {0.0, 0.0, M_PI, 0.0};   // upright cart-pole
//   LinearizedKf<models::CartPole, models::CartPole::XTheta> kf(params, options);
//   kf.Initialize(x0, P0);
//   kf.SetInput(force);
//   kf.Predict(t0, t1, Q);
//   StepResult<2> r = kf.Update(z, R);
//
// Model (deviations from the operating point, delta = x - x*, angle states of
// delta wrapped):
//   d/dt delta = A delta + B (u - u*) + c,   A = df/dx, B = df/du, c = f(x*, u*)
//   z ~= h(x*, u*) + H delta + D (u - u*),   H = dh/dx, D = dh/du at (x*, u*)
// (D = 0 unless h sees u; u: the input at the update's time; h*, H, D are
// re-linearised about x* at each update's time t_k when h sees t, SetTime).
// Exact discretisation over dt, by the exponential of the augmented matrix
//   exp([[A, B, c], [0, 0, 0], [0, 0, 0]] dt) = [[Phi, Gamma, d], [0, I, 0], [0, 0, 1]]
//   delta+ = Phi delta + Gamma (u - u*) + d            (u held: zero-order hold)
// and, for a linear hold (u from u0 at t0 to u1 at t1, src/ode/input_path.h),
// the first-order-hold exponential, with w' = 0, u' = w / dt:
//   exp([[A, B, 0, c], [0, 0, I/dt, 0], [0, 0, 0, 0], [0, 0, 0, 0]] dt)
//     = [[Phi, Gamma, Gamma1, d], ...],  Gamma1 = int_0^dt e^{A(dt-s)} B s/dt ds
//   delta+ = Phi delta + Gamma (u0 - u*) + Gamma1 (u1 - u0) + d.
// A and H are exact (AD); B and D are fourth-order central differences (see
// InputDerivative in linearize.h). The discretisation is cached for the last dt.
// A discrete-time model (kDiscreteTime) is its own discretisation: its map
// over dt linearised at (x*, u*), Phi = dStep/dx, Gamma = dStep/du,
// d = Step(x*, u*) - x* (StepMapJacobians); the transition's substeps do not
// apply to the KF, as they do not for continuous models.
//
// WARNING: the linearisation is fixed. Far from x* the filter is simply the
// wrong model; use the Ekf for that. With KfOptions::operating_point empty
// the model is linearised about the prior mean given to each Initialize().
#ifndef ESTLAB_FILTERS_KALMAN_H_
#define ESTLAB_FILTERS_KALMAN_H_

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "src/filters/filter.h"
#include "src/filters/filter_options.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/kalman_step.h"
#include "src/filters/linearize.h"
#include "src/filters/matrix_exponential.h"
#include "src/ode/transition.h"

namespace estlab {

template <class Model, class Meas>
class LinearizedKf final : public FilterCommon<Model, Meas> {
 public:
  using Base = FilterCommon<Model, Meas>;
  using Base::kM;
  using Base::kN;
  using typename Base::Measurement;
  using typename Base::MeasurementCov;
  using typename Base::State;
  using typename Base::StateCov;
  using Params = typename Model::Params;
  static constexpr int kU = kInputCols<Model>;
  static_assert(kN <= kMaxGainStates, "StepResult::gain holds at most kMaxGainStates rows");

  // Throws InputError for invalid options or an operating point of the wrong
  // length.
  LinearizedKf(const Params& params, const KfOptions& options) : params_(params) {
    std::string error;
    if (!options.IsValid(&error)) throw InputError(error);
    const size_t inputs = options.operating_input.size();
    if (inputs != 0 && int(inputs) != kInputDim<Model>)
      throw InputError("operating input has " + std::to_string(inputs) + " values, model " +
                       Model::kName + " has " + std::to_string(kInputDim<Model>) + " inputs");
    input_ = input_end_ = InputFrom<Model>(inputs ? options.operating_input.data() : nullptr);
    lin_.u_star = InputColumn<Model>(input_);
    if (!options.operating_point.empty()) {
      if (int(options.operating_point.size()) != kN)
        throw InputError("operating point has " + std::to_string(options.operating_point.size()) +
                         " values, model " + Model::kName + " has " + std::to_string(kN) +
                         " states");
      fixed_point_ = true;
      for (int i = 0; i < kN; ++i) lin_.x_star(i) = options.operating_point[i];
      Linearize();
    }
  }

  std::string Name() const override { return "kf"; }

  void Initialize(const State& mean, const StateCov& cov) override {
    this->SetPrior(mean, cov);
    if (!fixed_point_) {
      lin_.x_star = mean;
      Linearize();
    }
  }

  void SetInputPath(const InputOf<Model>& u0, const InputOf<Model>& u1) override {
    input_ = u0;
    input_end_ = u1;
  }

  FilterStatus Predict(double t0, double t1, const StateCov& Q) override {
    const double dt = t1 - t0;
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk) return ready;
    if (!(dt >= 0.0) || !std::isfinite(dt))
      return Fail(FilterStatus::kNonFinite, "step t1 - t0 is negative or not finite");
    if (!dynamics_finite_)
      return Fail(FilterStatus::kNonFinite, "the linearisation (A, B, c) is not finite");
    Discretize(dt, !(input_ == input_end_));
    // x- = x* + Phi wrap(x - x*) + Gamma (u0 - u*) + Gamma1 (u1 - u0) + d,
    // P- = Phi P Phi^T + Q
    State x_pred = x_;
    StateCov P_pred = P_;
    KfPredict<Model, kM>(lin_, step_, input_, input_end_, Q, &x_pred, &P_pred);
    if (!BeliefFinite<kN>(x_pred, P_pred))
      return Fail(FilterStatus::kNonFinite, "predicted mean or covariance is not finite");
    this->SetPredicted(x_pred, P_pred, P_ * step_.phi.transpose());  // C = P Phi^T
    return FilterStatus::kOk;
  }

  StepResult<kM> Update(const Measurement& z, const MeasurementCov& R) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk)
      return FailResult(ready, error_);
    if constexpr (MeasurementSeesTime<Meas, Model>)  // h*, H, D at this update's time
      KfLinearizeMeasurement<Model, Meas>(this->time(), params_, &lin_);
    // The rows of the components observed (a missing sensor's h may be
    // undefined at x*: its rows are masked out of the update, missing.h).
    const MissingMask<kM> missing(z);
    if (!(lin_.h_star.allFinite() && lin_.H.allFinite() && lin_.D.allFinite()))
      for (int j = 0; j < kM; ++j)
        if (!missing.Missing(j) && !(std::isfinite(lin_.h_star(j)) && lin_.H.row(j).allFinite() &&
                                     lin_.D.row(j).allFinite()))
          return FailResult(FilterStatus::kNonFinite,
                            "h(t, x*, u*) or its Jacobians H, D are not finite at this update");
    GaussianUpdate<double, kN, kM> u;
    std::string why;
    const FilterStatus status = KfUpdate<Model, Meas>(lin_, input_, x_, P_, z, R, &u, &why);
    if (status != FilterStatus::kOk) return FailResult(status, why);
    StepResult<kM> result;
    SetInnovation<kM>(u.nu, u.S, u.L, missing, &result);
    x_ = u.x;
    P_ = u.P;
    result.gain = u.K;
    // post-fit residual eps = wrap(z - h(x*, u*) - H wrap(x+ - x*) - D (u - u*))
    if (this->post_fit_residual())
      result.residual = WrapResidual<kM>(
          z - lin_.h_star - lin_.H * WrapResidual<kN>(x_ - lin_.x_star, Model::kAngleStates) -
              lin_.D * (InputColumn<Model>(input_) - lin_.u_star),
          Meas::kAngleOutputs);
    return result;
  }

  // The continuous linearisation at (x*, u*) and the measurement Jacobian.
  const Mat<kN, kN>& A() const { return A_; }
  const Mat<kN, kU>& B() const { return B_; }
  const Vec<double, kN>& c() const { return c_; }
  const Mat<kM, kN>& H() const { return lin_.H; }
  const State& operating_point() const { return lin_.x_star; }
  // What the steps (kalman_step.h) use: the linearisation, and the
  // discretisation of the last Predict (Phi, Gamma, d above).
  const KfLinearization<kN, kM, kU>& linearization() const { return lin_; }
  const KfDiscretization<kN, kU>& discretization() const { return step_; }
  const Mat<kN, kN>& Phi() const { return step_.phi; }
  const Mat<kN, kU>& Gamma() const { return step_.gamma; }
  const Vec<double, kN>& d() const { return step_.drift; }

  // The discretisation of the last Predict, for a step of dt: with Gamma1
  // when with_ramp (the tuner's likelihood asks for a linear hold's).
  const KfDiscretization<kN, kU>& DiscretizationFor(double dt, bool with_ramp) {
    Discretize(dt, with_ramp);
    return step_;
  }

 private:
  // A = df/dx, B = df/du, c = f(x*, u*), h* = h(x*, u*), H = dh/dx and
  // D = dh/du at (x*, u*).
  void Linearize() {
    const InputOf<Model> u_star = InputFrom<Model>(lin_.u_star.data());
    if constexpr (!kDiscreteTime<Model>) {  // a step map is linearised per dt (Discretize)
      A_ = ContinuousJacobian<Model>(lin_.x_star, u_star, params_);
      B_ = InputJacobian<Model>(lin_.x_star, u_star, params_);
      c_ = ContinuousRhs<Model>(lin_.x_star, u_star, params_);
    }
    KfLinearizeMeasurement<Model, Meas>(this->time(), params_, &lin_);
    // h is checked where it is used (Update): a measurement that sees t may
    // be undefined at the time of Initialize and fine at every update's.
    dynamics_finite_ = A_.allFinite() && B_.allFinite() && c_.allFinite();
    cached_dt_ = -1.0;  // invalidate the discretisation cache
  }

  // Phi, Gamma, d (and Gamma1 when with_ramp) of the header comment,
  // recomputed only when dt changes by more than 1e-12 relative or Gamma1 is
  // asked for the first time.
  void Discretize(double dt, bool with_ramp) {
    if (cached_dt_ >= 0.0 && std::abs(dt - cached_dt_) <= 1e-12 * std::max(1.0, cached_dt_) &&
        (step_.with_ramp || !with_ramp))
      return;
    if constexpr (kDiscreteTime<Model>) {
      // A step map: Phi = dStep/dx, Gamma = dStep/du, d = Step(x*, u*) - x*.
      step_.drift = StepMapJacobians<Model>(lin_.x_star, InputFrom<Model>(lin_.u_star.data()), dt,
                                            params_, &step_.phi, &step_.gamma) -
                    lin_.x_star;
      step_.gamma1.setZero();  // the map sees u0 under either hold
      step_.with_ramp = with_ramp;
      cached_dt_ = dt;
      return;
    }
    if (with_ramp) {
      constexpr int kA = kN + 2 * kU + 1;  // [x, u, w, 1]
      Mat<kA, kA> augmented = Mat<kA, kA>::Zero();
      augmented.template topLeftCorner<kN, kN>() = A_ * dt;
      augmented.template block<kN, kU>(0, kN) = B_ * dt;
      augmented.template block<kU, kU>(kN, kN + kU).setIdentity();  // (I / dt) dt
      augmented.template block<kN, 1>(0, kN + 2 * kU) = c_ * dt;
      const Mat<kA, kA> e = MatrixExponential<kA>(augmented);
      step_.phi = e.template topLeftCorner<kN, kN>();
      step_.gamma = e.template block<kN, kU>(0, kN);
      step_.gamma1 = e.template block<kN, kU>(0, kN + kU);
      step_.drift = e.template block<kN, 1>(0, kN + 2 * kU);
    } else {
      constexpr int kA = kN + kU + 1;
      Mat<kA, kA> augmented = Mat<kA, kA>::Zero();
      augmented.template topLeftCorner<kN, kN>() = A_ * dt;
      augmented.template block<kN, kU>(0, kN) = B_ * dt;
      augmented.template block<kN, 1>(0, kN + kU) = c_ * dt;
      const Mat<kA, kA> e = MatrixExponential<kA>(augmented);
      step_.phi = e.template topLeftCorner<kN, kN>();
      step_.gamma = e.template block<kN, kU>(0, kN);
      step_.gamma1.setZero();
      step_.drift = e.template block<kN, 1>(0, kN + kU);
    }
    step_.with_ramp = with_ramp;
    cached_dt_ = dt;
  }

  using Base::error_;
  using Base::Fail;
  using Base::FailResult;
  using Base::P_;
  using Base::x_;

  Params params_;
  bool fixed_point_ = false;
  bool dynamics_finite_ = false;
  KfLinearization<kN, kM, kU> lin_;  // x*, u*, h(x*, u*), H, D
  InputOf<Model> input_;
  InputOf<Model> input_end_;  // at the next Predict's end (linear hold)
  Mat<kN, kN> A_ = Mat<kN, kN>::Zero();
  Mat<kN, kU> B_ = Mat<kN, kU>::Zero();
  Vec<double, kN> c_ = Vec<double, kN>::Zero();
  double cached_dt_ = -1.0;
  KfDiscretization<kN, kU> step_;  // Phi, Gamma, d of cached_dt_
};

// The filter that FilterSpec::filter = KfOptions runs (MakeFilter,
// src/run/filter_run_impl.h, visits the options with this overload).
template <class Model, class Meas>
std::unique_ptr<Filter<Model, Meas>> MakeFilterFor(const KfOptions& options,
                                                   Transition<Model>* /*transition*/,
                                                   const typename Model::Params& params) {
  return std::make_unique<LinearizedKf<Model, Meas>>(params, options);
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_KALMAN_H_
