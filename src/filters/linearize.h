// Jacobians of a model's continuous dynamics and of its measurement
// functions, for the Kalman-type filters.
//
// Usage:
//   Mat<4, 4> A = ContinuousJacobian<models::CartPole>(x_star, 0.0, params);
//   Mat<4, 1> B = InputJacobian<models::CartPole>(x_star, 0.0, params);
//   Mat<2, 4> H;
//   Vec<double, 2> hx = MeasurementAndJacobian<models::CartPole,
//                                              models::CartPole::XTheta>(t, x, u, params, &H);
//
// A = df/dx and H = dh/dx are exact (forward-mode AD with ceres::Jet).
// WARNING: B = df/du and D = dh/du are central differences, because models
// take the input as plain doubles (no Jet can flow through it); see
// InputDerivative.
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
Vec<double, Model::kStateDim> ContinuousRhs(const Vec<double, Model::kStateDim>& x,
                                            const InputOf<Model>& u,
                                            const typename Model::Params& params) {
  return Model::Rhs(0.0, x, u, params);
}

// A = df/dx (x, u), exact by automatic differentiation of Model::Rhs.
template <class Model>
Mat<Model::kStateDim, Model::kStateDim> ContinuousJacobian(const Vec<double, Model::kStateDim>& x,
                                                           const InputOf<Model>& u,
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

// d f / d u (a matrix with one column per input; a zero column without
// input) by the fourth-order central difference of f along each input
// component i:
//   col i = [f(u - 2h e_i) - 8 f(u - h e_i) + 8 f(u + h e_i) - f(u + 2h e_i)] / (12 h),
// h = 1e-3 max(1, |u_i|): truncation error O(h^4 d^5f/du_i^5), rounding about
// 2 eps |f| / h. For inputs that enter affinely (forces on mechanical models,
// offsets) the truncation error is zero and only the rounding remains.
// f: any vector function of InputOf<Model>.
template <class Model, class F>
auto InputDerivative(F&& f, const InputOf<Model>& u) {
  using Column = decltype(f(u));
  constexpr int R = Column::RowsAtCompileTime;
  Mat<R, kInputCols<Model>> D = Mat<R, kInputCols<Model>>::Zero();
  if constexpr (kInputDim<Model> >= 1) {
    for (int i = 0; i < kInputCols<Model>; ++i) {
      const double ui = InputComponent<Model>(u, i);
      const double h = 1e-3 * std::max(1.0, std::abs(ui));
      auto at = [&](double v) {
        InputOf<Model> w = u;
        SetInputComponent<Model>(&w, i, v);
        return Column(f(w));
      };
      D.col(i) =
          (at(ui - 2.0 * h) - 8.0 * at(ui - h) + 8.0 * at(ui + h) - at(ui + 2.0 * h)) / (12.0 * h);
    }
  }
  return D;
}
template <class Model>
Mat<Model::kStateDim, kInputCols<Model>> InputJacobian(const Vec<double, Model::kStateDim>& x,
                                                       const InputOf<Model>& u,
                                                       const typename Model::Params& params) {
  return InputDerivative<Model>(
      [&](const InputOf<Model>& v) { return ContinuousRhs<Model>(x, v, params); }, u);
}

// A discrete-time model's map over dt linearised at (x*, u*):
//   Step(x, u) ~= Step(x*, u*) + F (x - x*) + G (u - u*),
// F = dStep/dx exact (AD), G = dStep/du by InputDerivative's central
// difference. Returns Step(x*, u*).
template <class Model>
Vec<double, Model::kStateDim> StepMapJacobians(const Vec<double, Model::kStateDim>& x,
                                               const InputOf<Model>& u, double dt,
                                               const typename Model::Params& params,
                                               Mat<Model::kStateDim, Model::kStateDim>* F,
                                               Mat<Model::kStateDim, kInputCols<Model>>* G) {
  constexpr int N = Model::kStateDim;
  *G = InputDerivative<Model>(
      [&](const InputOf<Model>& v) { return Model::template Step<double>(0.0, x, dt, v, params); },
      u);
  return ValueAndJacobian<N, N>(
      [&](const auto& xj) {
        using T = typename std::decay_t<decltype(xj)>::Scalar;
        return Model::template Step<T>(T(0.0), xj, dt, u, params);
      },
      x, F);
}

// h(t, x, u), and H = dh/dx (t, x, u) by automatic differentiation when H is
// not null, for x of any scalar T (double; ceres::Jet, whose H is then a
// nested Jet: src/ode/nested_jet.h). t and u reach only the measurements that
// see them (EvalMeasurement, models/model.h).
// Prm: Params, or ParamsT<T> when parameters are estimated (lifted to the
// nested Jet inside the Jacobian).
template <class Model, class Meas, class T = double, class Prm = typename Model::Params>
Vec<T, Meas::kDim> MeasurementAndJacobian(
    double t, const Vec<T, Model::kStateDim>& x, const InputOf<Model>& u, const Prm& params,
    std::type_identity_t<MatT<T, Meas::kDim, Model::kStateDim>>* H) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  if (H == nullptr) return EvalMeasurement<Model, Meas, T>(t, x, u, params);
  return ValueAndJacobianT<M, N>(
      [&](const auto& xj) {
        using S = typename std::decay_t<decltype(xj)>::Scalar;
        return EvalMeasurement<Model, Meas, S>(t, xj, u, ParamsAs<Model, S>(params));
      },
      x, H);
}

// D = dh/du (t, x, u) of a measurement (zero for one that does not see the
// input), by InputDerivative's central difference.
template <class Model, class Meas>
Mat<Meas::kDim, kInputCols<Model>> MeasurementInputJacobian(double t,
                                                            const Vec<double, Model::kStateDim>& x,
                                                            const InputOf<Model>& u,
                                                            const typename Model::Params& params) {
  if constexpr (MeasurementSeesInput<Meas, Model> || MeasurementSeesTime<Meas, Model>)
    return InputDerivative<Model>(
        [&](const InputOf<Model>& v) {
          return EvalMeasurement<Model, Meas, double>(t, x, v, params);
        },
        u);
  else
    return Mat<Meas::kDim, kInputCols<Model>>::Zero();
}
}  // namespace estlab

#endif  // ESTLAB_FILTERS_LINEARIZE_H_
