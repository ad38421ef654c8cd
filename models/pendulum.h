// Simple pendulum with viscous damping (papers 000, 002).
//
//   theta' = omega
//   omega' = -(g / L) sin(theta) - b omega
//
// Energy per unit mass, E = L^2 omega^2 / 2 + g L (1 - cos theta), is
// conserved when b = 0.
#ifndef ESTLAB_MODELS_PENDULUM_H_
#define ESTLAB_MODELS_PENDULUM_H_

#include <array>
#include <cmath>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab::models {

struct Pendulum {
  static constexpr const char* kName = "pendulum";
  static constexpr const char* kDescription = "simple pendulum, theta from the downward vertical";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = false;
  // Rhs and every Eval are branch-free in T: points are moved in packets
  // (src/core/packet.h).
  static constexpr bool kPacketRhs = true;
  static constexpr std::array<const char*, 2> kStateNames = {"theta", "omega"};
  // Unit of each state ("" = dimensionless), for axis labels and reports.
  static constexpr std::array<const char*, 2> kStateUnits = {"rad", "rad/s"};
  static constexpr std::array<bool, 2> kAngleStates = {true, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};

  // Generic over the scalar S so that L, b, g can be estimated
  // (models/model_params.h); Params is the double one.
  template <class S = double>
  struct ParamsT {
    S g = S(9.81);
    S L = S(1.0);
    S b = S(0.0);
  };
  using Params = ParamsT<>;
  static constexpr std::array<ParamSpec<Params>, 3> kParams = {{
      {"g", &Params::g, "gravity [m/s^2]", Constraint::kPositive},
      {"L", &Params::L, "length [m]", Constraint::kPositive},
      {"b", &Params::b, "viscous damping [1/s]", Constraint::kNonNegative},
  }};

  template <class T, class P>
  static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, double /*u*/, const P& p) {
    using std::sin;
    Vec<T, 2> dx;
    dx(0) = x(1);
    dx(1) = -(p.g / p.L) * sin(x(0)) - p.b * x(1);
    return dx;
  }

  // Invariants, conserved when b = 0.
  static constexpr std::array<const char*, 1> kInvariantNames = {"energy"};
  static bool InvariantsHold(const Params& p, double /*u*/) { return p.b == 0.0; }
  static Vec<double, 1> Invariants(const Vec<double, 2>& x, const Params& p) {
    Vec<double, 1> e;
    e(0) = 0.5 * p.L * p.L * x(1) * x(1) + p.g * p.L * (1.0 - std::cos(x(0)));
    return e;
  }

  struct Angle {
    static constexpr const char* kName = "angle";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"theta"};
    static constexpr std::array<bool, 1> kAngleOutputs = {true};
    template <class T, class P>
    static Vec<T, 1> Eval(const Vec<T, 2>& x, const P& /*p*/) {
      return Vec<T, 1>(x(0));
    }
  };
  struct Sin {
    static constexpr const char* kName = "sin";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"sin_theta"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T, class P>
    static Vec<T, 1> Eval(const Vec<T, 2>& x, const P& /*p*/) {
      using std::sin;
      return Vec<T, 1>(sin(x(0)));
    }
  };
  // Both states (theta from the encoder and omega, e.g. its finite
  // difference or a gyro), as the double pendulum's `full`.
  struct Full {
    static constexpr const char* kName = "full";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"theta", "omega"};
    static constexpr std::array<bool, 2> kAngleOutputs = {true, false};
    template <class T, class P>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const P& /*p*/) {
      return x;
    }
  };
  using Measurements = std::tuple<Angle, Sin, Full>;
};

}  // namespace estlab::models

#endif  // ESTLAB_MODELS_PENDULUM_H_
