// The model contract, stated in the type: what every estlab model and
// measurement must define, checked by the compiler wherever a model is used
// (Transition, Filter, MakeModelEntry). A model missing a member fails with
// one error naming the unmet requirement, not pages of template errors.
//
// A model (see models/pendulum.h for a complete one):
//   kName, kDescription              const char*
//   kStateDim                        int, the state dimension n
//   kInputDim                        int, the number of inputs nu (0, 1, ...)
//   kInputNames, kInputUnits         nu names and units (optional for nu <= 1:
//                                    "u" and ""); the data columns matched
//   kStiff                           bool (BDF by default)
//   kStateNames, kStateUnits         n names, n units ("" = dimensionless)
//   kAngleStates                     n flags: wrapped in innovations and errors
//   kPositionRatePairs               (position, rate) index pairs (white-accel Q)
//   Params, kParams                  parameter struct and its table (name,
//                                    member, description with unit, constraint)
//   Rhs<T>(t, x, u, params)          dx/dt for any scalar T (double, Jet);
//                                    u is InputOf<M>: a double for nu <= 1
//                                    (0 without input), Vec<double, nu> else
//     or, for a discrete-time model (kDiscreteTime = true):
//   Step<T>(t, x, dt, u, params)     x(t + dt) for any scalar T; such a model
//                                    runs with Integrator::kDiscrete only
//   kPacketRhs (optional)            true when Rhs (or Step) and every Eval
//                                    are branch-free in T (no if, ?:, min,
//                                    max or comparison on T): point sets are
//                                    then moved kPacketWidth points per call
//                                    (src/core/packet.h)
//   kInvariantNames, Invariants(x, p), InvariantsHold(p, u)
//   Measurements                     std::tuple of measurement structs
// A measurement:
//   kName, kDim (m), kOutputs (m names), kAngleOutputs (m flags)
//   Eval<T>(x, params)               h(x) for any scalar T, or
//   Eval<T>(x, u, params)            h(x, u): a measurement that sees the
//                                    input (u as in Rhs; EvalMeasurement), or
//   Eval<T>(t, x, u, params)         h(t, x, u): one that sees the time too
//                                    (t: const T&, as in Rhs)
//   kGroups (optional)               its sensor groups: std::array of
//                                    OutputGroupSpec {name, first, count},
//                                    consecutive ranges that cover the
//                                    outputs in order; each group has its own
//                                    R block, tuned R, NIS and, in simulated
//                                    studies, its own rate (docs/multirate.md)
#ifndef ESTLAB_MODELS_MODEL_H_
#define ESTLAB_MODELS_MODEL_H_

#include <array>
#include <concepts>
#include <cstddef>
#include <tuple>
#include <type_traits>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab {

// The number of inputs of M (M::kInputDim).
template <class M>
inline constexpr int kInputDim = int(M::kInputDim);

// The number of columns of an input Jacobian (df/du, dh/du): one per
// input, and one (zero) column for a model without input.
template <class M>
inline constexpr int kInputCols = kInputDim<M> > 1 ? kInputDim<M> : 1;

// The input as M's functions take it: a double for models with at most one
// input (0.0 without input), Vec<double, nu> for more.
template <class M>
using InputOf = std::conditional_t<(kInputDim<M> > 1), Vec<double, kInputCols<M>>, double>;

// The input of M from nu doubles (the zero input when u is null).
template <class M>
InputOf<M> InputFrom(const double* u) {
  if constexpr (kInputDim<M> >= 2) {
    if (u == nullptr) return InputOf<M>::Zero();
    return Eigen::Map<const InputOf<M>>(u);
  } else {
    return (u != nullptr && kInputDim<M> == 1) ? u[0] : 0.0;
  }
}
// Component i of an input (0 <= i < max(1, nu)).
template <class M>
double InputComponent(const InputOf<M>& u, int i) {
  if constexpr (kInputDim<M> >= 2)
    return u(i);
  else
    return (void)i, u;
}
template <class M>
void SetInputComponent(InputOf<M>* u, int i, double value) {
  if constexpr (kInputDim<M> >= 2)
    (*u)(i) = value;
  else
    (void)i, *u = value;
}

// The name and unit of M's input i: kInputNames/kInputUnits when M has them,
// else "u" and "" (a model with one input may leave them out).
template <class M>
const char* InputName(int i) {
  if constexpr (requires { M::kInputNames; })
    return M::kInputNames[std::size_t(i)];
  else
    return (void)i, "u";
}
template <class M>
const char* InputUnit(int i) {
  if constexpr (requires { M::kInputUnits; })
    return M::kInputUnits[std::size_t(i)];
  else
    return (void)i, "";
}

// True for a model that states its dynamics as a step map x(t + dt) =
// Step(t, x, dt, u, p) (`static constexpr bool kDiscreteTime = true;`);
// models without the member are continuous (Rhs).
template <class M>
consteval bool IsDiscreteTime() {
  if constexpr (requires { M::kDiscreteTime; })
    return bool(M::kDiscreteTime);
  else
    return false;
}
template <class M>
inline constexpr bool kDiscreteTime = IsDiscreteTime<M>();

// True for a model whose Rhs (or Step) and every measurement's Eval may be
// evaluated on packets of points (`static constexpr bool kPacketRhs = true;`,
// src/core/packet.h); models without the member are evaluated point by point.
template <class M>
consteval bool IsPacketModel() {
  if constexpr (requires { M::kPacketRhs; })
    return bool(M::kPacketRhs);
  else
    return false;
}
template <class M>
inline constexpr bool kPacketModel = IsPacketModel<M>();

// The dynamics: Rhs<T>(t, x, u, p) = dx/dt, or Step<T>(t, x, dt, u, p) for a
// discrete-time model.
template <class M>
concept ContinuousDynamics =
    !kDiscreteTime<M> &&
    requires(const Vec<double, M::kStateDim>& x, const InputOf<M>& u, const typename M::Params& p) {
  { M::template Rhs<double>(0.0, x, u, p) } -> std::convertible_to<Vec<double, M::kStateDim>>;
};
template <class M>
concept DiscreteDynamics = kDiscreteTime<M> &&
    requires(const Vec<double, M::kStateDim>& x, const InputOf<M>& u, const typename M::Params& p) {
  { M::template Step<double>(0.0, x, 0.1, u, p) } -> std::convertible_to<Vec<double, M::kStateDim>>;
};

template <class M>
concept DynamicModel = requires(const Vec<double, M::kStateDim>& x, const InputOf<M>& u,
                                const typename M::Params& p) {
  { M::kName } -> std::convertible_to<const char*>;
  { M::kDescription } -> std::convertible_to<const char*>;
  { M::kStateDim } -> std::convertible_to<int>;
  { M::kInputDim } -> std::convertible_to<int>;
  requires M::kInputDim >= 0;
  requires M::kInputDim <= 1 || (M::kInputNames.size() == std::size_t(M::kInputDim) &&
                                 M::kInputUnits.size() == std::size_t(M::kInputDim));
  { M::kStiff } -> std::convertible_to<bool>;
  requires M::kStateNames.size() == std::size_t(M::kStateDim);
  requires M::kStateUnits.size() == std::size_t(M::kStateDim);
  requires M::kAngleStates.size() == std::size_t(M::kStateDim);
  { M::kPositionRatePairs.size() } -> std::convertible_to<std::size_t>;
  { M::kParams.size() } -> std::convertible_to<std::size_t>;
  requires ContinuousDynamics<M> || DiscreteDynamics<M>;
  { M::kInvariantNames.size() } -> std::convertible_to<std::size_t>;
  M::Invariants(x, p);
  { M::InvariantsHold(p, u) } -> std::convertible_to<bool>;
  std::tuple_size<typename M::Measurements>::value;
};

// True for a measurement h(t, x, u, p) of M: Eval takes the time and the
// input.
template <class Meas, class M>
concept MeasurementSeesTime = requires(const Vec<double, M::kStateDim>& x, const InputOf<M>& u,
                                       const typename M::Params& p) {
  { Meas::template Eval<double>(0.0, x, u, p) } -> std::convertible_to<Vec<double, Meas::kDim>>;
};

// True for a measurement h(x, u, p) of M: Eval takes the input.
template <class Meas, class M>
concept MeasurementSeesInput = requires(const Vec<double, M::kStateDim>& x, const InputOf<M>& u,
                                        const typename M::Params& p) {
  { Meas::template Eval<double>(x, u, p) } -> std::convertible_to<Vec<double, Meas::kDim>>;
};

// Meas::kGroups, or none (the measurement is one sensor).
template <class Meas>
constexpr auto MeasurementGroups() {
  if constexpr (requires { Meas::kGroups; })
    return Meas::kGroups;
  else
    return std::array<OutputGroupSpec, 0>{};
}

// The groups, if any, are non-empty consecutive ranges that cover the
// outputs in order.
template <class Meas>
constexpr bool GroupsCoverOutputs() {
  int next = 0;
  for (const OutputGroupSpec& g : MeasurementGroups<Meas>()) {
    if (g.first != next || g.count < 1) return false;
    next += g.count;
  }
  return next == 0 || next == Meas::kDim;
}

template <class Meas, class M>
concept MeasurementOf = DynamicModel<M> &&
    requires(const Vec<double, M::kStateDim>& x, const typename M::Params& p) {
  { Meas::kName } -> std::convertible_to<const char*>;
  { Meas::kDim } -> std::convertible_to<int>;
  requires Meas::kOutputs.size() == std::size_t(Meas::kDim);
  requires Meas::kAngleOutputs.size() == std::size_t(Meas::kDim);
  requires GroupsCoverOutputs<Meas>();
  requires MeasurementSeesTime<Meas, M> || MeasurementSeesInput<Meas, M> || requires {
    { Meas::template Eval<double>(x, p) } -> std::convertible_to<Vec<double, Meas::kDim>>;
  };
};

// h(t, x, u, p) for every measurement: the time and the input are passed to
// those that see them and dropped for the others. t: the measurement's time
// (the filters' time(), src/filters/filter.h). T: the state's scalar; P:
// Params or ParamsT<S>.
template <class Model, class Meas, class T, class P>
Vec<T, Meas::kDim> EvalMeasurement(double t, const Vec<T, Model::kStateDim>& x,
                                   const InputOf<Model>& u, const P& p) {
  if constexpr (MeasurementSeesTime<Meas, Model>)
    return Meas::template Eval<T>(T(t), x, u, p);
  else if constexpr (MeasurementSeesInput<Meas, Model>)
    return (void)t, Meas::template Eval<T>(x, u, p);
  else
    return (void)t, (void)u, Meas::template Eval<T>(x, p);
}

// Every measurement in M::Measurements satisfies MeasurementOf<., M>.
template <class M, class Tuple = typename M::Measurements>
inline constexpr bool kAllMeasurementsOf = false;
template <class M, class... Meas>
inline constexpr bool kAllMeasurementsOf<M, std::tuple<Meas...>> = (MeasurementOf<Meas, M> && ...);

}  // namespace estlab

#endif  // ESTLAB_MODELS_MODEL_H_
