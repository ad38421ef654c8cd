// Exact Jacobians by forward-mode automatic differentiation with ceres::Jet.
//
// Usage:
//   Mat<2, 2> J;
//   Vec<double, 2> fx = ValueAndJacobian<2, 2>(
//       [&](const auto& x) { return Model::Rhs(T(t), x, u, p); }, x, &J);
//
// The functor must be a generic lambda (or template) accepting
// Vec<ceres::Jet<double, N>, N> and returning Vec<same Jet, M>.
// WARNING: include this header only in translation units that instantiate
// models (the generated per-model units of models/model_list.cmake, tests); ceres/jet.h is a heavy
// template.
#ifndef ESTLAB_ODE_AUTODIFF_H_
#define ESTLAB_ODE_AUTODIFF_H_

#include <ceres/jet.h>

#include "src/core/types.h"

namespace estlab {

template <int N>
using Jet = ceres::Jet<double, N>;

// Seeds x as N independent Jet variables.
template <int N>
Vec<Jet<N>, N> SeedJets(const Vec<double, N>& x) {
  Vec<Jet<N>, N> xj;
  for (int i = 0; i < N; ++i) xj(i) = Jet<N>(x(i), i);
  return xj;
}

// Returns f(x) and writes df/dx into *jacobian (skipped when null).
template <int M, int N, class F>
Vec<double, M> ValueAndJacobian(F&& f, const Vec<double, N>& x, Mat<M, N>* jacobian) {
  const Vec<Jet<N>, M> fj = f(SeedJets<N>(x));
  Vec<double, M> value;
  for (int i = 0; i < M; ++i) {
    value(i) = fj(i).a;
    if (jacobian != nullptr) jacobian->row(i) = fj(i).v.transpose();
  }
  return value;
}

}  // namespace estlab

#endif  // ESTLAB_ODE_AUTODIFF_H_
