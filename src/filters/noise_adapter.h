// Online adaptation of the process- and measurement-noise covariances Q and R
// from each filter step (the "adaptive UKF" = SigmaPointFilter + this).
//
// Usage (the runner does this every update whose z is complete; an update
// with missing components, r.observed < M, adapts nothing: the rules below
// need every component's innovation):
//   NoiseAdapter<N, M> adapter(spec.adapt);
//   P_pred = filter.cov() after Predict;  r = filter.Update(z, R);
//   adapter.Observe(r, P_pred, filter.cov(), &Q, &R);
//
// Rules
//   sage-husa (Sage & Husa 1969, with the fading-memory weight of Deng et al.):
//     d_k = (1 - b) / (1 - b^(k+1))
//     R_k = (1 - d_k) R_{k-1} + d_k (nu nu^T - (S - R_{k-1}))        [S - R = H P- H^T]
//     Q_k = (1 - d_k) Q_{k-1} + d_k (K nu nu^T K^T + P+ - (P- - Q_{k-1}))
//   innovation-matching over a window of N steps
//     (Mohamed & Schwarz 1999; Akhlaghi, Zhou & Huang 2017):
//     C_nu = mean of nu nu^T over the window           Q_k = K C_nu K^T
//     C_eps = mean of eps eps^T (post-fit residuals)   R_k = C_eps + H P+ H^T,
//     with H P+ H^T = (S - R) - (S - R) S^-1 (S - R) (needs no Jacobian).
// The result is symmetrised and its eigenvalues clipped to `eigen_floor`
// so Q and R stay positive definite; clip_count() says how often that bit.
#ifndef ESTLAB_FILTERS_NOISE_ADAPTER_H_
#define ESTLAB_FILTERS_NOISE_ADAPTER_H_

#include <cmath>
#include <deque>
#include <string>

#include "src/core/types.h"
#include "src/filters/filter.h"
#include "src/filters/filter_options.h"
#include "src/filters/symmetric_eigen.h"

namespace estlab {

// Symmetrises A and raises its eigenvalues to at least `floor`; returns true
// when any eigenvalue had to be raised.
template <int D>
bool ClipToPositiveDefinite(Mat<D, D>* A, double floor) {
  Mat<D, D> sym = 0.5 * (*A + A->transpose());
  Vec<double, D> values;
  Mat<D, D> vectors;
  SymmetricEigen<D>(sym, &values, &vectors);
  bool clipped = false;
  for (int i = 0; i < D; ++i) {
    if (!(values(i) >= floor)) {
      values(i) = floor;
      clipped = true;
    }
  }
  if (clipped) sym = vectors * values.asDiagonal() * vectors.transpose();
  *A = 0.5 * (sym + sym.transpose());
  return clipped;
}

template <int N, int M>
class NoiseAdapter {
 public:
  explicit NoiseAdapter(const AdaptSpec& spec) : spec_(spec) {
    if (spec.rule != "sage-husa" && spec.rule != "innovation-matching") {
      throw InputError("unknown adaptation rule '" + spec.rule +
                       "' (expected sage-husa or innovation-matching)");
    }
    if (!(spec.forgetting > 0 && spec.forgetting < 1))
      throw InputError("--forgetting must be in (0, 1), got " + std::to_string(spec.forgetting));
    if (spec.window < 1) throw InputError("--window must be >= 1");
  }

  // r: the update's result (innovation nu, S, gain K, post-fit residual eps);
  // p_pred: P- (including the Q used); p_post: P+. Adapts *Q and/or *R in place.
  void Observe(const StepResult<M>& r, const Mat<N, N>& p_pred, const Mat<N, N>& p_post,
               Mat<N, N>* Q, Mat<M, M>* R) {
    if (r.status != FilterStatus::kOk || r.gain.rows() != N || r.gain.cols() != M) return;
    const Mat<N, M> K = r.gain;
    const Vec<double, M>& nu = r.innovation;
    const Mat<M, M> hph = r.innovation_cov - *R;  // H P- H^T
    if (spec_.rule == "sage-husa") {
      const double b = spec_.forgetting;
      const double d = (1.0 - b) / (1.0 - bk_ * b);  // bk_ = b^k, k = steps seen
      bk_ *= b;
      if (spec_.adapt_r) {
        Mat<M, M> r_new = (1.0 - d) * *R + d * (nu * nu.transpose() - hph);
        clips_ += ClipToPositiveDefinite<M>(&r_new, spec_.eigen_floor);
        *R = r_new;
      }
      if (spec_.adapt_q) {
        Mat<N, N> q_new =
            (1.0 - d) * *Q + d * (K * nu * nu.transpose() * K.transpose() + p_post - (p_pred - *Q));
        clips_ += ClipToPositiveDefinite<N>(&q_new, spec_.eigen_floor);
        *Q = q_new;
      }
      return;
    }
    // Innovation / residual covariance matching over the last `window` steps.
    nu_outer_.push_back(nu * nu.transpose());
    eps_outer_.push_back(r.residual * r.residual.transpose());
    if (int(nu_outer_.size()) > spec_.window) {
      nu_outer_.pop_front();
      eps_outer_.pop_front();
    }
    if (int(nu_outer_.size()) < spec_.window) return;  // wait for a full window
    Mat<M, M> c_nu = Mat<M, M>::Zero(), c_eps = Mat<M, M>::Zero();
    for (const auto& c : nu_outer_) c_nu += c;
    for (const auto& c : eps_outer_) c_eps += c;
    c_nu /= double(nu_outer_.size());
    c_eps /= double(eps_outer_.size());
    if (spec_.adapt_r) {
      const Eigen::LLT<Mat<M, M>> s_llt(r.innovation_cov);
      if (s_llt.info() == Eigen::Success) {
        const Mat<M, M> hpph = hph - hph * s_llt.solve(hph);  // H P+ H^T
        Mat<M, M> r_new = c_eps + hpph;
        clips_ += ClipToPositiveDefinite<M>(&r_new, spec_.eigen_floor);
        *R = r_new;
      }
    }
    if (spec_.adapt_q) {
      Mat<N, N> q_new = K * c_nu * K.transpose();
      clips_ += ClipToPositiveDefinite<N>(&q_new, spec_.eigen_floor);
      *Q = q_new;
    }
  }

  long clip_count() const { return clips_; }

 private:
  AdaptSpec spec_;
  double bk_ = 1.0;  // b^k
  long clips_ = 0;
  std::deque<Mat<M, M>> nu_outer_, eps_outer_;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_NOISE_ADAPTER_H_
