// The sigma-point filters' equations (unscented, cubature, Gauss-Hermite:
// the rule is a SigmaPointSet, sigma_rules.h), written once for any scalar T:
// SigmaPointFilter (sigma_point.h) runs them in double, the tuner's
// likelihood (adaptive/likelihood.h) with ceres::Jet.
//
// Draw (L points xi_i, weights Wm_i, Wc_i of the rule):
//   C + jitter I = L L^T (Cholesky),   X_i = m + L xi_i
// Predict moments of the propagated points X-_i = Phi(X_i):
//   x- = X-_0 + sum_{i >= 1} Wm_i (X-_i - X-_0)
//   P- = sum_i Wc_i (X-_i - x-)(X-_i - x-)^T + Q + jitter I     (symmetrised)
// Update with points Y_i (the propagated ones, or redrawn from (x-, P-)):
//   Z_i = h(Y_i),  z^ = Z_0 + sum_{i >= 1} Wm_i (Z_i - Z_0)
//   S = sum_i Wc_i dZ_i dZ_i^T + R + jitter I,   C = sum_i Wc_i dY_i dZ_i^T
//   K = C S^-1 (Cholesky solve),   nu = wrap(z - z^)
//   x+ = x- + K nu,   P+ = P- - K S K^T (symmetrised)
//   with the observed components of z only when some are missing (NaN):
//   S's block, C's columns and nu's rows of those (missing.h)
// No difference inside a point set is wrapped (filter_util.h, WeightedMean):
// only the innovation of angle outputs is.
//
// Usage:
//   const SigmaPointSet set = MakeSigmaPointSet(2, options);
//   Eigen::Matrix<double, 2, Eigen::Dynamic> X(2, set.unit_points.cols()), Xp = X;
//   DrawSigmaPoints<2>(set, x, P, /*add_jitter=*/true, &X);
//   ... Xp = Phi(X) ...
//   SigmaPredictMoments<2>(set, Xp, Q, &x_pred, &P_pred);
//   SigmaUpdate<Model, Meas>(set, Y, &Z, x_pred, P_pred, z, R, t, u, params, &out, &why);
#ifndef ESTLAB_FILTERS_SIGMA_POINT_STEP_H_
#define ESTLAB_FILTERS_SIGMA_POINT_STEP_H_

#include <string>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/sigma_rules.h"

namespace estlab {

template <class T, int D>
using PointsT = Eigen::Matrix<T, D, Eigen::Dynamic>;

// X_i = mean + L xi_i with L L^T = cov (+ jitter I when add_jitter), into the
// preallocated *points. False when the Cholesky fails (not positive
// definite, or not finite).
template <int N, class T = double>
bool DrawSigmaPoints(const SigmaPointSet& set, const Vec<T, N>& mean, const MatT<T, N, N>& cov,
                     bool add_jitter, PointsT<T, N>* points) {
  MatT<T, N, N> C = cov;
  if (add_jitter) C.diagonal().array() += T(set.jitter);
  MatT<T, N, N> L;
  if (!AllFiniteT(C) || !SmallCholesky<N, T>(C, &L)) return false;
  const Eigen::Index count = set.unit_points.cols();
  if (set.axis_aligned) {
    for (Eigen::Index i = 0; i < count; ++i) {
      if (set.axis_index[i] < 0)
        points->col(i) = mean;
      else
        points->col(i).noalias() = mean + set.axis_scale(i) * L.col(set.axis_index[i]);
    }
  } else {
    for (Eigen::Index i = 0; i < count; ++i)
      points->col(i).noalias() = mean + L * set.unit_points.col(i).template cast<T>();
  }
  return true;
}

// x-, P- from the propagated points.
template <int N, class T = double>
void SigmaPredictMoments(const SigmaPointSet& set, const PointsT<T, N>& propagated,
                         const MatT<T, N, N>& Q, Vec<T, N>* x_pred, MatT<T, N, N>* P_pred) {
  *x_pred = WeightedMean<N>(propagated, set.mean_weights);
  *P_pred = WeightedCov<N>(propagated, *x_pred, set.cov_weights);
  *P_pred += Q;
  P_pred->diagonal().array() += T(set.jitter);
  Symmetrize<N, T>(P_pred);
}

// The update of (x-, P-) with points Y; *Z is a preallocated workspace
// (M x count). Returns kOk, or a failure status with the reason in *why.
template <class Model, class Meas, class T = double, class Prm = typename Model::Params>
FilterStatus SigmaUpdate(const SigmaPointSet& set, const PointsT<T, Model::kStateDim>& Y,
                         PointsT<T, Meas::kDim>* Z, const Vec<T, Model::kStateDim>& x_prior,
                         const MatT<T, Model::kStateDim, Model::kStateDim>& P,
                         const Vec<double, Meas::kDim>& z, const MatT<T, Meas::kDim, Meas::kDim>& R,
                         double t, const InputOf<Model>& u, const Prm& params,
                         GaussianUpdate<T, Model::kStateDim, Meas::kDim>* out, std::string* why) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  // Z_i = h(t, Y_i, u),  z^ = Z_0 + sum_i Wm_i (Z_i - Z_0)
  for (Eigen::Index i = 0; i < Y.cols(); ++i)
    Z->col(i) = EvalMeasurement<Model, Meas, T>(t, Vec<T, N>(Y.col(i)), u, params);
  const Vec<T, M> z_pred = WeightedMean<M>(*Z, set.mean_weights);
  // S = sum_i Wc_i dZ_i dZ_i^T + R + jitter I,  C = sum_i Wc_i dY_i dZ_i^T
  out->S = WeightedCov<M>(*Z, z_pred, set.cov_weights);
  out->S += R;
  out->S.diagonal().array() += T(set.jitter);
  Symmetrize<M, T>(&out->S);
  MatT<T, N, M> C = WeightedCrossCov<N, M>(Y, x_prior, *Z, z_pred, set.cov_weights);
  // the observed components only: rows and columns of S, columns of C
  // (missing.h)
  const MissingMask<M> missing(z);
  if (missing.Any()) missing.MaskCov(&out->S), missing.MaskCols(&C);
  if (!InnovationCholesky<M, T>(out->S, &out->L)) {
    *why = "Cholesky of the innovation covariance S failed";
    return FilterStatus::kFactorizationFailed;
  }
  // K = C S^-1, i.e. K^T = S^-1 C^T;  nu = wrap(z - z^)
  out->K = CholeskySolve<M, N, T>(out->L, C.transpose()).transpose();
  out->nu = WrapResidual<M, T>(z.template cast<T>() - z_pred, Meas::kAngleOutputs);
  if (missing.Any()) missing.MaskRows(&out->nu);
  // x+ = x- + K nu,  P+ = P- - K S K^T
  out->x = x_prior + out->K * out->nu;
  out->P = P - out->K * out->S * out->K.transpose();
  Symmetrize<N, T>(&out->P);
  if (!BeliefFinite<N, T>(out->x, out->P)) {
    *why = "updated mean or covariance is not finite";
    return FilterStatus::kNonFinite;
  }
  return FilterStatus::kOk;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_SIGMA_POINT_STEP_H_
