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

#include "src/core/types.h"
#include "src/ode/input_path.h"
#include "src/ode/transition.h"

namespace estlab {

// Prm: the model's Params, or ParamsT<T> for parameters being estimated
// (models/model_params.h).
template <class Model, class T, class Prm = typename Model::Params>
Vec<T, Model::kStateDim> FixedStep(Integrator scheme, const Vec<T, Model::kStateDim>& x, double t,
                                   double h, const InputPath<Model>& u, const Prm& p) {
  using State = Vec<T, Model::kStateDim>;
  const T tt(t);
  if constexpr (kDiscreteTime<Model>) {
    // The map sees the sample at the step's start under either hold (its
    // substeps too): a discrete-time model has no input between samples.
    return Model::template Step<T>(tt, x, h, u.u0, p);  // MakeTransition admits kDiscrete only
  } else {
    const InputOf<Model> u_t = u.At(t);
    switch (scheme) {
      case Integrator::kEuler:
        return x + h * Model::Rhs(tt, x, u_t, p);
      case Integrator::kSemiImplicitEuler: {
        const State f = Model::Rhs(tt, x, u_t, p);
        State next = x;
        for (const auto& [pos, rate] : Model::kPositionRatePairs)
          next(rate) = x(rate) + h * f(rate);
        const State g = Model::Rhs(tt, next, u_t, p);
        for (const auto& [pos, rate] : Model::kPositionRatePairs) next(pos) = x(pos) + h * g(pos);
        return next;
      }
      case Integrator::kRk4:
      default: {
        const T half(t + 0.5 * h), full(t + h);
        const InputOf<Model> u_half = u.At(t + 0.5 * h), u_full = u.At(t + h);
        const State k1 = Model::Rhs(tt, x, u_t, p);
        const State k2 = Model::Rhs(half, State(x + (0.5 * h) * k1), u_half, p);
        const State k3 = Model::Rhs(half, State(x + (0.5 * h) * k2), u_half, p);
        const State k4 = Model::Rhs(full, State(x + h * k3), u_full, p);
        return x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      }
    }
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

// `substeps` equal steps from t0 to t1.
template <class Model, class T, class Prm = typename Model::Params>
Vec<T, Model::kStateDim> FixedPropagate(Integrator scheme, const Vec<T, Model::kStateDim>& x0,
                                        double t0, double t1, int substeps,
                                        const InputPath<Model>& u, const Prm& p) {
  const double h = (t1 - t0) / substeps;
  Vec<T, Model::kStateDim> x = x0;
  for (int i = 0; i < substeps; ++i) x = FixedStep<Model, T, Prm>(scheme, x, t0 + i * h, h, u, p);
  return x;
}

}  // namespace estlab

#endif  // ESTLAB_ODE_FIXED_STEP_H_
