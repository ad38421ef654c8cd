// The Rauch-Tung-Striebel smoother, written once for every Gaussian filter:
// the KF (exact RTS), the EKF (extended RTS) and the sigma-point filters
// (unscented, cubature, Gauss-Hermite RTS in Saerkkae's form). They differ
// only in the cross-covariance C_{k+1} = Cov(x_k, x_{k+1} | z_{1:k}) of each
// prediction, which each filter hands over (Filter::PredictCrossCov: P Phi^T,
// P F^T, or the weighted cross-covariance of the sigma points and their
// propagated images). The forward pass's moments are recorded here; no model
// is evaluated in the backward pass.
//
// Backward pass, k = K-1, ..., 0 (the RTS recursion and its Gaussian /
// sigma-point generalisation in Saerkkae & Svensson, Bayesian Filtering and
// Smoothing, 2nd ed., 2023):
//   G_k     = C_{k+1} (P-_{k+1})^-1                  (Cholesky solve)
//   x^s_k   = x_k + G_k (x^s_{k+1} - x-_{k+1})
//   P^s_k   = P_k + G_k (P^s_{k+1} - P-_{k+1}) G_k^T   (symmetrised)
//   Cov(x_k, x_{k+1} | z_{1:K}) = G_k P^s_{k+1}        (lag-one, for EM)
// with (x_k, P_k) the filtered belief at step k (after its update, or the
// prediction when step k had no measurement) and (x-_{k+1}, P-_{k+1}) the
// prediction to step k + 1. x^s_K = x_K.
//
// Usage:
//   RtsSmoother<2> rts;
//   rts.AddFiltered(filter.mean(), filter.cov());             // step 0
//   for k = 1..K:
//     filter.Predict(...); filter.PredictCrossCov(&C);
//     rts.AddPredicted(filter.mean(), filter.cov(), C);
//     filter.Update(...);                                     // if z_k
//     rts.AddFiltered(filter.mean(), filter.cov());
//   if (!rts.Smooth(&why)) ...;   rts.mean(k), rts.cov(k), rts.lag_one_cov(k)
//
// WARNING: differences of angle states are not wrapped (the filters do not
// wrap their state either); a smoothed angle that crosses +-pi between steps
// is smoothed on the unwrapped line, which is what the forward filter used.
#ifndef ESTLAB_FILTERS_RTS_SMOOTHER_H_
#define ESTLAB_FILTERS_RTS_SMOOTHER_H_

#include <Eigen/Cholesky>
#include <string>
#include <vector>

#include "src/core/types.h"
#include "src/filters/filter_util.h"

namespace estlab {

template <int N>
class RtsSmoother {
 public:
  using State = Vec<double, N>;
  using StateCov = Mat<N, N>;

  void Clear() {
    filtered_x_.clear();
    filtered_P_.clear();
    predicted_x_.clear();
    predicted_P_.clear();
    cross_.clear();
  }
  // Step k's filtered belief; the first call is step 0.
  void AddFiltered(const State& x, const StateCov& P) {
    filtered_x_.push_back(x);
    filtered_P_.push_back(P);
  }
  // The prediction to the next step, with its cross-covariance C.
  void AddPredicted(const State& x_pred, const StateCov& P_pred, const StateCov& C) {
    predicted_x_.push_back(x_pred);
    predicted_P_.push_back(P_pred);
    cross_.push_back(C);
  }

  // The backward pass. False, with the step in *why, when a P-_{k+1} is not
  // positive definite or the result is not finite, or the recording is
  // inconsistent (one prediction between consecutive filtered steps).
  bool Smooth(std::string* why) {
    const size_t K = filtered_x_.size();
    if (K == 0 || predicted_x_.size() + 1 != K) {
      *why = "RTS smoother: " + std::to_string(K) + " filtered steps need " +
             std::to_string(K == 0 ? 0 : K - 1) + " predictions, got " +
             std::to_string(predicted_x_.size());
      return false;
    }
    smoothed_x_ = filtered_x_;
    smoothed_P_ = filtered_P_;
    lag_one_.assign(K - 1, StateCov::Zero());
    for (size_t k = K - 1; k-- > 0;) {
      // G_k = C_{k+1} (P-_{k+1})^-1, i.e. G^T = (P-)^-1 C^T
      const Eigen::LLT<StateCov> llt(predicted_P_[k]);
      if (llt.info() != Eigen::Success) {
        *why = "RTS smoother: the predicted covariance of step " + std::to_string(k + 1) +
               " is not positive definite";
        return false;
      }
      const StateCov G = llt.solve(cross_[k].transpose()).transpose();
      smoothed_x_[k] = filtered_x_[k] + G * (smoothed_x_[k + 1] - predicted_x_[k]);
      smoothed_P_[k] = filtered_P_[k] + G * (smoothed_P_[k + 1] - predicted_P_[k]) * G.transpose();
      Symmetrize<N>(&smoothed_P_[k]);
      lag_one_[k] = G * smoothed_P_[k + 1];
      if (!BeliefFinite<N>(smoothed_x_[k], smoothed_P_[k])) {
        *why = "RTS smoother: the smoothed mean or covariance of step " + std::to_string(k) +
               " is not finite";
        return false;
      }
    }
    return true;
  }

  size_t size() const { return smoothed_x_.size(); }
  const State& mean(size_t k) const { return smoothed_x_[k]; }
  const StateCov& cov(size_t k) const { return smoothed_P_[k]; }
  // Cov(x_k, x_{k+1} | all data), k < size() - 1.
  const StateCov& lag_one_cov(size_t k) const { return lag_one_[k]; }

 private:
  std::vector<State> filtered_x_, predicted_x_, smoothed_x_;
  std::vector<StateCov> filtered_P_, predicted_P_, cross_, smoothed_P_, lag_one_;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_RTS_SMOOTHER_H_
