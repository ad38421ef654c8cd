// The model contract, stated in the type: what every estlab model and
// measurement must define, checked by the compiler wherever a model is used
// (Transition, Filter, MakeModelEntry). A model missing a member fails with
// one error naming the unmet requirement, not pages of template errors.
//
// A model (see models/pendulum.h for a complete one):
//   kName, kDescription              const char*
//   kStateDim                        int, the state dimension n
//   kHasInput, kStiff                bool (one scalar input u; BDF by default)
//   kStateNames, kStateUnits         n names, n units ("" = dimensionless)
//   kAngleStates                     n flags: wrapped in innovations and errors
//   kPositionRatePairs               (position, rate) index pairs (white-accel Q)
//   Params, kParams                  parameter struct and its table (name,
//                                    member, description with unit, constraint)
//   Rhs<T>(t, x, u, params)          dx/dt for any scalar T (double, Jet)
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
//   Eval<T>(x, params)               h(x) for any scalar T
#ifndef ESTLAB_MODELS_MODEL_H_
#define ESTLAB_MODELS_MODEL_H_

#include <concepts>
#include <cstddef>
#include <tuple>
#include <utility>

#include "src/core/types.h"

namespace estlab {

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
    !kDiscreteTime<M> && requires(const Vec<double, M::kStateDim>& x, const typename M::Params& p) {
  { M::template Rhs<double>(0.0, x, 0.0, p) } -> std::convertible_to<Vec<double, M::kStateDim>>;
};
template <class M>
concept DiscreteDynamics = kDiscreteTime<M> &&
    requires(const Vec<double, M::kStateDim>& x, const typename M::Params& p) {
  {
    M::template Step<double>(0.0, x, 0.1, 0.0, p)
    } -> std::convertible_to<Vec<double, M::kStateDim>>;
};

template <class M>
concept DynamicModel = requires(const Vec<double, M::kStateDim>& x, const typename M::Params& p) {
  { M::kName } -> std::convertible_to<const char*>;
  { M::kDescription } -> std::convertible_to<const char*>;
  { M::kStateDim } -> std::convertible_to<int>;
  { M::kHasInput } -> std::convertible_to<bool>;
  { M::kStiff } -> std::convertible_to<bool>;
  requires M::kStateNames.size() == std::size_t(M::kStateDim);
  requires M::kStateUnits.size() == std::size_t(M::kStateDim);
  requires M::kAngleStates.size() == std::size_t(M::kStateDim);
  { M::kPositionRatePairs.size() } -> std::convertible_to<std::size_t>;
  { M::kParams.size() } -> std::convertible_to<std::size_t>;
  requires ContinuousDynamics<M> || DiscreteDynamics<M>;
  { M::kInvariantNames.size() } -> std::convertible_to<std::size_t>;
  M::Invariants(x, p);
  { M::InvariantsHold(p, 0.0) } -> std::convertible_to<bool>;
  std::tuple_size<typename M::Measurements>::value;
};

template <class Meas, class M>
concept MeasurementOf = DynamicModel<M> &&
    requires(const Vec<double, M::kStateDim>& x, const typename M::Params& p) {
  { Meas::kName } -> std::convertible_to<const char*>;
  { Meas::kDim } -> std::convertible_to<int>;
  requires Meas::kOutputs.size() == std::size_t(Meas::kDim);
  requires Meas::kAngleOutputs.size() == std::size_t(Meas::kDim);
  { Meas::template Eval<double>(x, p) } -> std::convertible_to<Vec<double, Meas::kDim>>;
};

// Every measurement in M::Measurements satisfies MeasurementOf<., M>.
template <class M, class Tuple = typename M::Measurements>
inline constexpr bool kAllMeasurementsOf = false;
template <class M, class... Meas>
inline constexpr bool kAllMeasurementsOf<M, std::tuple<Meas...>> = (MeasurementOf<Meas, M> && ...);

}  // namespace estlab

#endif  // ESTLAB_MODELS_MODEL_H_
