// The extended Kalman filter's equations, written once for any scalar T:
// the Ekf class (src/filters/ekf.h) runs them in double, the tuner's
// likelihood (adaptive/likelihood.h) with ceres::Jet to differentiate the
// innovation likelihood in the noise parameters.
//
// Predict (x- = Phi(x) and F = dPhi/dx come from the caller's transition):
//   P- = F P F^T + Q                                   (symmetrised)
// Update (i = 0 .. iterations-1, x_0 = x-, Bell & Cathey 1993):
//   H_i = dh/dx(x_i),  S_i = H_i P- H_i^T + R,  K_i = P- H_i^T S_i^-1
//   x_{i+1} = x- + K_i (wrap(z - h(x_i)) - H_i wrap(x- - x_i))
//   x+ = x_iterations,  P+ = (I - K H) P- (I - K H)^T + K R K^T  (last K, H)
// Components of z that are missing (NaN) take no part: the rows of H and nu,
// R's block of the observed ones (missing.h). With iterations = 1 this is
// the EKF. The innovation nu = wrap(z - h(x-)) and
// S are those at the prior (i = 0), so the likelihood is the EKF's whatever
// the number of iterations.
//
// Usage:
//   GaussianUpdate<double, 2, 1> u;
//   std::string why;
//   P_pred = EkfPredictCovariance<2>(F, P, Q);
//   if (EkfUpdate<Model, Meas>(x_pred, P_pred, z, R, t, u, params, 1, &u, &why) != ...) ...
#ifndef ESTLAB_FILTERS_EKF_STEP_H_
#define ESTLAB_FILTERS_EKF_STEP_H_

#include <string>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/linearize.h"

namespace estlab {

// P- = F P F^T + Q, symmetrised.
template <int N, class T = double>
MatT<T, N, N> EkfPredictCovariance(const MatT<T, N, N>& F, const MatT<T, N, N>& P,
                                   const MatT<T, N, N>& Q) {
  MatT<T, N, N> P_pred = F * P * F.transpose() + Q;
  Symmetrize<N, T>(&P_pred);
  return P_pred;
}

// The (iterated) EKF update of (x-, P-) with measurement z, noise R, at the
// measurement's time t with the input u there (seen by measurements
// h(t, x, u)).
// Returns kOk, or a failure status with the reason in *why (set only then).
template <class Model, class Meas, class T = double, class Prm = typename Model::Params>
FilterStatus EkfUpdate(const Vec<T, Model::kStateDim>& x_prior,
                       const MatT<T, Model::kStateDim, Model::kStateDim>& P,
                       const Vec<double, Meas::kDim>& z, const MatT<T, Meas::kDim, Meas::kDim>& R,
                       double t, const InputOf<Model>& u, const Prm& params, int iterations,
                       GaussianUpdate<T, Model::kStateDim, Meas::kDim>* out, std::string* why) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const Vec<T, M> zt = z.template cast<T>();
  // the observed components only (missing.h)
  const MissingMask<M> missing(z);
  MatT<T, M, M> masked;
  const MatT<T, M, M>& Ru = missing.Noise(R, &masked);
  MatT<T, M, N> H;
  // i = 0:  nu = wrap(z - h(x-)),  S = H P- H^T + R,  K = P- H^T S^-1
  out->nu = WrapResidual<M, T>(
      zt - MeasurementAndJacobian<Model, Meas, T>(t, x_prior, u, params, &H), Meas::kAngleOutputs);
  if (missing.Any()) missing.MaskRows(&H), missing.MaskRows(&out->nu);
  if (!KalmanGain<N, M, T>(H, P, Ru, missing, &out->S, &out->L, &out->K)) {
    *why = "Cholesky of the innovation covariance S = H P H^T + R failed";
    return FilterStatus::kFactorizationFailed;
  }
  Vec<T, N> x_iter = x_prior + out->K * out->nu;  // x_1 = x- + K_0 nu
  MatT<T, M, M> S_i, L_i;
  for (int i = 1; i < iterations; ++i) {
    // x_{i+1} = x- + K_i (wrap(z - h(x_i)) - H_i wrap(x- - x_i))
    Vec<T, M> r = WrapResidual<M, T>(
        zt - MeasurementAndJacobian<Model, Meas, T>(t, x_iter, u, params, &H), Meas::kAngleOutputs);
    if (missing.Any()) missing.MaskRows(&H), missing.MaskRows(&r);
    if (!KalmanGain<N, M, T>(H, P, Ru, missing, &S_i, &L_i, &out->K)) {
      *why = "Cholesky of S = H P H^T + R failed in IEKF iteration " + std::to_string(i);
      return FilterStatus::kFactorizationFailed;
    }
    x_iter = x_prior + out->K * (r - H * WrapResidual<N, T>(x_prior - x_iter, Model::kAngleStates));
  }
  // P+ = (I - K H) P- (I - K H)^T + K R K^T with the last K, H
  out->P = JosephUpdate<N, M, T>(P, out->K, H, Ru, missing);
  out->x = x_iter;
  if (!BeliefFinite<N, T>(out->x, out->P)) {
    *why = "updated mean or covariance is not finite";
    return FilterStatus::kNonFinite;
  }
  return FilterStatus::kOk;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_EKF_STEP_H_
