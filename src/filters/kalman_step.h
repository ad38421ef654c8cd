// The linearised Kalman filter's equations, written once for any scalar T:
// LinearizedKf (kalman.h) runs them in double, the tuner's likelihood
// (adaptive/likelihood.h) with ceres::Jet. The linearisation (x*, u*, h(x*),
// H, D) and the discretisation (Phi, Gamma, d) are plain doubles: they do not
// depend on the noise. U: the number of input columns (kInputCols, one for
// a model without input, whose u - u* is then 0).
//
// Predict (delta = wrap(x - x*), angle states wrapped; u0, u1 the inputs at
// the step's ends, u1 = u0 under zero-order hold):
//   x- = x* + Phi delta + Gamma (u0 - u*) + Gamma1 (u1 - u0) + d,
//   P- = Phi P Phi^T + Q
// Update (h*, H, D at the update's time t_k for a measurement h(t, x, u),
// KfLinearizeMeasurement; once, at x*, for the others):
//   z^ = h(x*, u*) + H wrap(x- - x*) + D (u - u*),  nu = wrap(z - z^)
//   S = H P- H^T + R,  K = P- H^T S^-1
//   x+ = x- + K nu,  P+ = (I - K H) P- (I - K H)^T + K R K^T   (Joseph form)
// with the observed components of z only (rows of H and nu, R's block;
// missing.h) when some are missing (NaN).
#ifndef ESTLAB_FILTERS_KALMAN_STEP_H_
#define ESTLAB_FILTERS_KALMAN_STEP_H_

#include <string>

#include "src/filters/filter.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/linearize.h"

namespace estlab {

// The model linearised about (x*, u*): what the KF steps need.
template <int N, int M, int U = 1>
struct KfLinearization {
  Vec<double, N> x_star = Vec<double, N>::Zero();
  Vec<double, U> u_star = Vec<double, U>::Zero();
  Vec<double, M> h_star = Vec<double, M>::Zero();  // h(x*, u*)
  Mat<M, N> H = Mat<M, N>::Zero();                 // dh/dx at (x*, u*)
  Mat<M, U> D = Mat<M, U>::Zero();                 // dh/du at (x*, u*)
};
// Its exact discretisation over one step length. gamma1: the response to
// an input ramping from 0 to 1 over the step (linear hold), with_ramp when
// it was computed (else zero: only zero-order-hold steps may use it).
template <int N, int U = 1>
struct KfDiscretization {
  Mat<N, N> phi = Mat<N, N>::Identity();
  Mat<N, U> gamma = Mat<N, U>::Zero();
  Mat<N, U> gamma1 = Mat<N, U>::Zero();
  Vec<double, N> drift = Vec<double, N>::Zero();
  bool with_ramp = false;
};

// The input as a column of kInputCols<Model> values (a zero for a model
// without input).
template <class Model>
Vec<double, kInputCols<Model>> InputColumn(const InputOf<Model>& u) {
  Vec<double, kInputCols<Model>> v;
  for (int i = 0; i < kInputCols<Model>; ++i) v(i) = InputComponent<Model>(u, i);
  return v;
}

// h* = h(t, x*, u*), H = dh/dx and D = dh/du there: the measurement's part
// of the linearisation, at time t (which only a measurement h(t, x, u) sees).
template <class Model, class Meas>
void KfLinearizeMeasurement(double t, const typename Model::Params& params,
                            KfLinearization<Model::kStateDim, Meas::kDim, kInputCols<Model>>* lin) {
  const InputOf<Model> u_star = InputFrom<Model>(lin->u_star.data());
  lin->h_star = MeasurementAndJacobian<Model, Meas>(t, lin->x_star, u_star, params, &lin->H);
  lin->D = MeasurementInputJacobian<Model, Meas>(t, lin->x_star, u_star, params);
}

template <class Model, int M, class T = double>
void KfPredict(const KfLinearization<Model::kStateDim, M, kInputCols<Model>>& lin,
               const KfDiscretization<Model::kStateDim, kInputCols<Model>>& step,
               const InputOf<Model>& u0, const InputOf<Model>& u1,
               const MatT<T, Model::kStateDim, Model::kStateDim>& Q, Vec<T, Model::kStateDim>* x,
               MatT<T, Model::kStateDim, Model::kStateDim>* P) {
  constexpr int N = Model::kStateDim;
  // delta = wrap(x - x*);  x- = x* + Phi delta + Gamma (u0 - u*) + Gamma1 (u1 - u0) + d
  const Vec<T, N> x_star = lin.x_star.template cast<T>();
  const Vec<T, N> delta = WrapResidual<N, T>(*x - x_star, Model::kAngleStates);
  const Vec<double, kInputCols<Model>> c0 = InputColumn<Model>(u0);
  Vec<double, N> forced = step.gamma * (c0 - lin.u_star);
  if (step.with_ramp) forced += step.gamma1 * (InputColumn<Model>(u1) - c0);
  *x = x_star + step.phi.template cast<T>() * delta + forced.template cast<T>() +
       step.drift.template cast<T>();
  // P- = Phi P Phi^T + Q
  MatT<T, N, N> P_pred =
      step.phi.template cast<T>() * (*P) * step.phi.transpose().template cast<T>() + Q;
  Symmetrize<N, T>(&P_pred);
  *P = P_pred;
}

template <class Model, class Meas, class T = double>
FilterStatus KfUpdate(const KfLinearization<Model::kStateDim, Meas::kDim, kInputCols<Model>>& lin,
                      const InputOf<Model>& u, const Vec<T, Model::kStateDim>& x,
                      const MatT<T, Model::kStateDim, Model::kStateDim>& P,
                      const Vec<double, Meas::kDim>& z, const MatT<T, Meas::kDim, Meas::kDim>& R,
                      GaussianUpdate<T, Model::kStateDim, Meas::kDim>* out, std::string* why) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  MatT<T, M, N> H = lin.H.template cast<T>();
  // z^ = h(x*, u*) + H wrap(x- - x*) + D (u - u*),  nu = wrap(z - z^)
  const Vec<T, N> delta =
      WrapResidual<N, T>(x - lin.x_star.template cast<T>(), Model::kAngleStates);
  const Vec<double, M> fed = lin.h_star + lin.D * (InputColumn<Model>(u) - lin.u_star);
  const Vec<T, M> z_pred = fed.template cast<T>() + H * delta;
  out->nu = WrapResidual<M, T>(z.template cast<T>() - z_pred, Meas::kAngleOutputs);
  // the observed components only (missing.h)
  const MissingMask<M> missing(z);
  MatT<T, M, M> masked;
  const MatT<T, M, M>& Ru = missing.Noise(R, &masked);
  if (missing.Any()) missing.MaskRows(&H), missing.MaskRows(&out->nu);
  // S = H P H^T + R,  K = P H^T S^-1
  if (!KalmanGain<N, M, T>(H, P, Ru, missing, &out->S, &out->L, &out->K)) {
    *why = "Cholesky of the innovation covariance S = H P H^T + R failed";
    return FilterStatus::kFactorizationFailed;
  }
  // x+ = x- + K nu;  P+ = (I - K H) P (I - K H)^T + K R K^T
  out->x = x + out->K * out->nu;
  out->P = JosephUpdate<N, M, T>(P, out->K, H, Ru, missing);
  if (!BeliefFinite<N, T>(out->x, out->P)) {
    *why = "updated mean or covariance is not finite";
    return FilterStatus::kNonFinite;
  }
  return FilterStatus::kOk;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_KALMAN_STEP_H_
