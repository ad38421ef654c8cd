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
//   if (!rts.Smooth(&why, LagOne::kCompute)) ...;
//   rts.mean(k), rts.cov(k), rts.lag_one_cov(k)
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

// Whether Smooth computes the lag-one cross-covariances (EM needs them; the
// smoothed means and covariances do not).
enum class LagOne { kSkip, kCompute };

template <int N>
class RtsSmoother {
 public:
  using State = Vec<double, N>;
  using StateCov = Mat<N, N>;

  void Clear() {
    steps_.clear();
    lag_one_.clear();
  }
  void Reserve(size_t steps) { steps_.reserve(steps); }
  // Step k's filtered belief; the first call is step 0. After the prediction
  // to step k (AddPredicted), the next AddFiltered is step k.
  void AddFiltered(const State& x, const StateCov& P) {
    if (steps_.empty() || steps_.back().has_filtered) steps_.emplace_back();
    Step& s = steps_.back();
    s.x = x;
    s.P = P;
    s.has_filtered = true;
  }
  // Replaces the newest filtered belief (a second measurement at the same
  // time: no prediction between the two updates).
  void ReplaceFiltered(const State& x, const StateCov& P) {
    steps_.back().x = x;
    steps_.back().P = P;
  }
  // The prediction from the newest filtered step to the next, with its
  // cross-covariance C.
  void AddPredicted(const State& x_pred, const StateCov& P_pred, const StateCov& C) {
    steps_.emplace_back();
    Step& s = steps_.back();
    s.x_pred = x_pred;
    s.P_pred = P_pred;
    s.C = C;
    s.has_predicted = true;
  }
  // Forgets a prediction whose filtered belief never came (the forward pass
  // stopped in its update), so that Smooth works on the steps before.
  void DropUnfinishedStep() {
    if (!steps_.empty() && !steps_.back().has_filtered) steps_.pop_back();
  }
  // The number of filtered steps recorded (= size() after Smooth).
  size_t filtered_steps() const { return steps_.size(); }

  // The backward pass, in place. False, with the step in *why, when a
  // P-_{k+1} is not positive definite or the result is not finite, or the
  // recording is inconsistent (a prediction without its filtered belief).
  bool Smooth(std::string* why, LagOne lag_one = LagOne::kSkip) {
    const size_t K = steps_.size();
    if (K == 0 || !steps_.back().has_filtered) {
      *why = K == 0 ? "RTS smoother: no filtered step recorded"
                    : "RTS smoother: the last prediction has no filtered belief";
      return false;
    }
    lag_one_.assign(lag_one == LagOne::kCompute ? K - 1 : 0, StateCov::Zero());
    for (size_t k = K - 1; k-- > 0;) {
      Step& s = steps_[k];
      const Step& next = steps_[k + 1];  // smoothed already; holds the prediction to k + 1
      if (!next.has_predicted) {
        *why = "RTS smoother: step " + std::to_string(k + 1) + " has no prediction from step " +
               std::to_string(k);
        return false;
      }
      // G_k = C_{k+1} (P-_{k+1})^-1, i.e. G^T = (P-)^-1 C^T
      const Eigen::LLT<StateCov> llt(next.P_pred);
      if (llt.info() != Eigen::Success) {
        *why = "RTS smoother: the predicted covariance of step " + std::to_string(k + 1) +
               " is not positive definite";
        return false;
      }
      // Row by row: Eigen's triangular solve with a matrix right-hand side
      // takes its general blocked path, twice as slow at n = 2 as n vector solves.
      StateCov G;
      for (int i = 0; i < N; ++i) G.row(i) = llt.solve(next.C.row(i).transpose()).transpose();
      s.x.noalias() += G * (next.x - next.x_pred);
      const StateCov GD = G * (next.P - next.P_pred);
      s.P.noalias() += GD * G.transpose();
      Symmetrize<N>(&s.P);
      if (!lag_one_.empty()) lag_one_[k] = G * next.P;
      if (!BeliefFinite<N>(s.x, s.P)) {
        *why = "RTS smoother: the smoothed mean or covariance of step " + std::to_string(k) +
               " is not finite";
        return false;
      }
    }
    return true;
  }

  size_t size() const { return steps_.size(); }
  // After Smooth: the smoothed mean and covariance of step k.
  const State& mean(size_t k) const { return steps_[k].x; }
  const StateCov& cov(size_t k) const { return steps_[k].P; }
  // Cov(x_k, x_{k+1} | all data), k < size() - 1; Smooth(.., LagOne::kCompute) only.
  const StateCov& lag_one_cov(size_t k) const { return lag_one_[k]; }

 private:
  // Step k: its filtered (then smoothed) belief, and the prediction from
  // step k - 1 to it (unused for k = 0).
  // (Left uninitialised: each member is written before it is read, and
  // zeroing five matrices per step is a measurable part of the KF's cost.)
  struct Step {
    State x, x_pred;
    StateCov P, P_pred, C;
    bool has_filtered = false, has_predicted = false;
  };
  std::vector<Step> steps_;
  std::vector<StateCov> lag_one_;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_RTS_SMOOTHER_H_
