// Double pendulum of point masses on massless rods (papers 000, 003), with the
// equations of myphysicslab (https://www.myphysicslab.com/pendulum/double-pendulum-en.html).
// Angles from the downward vertical; state [theta1, omega1, theta2, omega2].
//
//   D = 2 m1 + m2 - m2 cos(2 theta1 - 2 theta2)
//   theta1'' = [-g (2 m1 + m2) sin th1 - m2 g sin(th1 - 2 th2)
//               - 2 sin(th1 - th2) m2 (w2^2 L2 + w1^2 L1 cos(th1 - th2))] / (L1 D)
//   theta2'' = [2 sin(th1 - th2) (w1^2 L1 (m1 + m2) + g (m1 + m2) cos th1
//               + w2^2 L2 m2 cos(th1 - th2))] / (L2 D)
//
// The total energy T + V (V = 0 hanging at rest) is conserved.
#ifndef ESTLAB_MODELS_DOUBLE_PENDULUM_H_
#define ESTLAB_MODELS_DOUBLE_PENDULUM_H_

#include <array>
#include <cmath>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab::models {

struct DoublePendulum {
  static constexpr const char* kName = "double-pendulum";
  static constexpr const char* kDescription =
      "double pendulum of point masses (myphysicslab), both angles absolute from the downward "
      "vertical";
  static constexpr int kStateDim = 4;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = false;
  // Rhs and every Eval are branch-free in T: points are moved in packets
  // (src/core/packet.h).
  static constexpr bool kPacketRhs = true;
  static constexpr std::array<const char*, 4> kStateNames = {"theta1", "omega1", "theta2",
                                                             "omega2"};
  // Unit of each state ("" = dimensionless), for axis labels and reports.
  static constexpr std::array<const char*, 4> kStateUnits = {"rad", "rad/s", "rad", "rad/s"};
  static constexpr std::array<bool, 4> kAngleStates = {true, false, true, false};
  static constexpr std::array<std::pair<int, int>, 2> kPositionRatePairs = {{{0, 1}, {2, 3}}};

  struct Params {
    double g = 9.81;
    double L1 = 1.0;
    double L2 = 1.0;
    double m1 = 1.0;
    double m2 = 1.0;
  };
  static constexpr std::array<ParamSpec<Params>, 5> kParams = {{
      {"g", &Params::g, "gravity [m/s^2]", Constraint::kPositive},
      {"L1", &Params::L1, "upper rod length [m]", Constraint::kPositive},
      {"L2", &Params::L2, "lower rod length [m]", Constraint::kPositive},
      {"m1", &Params::m1, "upper bob mass [kg]", Constraint::kPositive},
      {"m2", &Params::m2, "lower bob mass [kg]", Constraint::kPositive},
  }};

  template <class T>
  static Vec<T, 4> Rhs(const T& /*t*/, const Vec<T, 4>& x, double /*u*/, const Params& p) {
    using std::cos;
    using std::sin;
    const T& th1 = x(0);
    const T& w1 = x(1);
    const T& th2 = x(2);
    const T& w2 = x(3);
    const T delta = th1 - th2;
    const T s = sin(delta);
    const T c = cos(delta);
    const T den = 2.0 * p.m1 + p.m2 - p.m2 * cos(2.0 * delta);
    Vec<T, 4> dx;
    dx(0) = w1;
    dx(1) = (-p.g * (2.0 * p.m1 + p.m2) * sin(th1) - p.m2 * p.g * sin(th1 - 2.0 * th2) -
             2.0 * s * p.m2 * (w2 * w2 * p.L2 + w1 * w1 * p.L1 * c)) /
            (p.L1 * den);
    dx(2) = w2;
    dx(3) = (2.0 * s *
             (w1 * w1 * p.L1 * (p.m1 + p.m2) + p.g * (p.m1 + p.m2) * cos(th1) +
              w2 * w2 * p.L2 * p.m2 * c)) /
            (p.L2 * den);
    return dx;
  }

  static constexpr std::array<const char*, 1> kInvariantNames = {"energy"};
  static bool InvariantsHold(const Params& /*p*/, double /*u*/) { return true; }
  static Vec<double, 1> Invariants(const Vec<double, 4>& x, const Params& p) {
    const double th1 = x(0), w1 = x(1), th2 = x(2), w2 = x(3);
    const double kinetic = 0.5 * p.m1 * p.L1 * p.L1 * w1 * w1 +
                           0.5 * p.m2 *
                               (p.L1 * p.L1 * w1 * w1 + p.L2 * p.L2 * w2 * w2 +
                                2.0 * p.L1 * p.L2 * w1 * w2 * std::cos(th1 - th2));
    // Potential measured from the hanging rest position, so E > 0 away from rest.
    const double potential = (p.m1 + p.m2) * p.g * p.L1 * (1.0 - std::cos(th1)) +
                             p.m2 * p.g * p.L2 * (1.0 - std::cos(th2));
    return Vec<double, 1>(kinetic + potential);
  }

  struct Angles {
    static constexpr const char* kName = "angles";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"theta1", "theta2"};
    static constexpr std::array<bool, 2> kAngleOutputs = {true, true};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 4>& x, const Params& /*p*/) {
      return Vec<T, 2>(x(0), x(2));
    }
  };
  struct Full {
    static constexpr const char* kName = "full";
    static constexpr int kDim = 4;
    static constexpr std::array<const char*, 4> kOutputs = {"theta1", "omega1", "theta2", "omega2"};
    static constexpr std::array<bool, 4> kAngleOutputs = {true, false, true, false};
    template <class T>
    static Vec<T, 4> Eval(const Vec<T, 4>& x, const Params& /*p*/) {
      return x;
    }
  };
  // Bob positions, x to the right and y down from the pivot.
  struct Positions {
    static constexpr const char* kName = "positions";
    static constexpr int kDim = 4;
    static constexpr std::array<const char*, 4> kOutputs = {"x1", "y1", "x2", "y2"};
    static constexpr std::array<bool, 4> kAngleOutputs = {false, false, false, false};
    template <class T>
    static Vec<T, 4> Eval(const Vec<T, 4>& x, const Params& p) {
      using std::cos;
      using std::sin;
      Vec<T, 4> z;
      z(0) = p.L1 * sin(x(0));
      z(1) = p.L1 * cos(x(0));
      z(2) = z(0) + p.L2 * sin(x(2));
      z(3) = z(1) + p.L2 * cos(x(2));
      return z;
    }
  };
  using Measurements = std::tuple<Angles, Full, Positions>;
};

}  // namespace estlab::models

#endif  // ESTLAB_MODELS_DOUBLE_PENDULUM_H_
