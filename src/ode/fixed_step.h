// Fixed-step integrators templated on the scalar type, so that a step can be
// differentiated exactly with ceres::Jet (EKF Jacobians, tuner gradients).
//
//   euler:               x+ = x + h f(t, x)
//   semi-implicit-euler: velocities first, then positions with the new
//                        velocities (paper 003):  v+ = v + h a(t, q, v),
//                        q+ = q + h q'(t, q, v+)
//   rk4:                 classical fourth-order Runge-Kutta
//   discrete:            a discrete-time model's own map, x+ = Step(t, x, h, u)
//                        (models with kDiscreteTime; the only scheme they take)
// u: the input over the step (src/ode/input_path.h), evaluated where each
// scheme evaluates f: u(t) for Euler, u(t + h/2) and u(t + h) too for RK4.
// A held input (every zoh step) is u0 at every stage; a discrete-time map
// sees u0.
#ifndef ESTLAB_ODE_FIXED_STEP_H_
#define ESTLAB_ODE_FIXED_STEP_H_

#include <type_traits>

#include "src/core/types.h"
#include "src/ode/input_path.h"
#include "src/ode/transition.h"

namespace estlab {

template <int K, int N>
struct NestedJet;  // src/ode/nested_jet.h

namespace fixed_step_detail {

// One step of `scheme` with the input given by `u_at(t)` at each stage time.
// A held input's u_at returns a reference to the one sample, so the held step
// compiles to the same code as a step that takes the input directly.
template <class Model, class T, class Prm, class InputAt>
Vec<T, Model::kStateDim> Step(Integrator scheme, const Vec<T, Model::kStateDim>& x, double t,
                              double h, const InputAt& u_at, const Prm& p) {
  using State = Vec<T, Model::kStateDim>;
  const T tt(t);
  switch (scheme) {
    case Integrator::kEuler:
      return x + h * Model::Rhs(tt, x, u_at(t), p);
    case Integrator::kSemiImplicitEuler: {
      const State f = Model::Rhs(tt, x, u_at(t), p);
      State next = x;
      for (const auto& [pos, rate] : Model::kPositionRatePairs) next(rate) = x(rate) + h * f(rate);
      const State g = Model::Rhs(tt, next, u_at(t), p);
      for (const auto& [pos, rate] : Model::kPositionRatePairs) next(pos) = x(pos) + h * g(pos);
      return next;
    }
    case Integrator::kRk4:
    default: {
      const T half(t + 0.5 * h), full(t + h);
      const State k1 = Model::Rhs(tt, x, u_at(t), p);
      const State k2 = Model::Rhs(half, State(x + (0.5 * h) * k1), u_at(t + 0.5 * h), p);
      const State k3 = Model::Rhs(half, State(x + (0.5 * h) * k2), u_at(t + 0.5 * h), p);
      const State k4 = Model::Rhs(full, State(x + h * k3), u_at(t + h), p);
      return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
  }
}

// Step with everything it calls inlined (the model's Rhs, the vector sums):
// GCC's unit-growth limit otherwise decides; in a large translation unit
// (bench/filter_bench.cpp) it kept Rhs<Jet> as a call: +24 % per EKF step
// of the two-input cart (bench/results/input_hold.md). For
//   - the filters' own step: double and first-order Jets, the model's Params;
//   - the tuner's EKF flow Jacobian, NestedJet<K, N>, for N <= 4 states:
//     0.54 x the Ir per gradient of the pendulum's EKF (input_hold.md
//     "Stop 53"); GCC 12 stops with an internal compiler error at
//     NestedJet<4, 6> (the DIPC's tuner), and the double pendulum's tuner
//     (N = 4) compiles in 1.16 x the time.
template <class T>
inline constexpr bool kFlatScalar = std::is_same_v<T, double>;
template <template <class, int> class Jet, int N>
inline constexpr bool kFlatScalar<Jet<double, N>> = true;
template <class T>
inline constexpr bool kFlatNested = false;
template <int K, int N>
inline constexpr bool kFlatNested<NestedJet<K, N>> = N <= 4;
template <class Model, class T, class Prm>
inline constexpr bool kFlatStep =
    (kFlatScalar<T> && std::is_same_v<Prm, typename Model::Params>) || kFlatNested<T>;

template <class Model, class T, class Prm, class InputAt>
[[gnu::flatten]] Vec<T, Model::kStateDim> FlatStep(Integrator scheme,
                                                   const Vec<T, Model::kStateDim>& x, double t,
                                                   double h, const InputAt& u_at, const Prm& p) {
  return Step<Model, T>(scheme, x, t, h, u_at, p);
}

}  // namespace fixed_step_detail

// One step with the input u held over it. Prm: the model's Params, or
// ParamsT<T> for parameters being estimated (models/model_params.h).
template <class Model, class T, class Prm = typename Model::Params>
Vec<T, Model::kStateDim> FixedStep(Integrator scheme, const Vec<T, Model::kStateDim>& x, double t,
                                   double h, const InputOf<Model>& u, const Prm& p) {
  if constexpr (kDiscreteTime<Model>) {
    return Model::template Step<T>(T(t), x, h, u, p);  // MakeTransition admits kDiscrete only
  } else {
    const auto held = [&u](double) -> const InputOf<Model>& { return u; };
    if constexpr (fixed_step_detail::kFlatStep<Model, T, Prm>)
      return fixed_step_detail::FlatStep<Model, T>(scheme, x, t, h, held, p);
    else
      return fixed_step_detail::Step<Model, T>(scheme, x, t, h, held, p);
  }
}

// Number of right-hand side (or step map) evaluations per step of `scheme`.
inline int RhsEvalsPerStep(Integrator scheme) {
  switch (scheme) {
    case Integrator::kEuler:
    case Integrator::kDiscrete:
      return 1;
    case Integrator::kSemiImplicitEuler:
      return 2;
    default:
      return 4;
  }
}

namespace fixed_step_detail {

// FixedPropagate's loop on a ramping input, u(t) at every stage time: out
// of line, so that the held loop (every zoh step) inlines as if the ramp did
// not exist. Continuous-time models only: a discrete-time map sees the
// sample at the step's start under either hold (its substeps too).
template <class Model, class T, class Prm>
[[gnu::noinline]] Vec<T, Model::kStateDim> PropagateOnPath(Integrator scheme,
                                                           const Vec<T, Model::kStateDim>& x0,
                                                           double t0, double h, int substeps,
                                                           const InputPath<Model>& u,
                                                           const Prm& p) {
  const auto line = [&u](double s) { return u.At(s); };
  Vec<T, Model::kStateDim> x = x0;
  for (int i = 0; i < substeps; ++i) x = Step<Model, T>(scheme, x, t0 + i * h, h, line, p);
  return x;
}

}  // namespace fixed_step_detail

// `substeps` equal steps from t0 to t1 along the input u (held when its ends
// are equal).
template <class Model, class T, class Prm = typename Model::Params>
Vec<T, Model::kStateDim> FixedPropagate(Integrator scheme, const Vec<T, Model::kStateDim>& x0,
                                        double t0, double t1, int substeps,
                                        const InputPath<Model>& u, const Prm& p) {
  const double h = (t1 - t0) / substeps;
  if constexpr (!kDiscreteTime<Model>)
    if (u.ramp)
      return fixed_step_detail::PropagateOnPath<Model, T, Prm>(scheme, x0, t0, h, substeps, u, p);
  Vec<T, Model::kStateDim> x = x0;
  for (int i = 0; i < substeps; ++i)
    x = FixedStep<Model, T, Prm>(scheme, x, t0 + i * h, h, u.u0, p);
  return x;
}

}  // namespace estlab

#endif  // ESTLAB_ODE_FIXED_STEP_H_
