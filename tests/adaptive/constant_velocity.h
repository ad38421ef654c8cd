// A linear test model shared by the tuner's and EM's tests.
#ifndef ESTLAB_TESTS_ADAPTIVE_CONSTANT_VELOCITY_H_
#define ESTLAB_TESTS_ADAPTIVE_CONSTANT_VELOCITY_H_

#include <array>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"
#include "src/run/filter_spec.h"

namespace estlab::testing {

// Constant velocity on `Axes` independent axes, positions measured: with the
// Euler step this is exactly x+ = [[1, dt], [0, 1]] x per axis.
template <int Axes>
struct ConstantVelocity {
  static constexpr const char* kName = "constant-velocity";
  static constexpr const char* kDescription = "test model";
  static constexpr int kStateDim = 2 * Axes;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 4> kAllNames = {"p1", "v1", "p2", "v2"};
  static constexpr std::array<const char*, kStateDim> kStateNames = [] {
    std::array<const char*, kStateDim> a{};
    for (int i = 0; i < kStateDim; ++i) a[i] = kAllNames[i];
    return a;
  }();
  static constexpr std::array<bool, kStateDim> kAngleStates{};
  static constexpr std::array<const char*, kStateDim> kStateUnits = [] {
    std::array<const char*, kStateDim> a{};
    for (int i = 0; i < kStateDim; ++i) a[i] = i % 2 ? "m/s" : "m";
    return a;
  }();
  static constexpr std::array<std::pair<int, int>, Axes> kPositionRatePairs = [] {
    std::array<std::pair<int, int>, Axes> a{};
    for (int i = 0; i < Axes; ++i) a[i] = {2 * i, 2 * i + 1};
    return a;
  }();
  struct Params {};
  static constexpr std::array<ParamSpec<Params>, 0> kParams = {};

  template <class T>
  static Vec<T, kStateDim> Rhs(const T& /*t*/, const Vec<T, kStateDim>& x, double /*u*/,
                               const Params& /*p*/) {
    Vec<T, kStateDim> dx;
    for (int i = 0; i < Axes; ++i) {
      dx(2 * i) = x(2 * i + 1);
      dx(2 * i + 1) = T(0.0);
    }
    return dx;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, kStateDim>&, const Params&) {
    return Vec<double, 0>();
  }

  struct Positions {
    static constexpr const char* kName = "positions";
    static constexpr int kDim = Axes;
    static constexpr std::array<const char*, 2> kAllOutputs = {"p1", "p2"};
    static constexpr std::array<const char*, Axes> kOutputs = [] {
      std::array<const char*, Axes> a{};
      for (int i = 0; i < Axes; ++i) a[i] = kAllOutputs[i];
      return a;
    }();
    static constexpr std::array<bool, Axes> kAngleOutputs{};
    template <class T>
    static Vec<T, Axes> Eval(const Vec<T, kStateDim>& x, const Params& /*p*/) {
      Vec<T, Axes> z;
      for (int i = 0; i < Axes; ++i) z(i) = x(2 * i);
      return z;
    }
  };
  using Measurements = std::tuple<Positions>;
};

// The one-axis model's filter spec: x0 = (0, 1), P0 = I, white-accel Q
// (qc0) and R = r0, the Euler transition.
inline FilterSpec CvSpec(double qc0, double r0, FilterKindOptions filter = EkfOptions{}) {
  FilterSpec spec;
  spec.measurement = "positions";
  spec.filter = filter;
  spec.transition.integrator = Integrator::kEuler;
  spec.x0 = {0.0, 1.0};
  spec.p0 = {1.0, 0.0, 0.0, 1.0};
  spec.q_white_accel = true;
  spec.qc = qc0;
  spec.r = {r0};
  return spec;
}

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_ADAPTIVE_CONSTANT_VELOCITY_H_
