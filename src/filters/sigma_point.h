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
// Predict (L points xi_i, weights Wm_i, Wc_i of the rule):
//   P + jitter I = L L^T (Cholesky),   X_i = x + L xi_i,   X-_i = Phi(X_i)
//   x- = X-_0 + sum_i Wm_i wrap(X-_i - X-_0)
//   P- = sum_i Wc_i wrap(X-_i - x-) wrap(X-_i - x-)^T + Q + jitter I
// Update (Y_i = X-_i for kPropagate, Y_i = x- + L- xi_i with L- L-^T = P- for
// kRedraw):
//   Z_i = h(Y_i),  z^ = Z_0 + sum_i Wm_i wrap(Z_i - Z_0)
//   S = sum_i Wc_i dZ_i dZ_i^T + R + jitter I,   C = sum_i Wc_i dY_i dZ_i^T
//   K = C S^-1 (Cholesky solve),   nu = wrap(z - z^)
//   x+ = x- + K nu,   P+ = P- - K S K^T (symmetrised)
// wrap() acts on angle states (Model::kAngleStates) and angle outputs
// (Meas::kAngleOutputs) only; the means above are then circular means taken
// relative to the first point.
//
// WARNING: kPropagate reuses points whose spread does not contain Q (see
// SigmaPointOptions); the filter does not own the transition.
#ifndef ESTLAB_FILTERS_SIGMA_POINT_H_
#define ESTLAB_FILTERS_SIGMA_POINT_H_

#include <exception>
#include <string>
#include <vector>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
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
    std::string error;
    if (transition_ == nullptr) throw InputError("SigmaPointFilter needs a transition");
    if (!options.IsValid(&error)) throw InputError(error);
    const UnitSigmaPoints unit = MakeUnitSigmaPoints(kN, options);
    unit_points_ = unit.points;
    mean_weights_ = unit.mean_weights;
    cov_weights_ = unit.cov_weights;
    const Eigen::Index count = unit_points_.cols();
    // Unscented and cubature points lie on the axes (xi_i = s_i e_k): then
    // L xi_i = s_i L e_k, a scaled column of L instead of a matrix-vector
    // product (the same numbers: the other terms are exact zeros).
    axis_index_.assign(count, -1);
    axis_scale_.setZero(count);
    axis_aligned_ = true;
    for (Eigen::Index i = 0; i < count && axis_aligned_; ++i) {
      for (int k = 0; k < kN; ++k) {
        if (unit_points_(k, i) == 0.0) continue;
        if (axis_index_[i] >= 0) axis_aligned_ = false;
        axis_index_[i] = k;
        axis_scale_(i) = unit_points_(k, i);
      }
    }
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
  void SetInput(double u) override { transition_->SetInput(u); }

  FilterStatus Predict(double t0, double t1, const StateCov& Q) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk) return ready;
    have_propagated_ = false;
    // X_i = x + L xi_i,  L L^T = P + jitter I
    if (!DrawPoints(x_, P_, "P + jitter I")) return FilterStatus::kFactorizationFailed;
    // X-_i = Phi(X_i), all points in one call (no virtual call per point)
    try {
      transition_->StepPoints(points_, t0, t1, &propagated_);
    } catch (const std::exception& e) {
      return Fail(FilterStatus::kTransitionFailed, std::string("transition failed: ") + e.what());
    }
    // x- = X-_0 + sum_i Wm_i wrap(X-_i - X-_0)
    const State x_pred = WeightedMean<kN>(propagated_, mean_weights_, Model::kAngleStates);
    // P- = sum_i Wc_i dX_i dX_i^T + Q + jitter I
    StateCov P_pred = WeightedCov<kN>(propagated_, x_pred, Model::kAngleStates, cov_weights_);
    P_pred += Q;
    P_pred.diagonal().array() += options_.jitter;
    Symmetrize(&P_pred);
    if (!BeliefFinite(x_pred, P_pred))
      return Fail(FilterStatus::kNonFinite, "predicted mean or covariance is not finite");
    x_ = x_pred;
    P_ = P_pred;
    have_propagated_ = true;
    return FilterStatus::kOk;
  }

  StepResult<kM> Update(const Measurement& z, const MeasurementCov& R) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk)
      return FailResult(ready, error_);
    // Y_i: the propagated points, or new ones from (x-, P-).
    const bool redraw = options_.update == SigmaPointOptions::Update::kRedraw || !have_propagated_;
    if (redraw) {
      // Y_i = x- + L- xi_i, L- L-^T = P- (the jitter is already in P-).
      if (!DrawPoints(x_, P_, "P-", /*add_jitter=*/false))
        return FailResult(FilterStatus::kFactorizationFailed, error_);
    }
    const StatePoints& Y = redraw ? points_ : propagated_;
    have_propagated_ = false;
    // Z_i = h(Y_i),  z^ = Z_0 + sum_i Wm_i wrap(Z_i - Z_0)
    for (Eigen::Index i = 0; i < Y.cols(); ++i)
      measurement_points_.col(i) = Meas::Eval(State(Y.col(i)), params_);
    const Measurement z_pred =
        WeightedMean<kM>(measurement_points_, mean_weights_, Meas::kAngleOutputs);
    // S = sum_i Wc_i dZ_i dZ_i^T + R + jitter I,  C = sum_i Wc_i dY_i dZ_i^T
    MeasurementCov S =
        WeightedCov<kM>(measurement_points_, z_pred, Meas::kAngleOutputs, cov_weights_);
    S += R;
    S.diagonal().array() += options_.jitter;
    Symmetrize(&S);
    const Mat<kN, kM> C = WeightedCrossCov<kN, kM>(Y, x_, Model::kAngleStates, measurement_points_,
                                                   z_pred, Meas::kAngleOutputs, cov_weights_);
    const Eigen::LLT<MeasurementCov> llt(S);
    if (llt.info() != Eigen::Success)
      return FailResult(FilterStatus::kFactorizationFailed,
                        "Cholesky of the innovation covariance S failed");
    // K = C S^-1, i.e. K^T = S^-1 C^T
    const MeasurementCov S_lower = llt.matrixL();
    const Mat<kN, kM> K = CholeskySolve<kM, kN>(S_lower, C.transpose()).transpose();
    const Measurement nu = WrapResidual<kM>(z - z_pred, Meas::kAngleOutputs);
    StepResult<kM> result;
    SetInnovation(nu, S, llt, &result);
    // x+ = x- + K nu,  P+ = P- - K S K^T
    const State x_post = x_ + K * nu;
    StateCov P_post = P_ - K * S * K.transpose();
    Symmetrize(&P_post);
    if (!BeliefFinite(x_post, P_post))
      return FailResult(FilterStatus::kNonFinite, "updated mean or covariance is not finite");
    x_ = x_post;
    P_ = P_post;
    result.gain = K;
    // post-fit residual eps = wrap(z - h(x+))
    result.residual = WrapResidual<kM>(z - Meas::Eval(x_, params_), Meas::kAngleOutputs);
    return result;
  }

  // Number of points of the rule, and the points of the last Predict/Update.
  Eigen::Index num_points() const { return unit_points_.cols(); }
  const StatePoints& unit_points() const { return unit_points_; }
  const Eigen::VectorXd& mean_weights() const { return mean_weights_; }
  const Eigen::VectorXd& cov_weights() const { return cov_weights_; }

 private:
  using Base::error_;
  using Base::Fail;
  using Base::FailResult;
  using Base::P_;
  using Base::x_;

  // points_ = mean + L xi_i with L L^T = cov (+ jitter I when add_jitter).
  bool DrawPoints(const State& mean, const StateCov& cov, const char* what,
                  bool add_jitter = true) {
    StateCov C = cov;
    if (add_jitter) C.diagonal().array() += options_.jitter;
    StateCov L;
    if (!C.allFinite() || !SmallCholesky<kN>(C, &L)) {
      Fail(FilterStatus::kFactorizationFailed,
           std::string("Cholesky of ") + what + " failed (not positive definite)");
      return false;
    }
    if (axis_aligned_) {
      for (Eigen::Index i = 0; i < points_.cols(); ++i) {
        if (axis_index_[i] < 0)
          points_.col(i) = mean;
        else
          points_.col(i).noalias() = mean + axis_scale_(i) * L.col(axis_index_[i]);
      }
    } else {
      for (Eigen::Index i = 0; i < points_.cols(); ++i)
        points_.col(i).noalias() = mean + L * unit_points_.col(i);
    }
    return true;
  }

  Transition<Model>* transition_;
  Params params_;
  SigmaPointOptions options_;
  StatePoints unit_points_;
  bool axis_aligned_ = false;    // every xi_i = axis_scale_(i) e_{axis_index_[i]}
  std::vector<int> axis_index_;  // -1: xi_i = 0
  Eigen::VectorXd axis_scale_;
  Eigen::VectorXd mean_weights_;
  Eigen::VectorXd cov_weights_;
  StatePoints points_;      // X_i (or Y_i after a redraw)
  StatePoints propagated_;  // X-_i = Phi(X_i)
  MeasurementPoints measurement_points_;
  bool have_propagated_ = false;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_SIGMA_POINT_H_
