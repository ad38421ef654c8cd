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
//   z ~= h(x*) + H delta,                    H = dh/dx at x*
// Exact discretisation over dt (u held constant), by the exponential of the
// augmented matrix
//   exp([[A, B, c], [0, 0, 0], [0, 0, 0]] dt) = [[Phi, Gamma, d], [0, 1, 0], [0, 0, 1]]
//   delta+ = Phi delta + Gamma (u - u*) + d.
// A and H are exact (AD); B is a fourth-order central difference (see
// InputJacobian in linearize.h). The discretisation is cached for the last dt.
//
// WARNING: the linearisation is fixed. Far from x* the filter is simply the
// wrong model; use the Ekf for that. With KfOptions::operating_point empty
// the model is linearised about the prior mean given to each Initialize().
#ifndef ESTLAB_FILTERS_KALMAN_H_
#define ESTLAB_FILTERS_KALMAN_H_

#include <cmath>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
#include "src/filters/linearize.h"

namespace estlab {

struct KfOptions {
  // x*; empty = the prior mean given to Initialize().
  std::vector<double> operating_point;
  // u*.
  double operating_input = 0.0;

  bool IsValid(std::string* error) const;
};

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
  static_assert(kN <= kMaxGainStates, "StepResult::gain holds at most kMaxGainStates rows");

  // Throws InputError for invalid options or an operating point of the wrong
  // length.
  LinearizedKf(const Params& params, const KfOptions& options)
      : params_(params), u_star_(options.operating_input), input_(options.operating_input) {
    std::string error;
    if (!options.IsValid(&error)) throw InputError(error);
    if (!options.operating_point.empty()) {
      if (int(options.operating_point.size()) != kN)
        throw InputError("operating point has " + std::to_string(options.operating_point.size()) +
                         " values, model " + Model::kName + " has " + std::to_string(kN) +
                         " states");
      fixed_point_ = true;
      for (int i = 0; i < kN; ++i) x_star_(i) = options.operating_point[i];
      Linearize();
    }
  }

  std::string Name() const override { return "kf"; }

  void Initialize(const State& mean, const StateCov& cov) override {
    this->SetPrior(mean, cov);
    if (!fixed_point_) {
      x_star_ = mean;
      Linearize();
    }
  }

  void SetInput(double u) override { input_ = u; }

  FilterStatus Predict(double t0, double t1, const StateCov& Q) override {
    const double dt = t1 - t0;
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk) return ready;
    if (!(dt >= 0.0) || !std::isfinite(dt))
      return Fail(FilterStatus::kNonFinite, "step t1 - t0 is negative or not finite");
    if (!linear_finite_)
      return Fail(FilterStatus::kNonFinite, "the linearisation (A, B, c, H) is not finite");
    Discretize(dt);
    // delta = wrap(x - x*);  x- = x* + Phi delta + Gamma (u - u*) + d
    const State delta = WrapResidual<kN>(x_ - x_star_, Model::kAngleStates);
    const State x_pred = x_star_ + phi_ * delta + gamma_ * (input_ - u_star_) + drift_;
    // P- = Phi P Phi^T + Q
    StateCov P_pred = phi_ * P_ * phi_.transpose() + Q;
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
    // z^ = h(x*) + H wrap(x- - x*),  nu = wrap(z - z^)
    const State delta = WrapResidual<kN>(x_ - x_star_, Model::kAngleStates);
    const Measurement z_pred = h_star_ + H_ * delta;
    const Measurement nu = WrapResidual<kM>(z - z_pred, Meas::kAngleOutputs);
    // S = H P H^T + R,  K = P H^T S^-1
    MeasurementCov S;
    Eigen::LLT<MeasurementCov> llt;
    Mat<kN, kM> K;
    if (!KalmanGain<kN, kM>(H_, P_, R, &S, &llt, &K))
      return FailResult(FilterStatus::kFactorizationFailed,
                        "Cholesky of the innovation covariance S = H P H^T + R failed");
    StepResult<kM> result;
    SetInnovation(nu, S, llt, &result);
    // x+ = x- + K nu;  P+ = (I - K H) P (I - K H)^T + K R K^T
    const State x_post = x_ + K * nu;
    const StateCov P_post = JosephUpdate<kN, kM>(P_, K, H_, R);
    if (!BeliefFinite(x_post, P_post))
      return FailResult(FilterStatus::kNonFinite, "updated mean or covariance is not finite");
    x_ = x_post;
    P_ = P_post;
    result.gain = K;
    // post-fit residual eps = wrap(z - h(x*) - H wrap(x+ - x*))
    result.residual =
        WrapResidual<kM>(z - h_star_ - H_ * WrapResidual<kN>(x_ - x_star_, Model::kAngleStates),
                         Meas::kAngleOutputs);
    return result;
  }

  // The continuous linearisation at (x*, u*) and the measurement Jacobian.
  const Mat<kN, kN>& A() const { return A_; }
  const Vec<double, kN>& B() const { return B_; }
  const Vec<double, kN>& c() const { return c_; }
  const Mat<kM, kN>& H() const { return H_; }
  const State& operating_point() const { return x_star_; }
  // The discretisation of the last Predict (Phi, Gamma, d above).
  const Mat<kN, kN>& Phi() const { return phi_; }
  const Vec<double, kN>& Gamma() const { return gamma_; }
  const Vec<double, kN>& d() const { return drift_; }

 private:
  // A = df/dx, B = df/du, c = f(x*, u*), h* = h(x*), H = dh/dx at (x*, u*).
  void Linearize() {
    A_ = ContinuousJacobian<Model>(x_star_, u_star_, params_);
    B_ = InputJacobian<Model>(x_star_, u_star_, params_);
    c_ = ContinuousRhs<Model>(x_star_, u_star_, params_);
    h_star_ = MeasurementAndJacobian<Model, Meas>(x_star_, params_, &H_);
    linear_finite_ =
        A_.allFinite() && B_.allFinite() && c_.allFinite() && H_.allFinite() && h_star_.allFinite();
    cached_dt_ = -1.0;  // invalidate the discretisation cache
  }

  // [[Phi, Gamma, d], [0, 1, 0], [0, 0, 1]] = exp([[A, B, c], [0, 0, 0], [0, 0, 0]] dt),
  // recomputed only when dt changes by more than 1e-12 relative.
  void Discretize(double dt) {
    if (cached_dt_ >= 0.0 && std::abs(dt - cached_dt_) <= 1e-12 * std::max(1.0, cached_dt_)) return;
    Mat<kN + 2, kN + 2> augmented = Mat<kN + 2, kN + 2>::Zero();
    augmented.template topLeftCorner<kN, kN>() = A_ * dt;
    augmented.template block<kN, 1>(0, kN) = B_ * dt;
    augmented.template block<kN, 1>(0, kN + 1) = c_ * dt;
    const Mat<kN + 2, kN + 2> e = augmented.exp();
    phi_ = e.template topLeftCorner<kN, kN>();
    gamma_ = e.template block<kN, 1>(0, kN);
    drift_ = e.template block<kN, 1>(0, kN + 1);
    cached_dt_ = dt;
  }

  using Base::error_;
  using Base::Fail;
  using Base::FailResult;
  using Base::P_;
  using Base::x_;

  Params params_;
  bool fixed_point_ = false;
  bool linear_finite_ = false;
  State x_star_ = State::Zero();
  double u_star_;
  double input_;
  Mat<kN, kN> A_ = Mat<kN, kN>::Zero();
  Vec<double, kN> B_ = Vec<double, kN>::Zero();
  Vec<double, kN> c_ = Vec<double, kN>::Zero();
  Measurement h_star_ = Measurement::Zero();
  Mat<kM, kN> H_ = Mat<kM, kN>::Zero();
  double cached_dt_ = -1.0;
  Mat<kN, kN> phi_ = Mat<kN, kN>::Identity();
  Vec<double, kN> gamma_ = Vec<double, kN>::Zero();
  Vec<double, kN> drift_ = Vec<double, kN>::Zero();
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_KALMAN_H_
