// Jacobians of a model's continuous dynamics and of its measurement
// functions, for the Kalman-type filters.
//
// Usage:
//   Mat<4, 4> A = ContinuousJacobian<models::CartPole>(x_star, 0.0, params);
//   Vec<double, 4> B = InputJacobian<models::CartPole>(x_star, 0.0, params);
//   Mat<2, 4> H;
//   Vec<double, 2> hx = MeasurementAndJacobian<models::CartPole,
//                                              models::CartPole::XTheta>(x, params, &H);
//
// A = df/dx and H = dh/dx are exact (forward-mode AD with ceres::Jet).
// WARNING: B = df/du is a central difference, because Model::Rhs takes the
// input as a plain double (no Jet can flow through it); see InputJacobian.
// Include only where models are instantiated (this pulls in ceres/jet.h).
#ifndef ESTLAB_FILTERS_LINEARIZE_H_
#define ESTLAB_FILTERS_LINEARIZE_H_

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "models/model_params.h"
#include "src/core/types.h"
#include "src/ode/autodiff.h"
#include "src/ode/nested_jet.h"

namespace estlab {

// f(x, u) of the (time-invariant) model, evaluated at t = 0.
template <class Model>
Vec<double, Model::kStateDim> ContinuousRhs(const Vec<double, Model::kStateDim>& x, double u,
                                            const typename Model::Params& params) {
  return Model::Rhs(0.0, x, u, params);
}

// A = df/dx (x, u), exact by automatic differentiation of Model::Rhs.
template <class Model>
Mat<Model::kStateDim, Model::kStateDim> ContinuousJacobian(const Vec<double, Model::kStateDim>& x,
                                                           double u,
                                                           const typename Model::Params& params) {
  constexpr int N = Model::kStateDim;
  Mat<N, N> A;
  ValueAndJacobian<N, N>(
      [&](const auto& xj) {
        using T = typename std::decay_t<decltype(xj)>::Scalar;
        return Model::Rhs(T(0.0), xj, u, params);
      },
      x, &A);
  return A;
}

// B = df/du (x, u) by the fourth-order central difference of f(u) (any
// vector function of the input, InputDerivative)
//   B = [f(u - 2h) - 8 f(u - h) + 8 f(u + h) - f(u + 2h)] / (12 h),
// h = 1e-3 max(1, |u|): truncation error O(h^4 d^5f/du^5), rounding about
// 2 eps |f| / h. For inputs that enter affinely (forces on mechanical models)
// the truncation error is zero and only the rounding remains.
template <class F>
auto InputDerivative(F&& f, double u) {
  const double h = 1e-3 * std::max(1.0, std::abs(u));
  return decltype(f(u))((f(u - 2.0 * h) - 8.0 * f(u - h) + 8.0 * f(u + h) - f(u + 2.0 * h)) /
                        (12.0 * h));
}
template <class Model>
Vec<double, Model::kStateDim> InputJacobian(const Vec<double, Model::kStateDim>& x, double u,
                                            const typename Model::Params& params) {
  return InputDerivative([&](double v) { return ContinuousRhs<Model>(x, v, params); }, u);
}

// A discrete-time model's map over dt linearised at (x*, u*):
//   Step(x, u) ~= Step(x*, u*) + F (x - x*) + G (u - u*),
// F = dStep/dx exact (AD), G = dStep/du by InputDerivative's central
// difference. Returns Step(x*, u*).
template <class Model>
Vec<double, Model::kStateDim> StepMapJacobians(const Vec<double, Model::kStateDim>& x, double u,
                                               double dt, const typename Model::Params& params,
                                               Mat<Model::kStateDim, Model::kStateDim>* F,
                                               Vec<double, Model::kStateDim>* G) {
  constexpr int N = Model::kStateDim;
  *G = InputDerivative(
      [&](double v) { return Model::template Step<double>(0.0, x, dt, v, params); }, u);
  return ValueAndJacobian<N, N>(
      [&](const auto& xj) {
        using T = typename std::decay_t<decltype(xj)>::Scalar;
        return Model::template Step<T>(T(0.0), xj, dt, u, params);
      },
      x, F);
}

// h(x), and H = dh/dx (x) by automatic differentiation when H is not null,
// for x of any scalar T (double; ceres::Jet, whose H is then a nested Jet:
// src/ode/nested_jet.h).
// Prm: Params, or ParamsT<T> when parameters are estimated (lifted to the
// nested Jet inside the Jacobian).
template <class Model, class Meas, class T = double, class Prm = typename Model::Params>
Vec<T, Meas::kDim> MeasurementAndJacobian(
    const Vec<T, Model::kStateDim>& x, const Prm& params,
    std::type_identity_t<MatT<T, Meas::kDim, Model::kStateDim>>* H) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  if (H == nullptr) return Meas::template Eval<T>(x, params);
  return ValueAndJacobianT<M, N>(
      [&](const auto& xj) {
        using S = typename std::decay_t<decltype(xj)>::Scalar;
        return Meas::template Eval<S>(xj, ParamsAs<Model, S>(params));
      },
      x, H);
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_LINEARIZE_H_
