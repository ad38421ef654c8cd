// Double inverted pendulum on a cart (paper 001), uniform rods, angles from
// upright, input u = force on the cart. Lagrangian form of Bogdanov (2004),
// "Optimal control of a double inverted pendulum on a cart", OGI CSE-04-006:
//
//   D(theta) q'' + C(theta, theta') q' + G(theta) = [1 0 0]^T u,  q = [x, th1, th2]
//   D = [d1, d2 cos th1, d3 cos th2; d2 cos th1, d4, d5 cos(th1-th2); d3 cos th2, d5 cos(th1-th2),
//   d6] C = [0, -d2 sin(th1) th1', -d3 sin(th2) th2';
//        0, 0, d5 sin(th1-th2) th2';
//        0, -d5 sin(th1-th2) th1', 0]
//   G = [0, -f1 sin th1, -f2 sin th2]
//   d1 = m0+m1+m2, d2 = (m1/2+m2) L1, d3 = m2 L2/2, d4 = (m1/3+m2) L1^2,
//   d5 = m2 L1 L2/2, d6 = m2 L2^2/3, f1 = (m1/2+m2) L1 g, f2 = m2 L2 g/2.
//
// State [x, v, theta1, omega1, theta2, omega2]. With u = 0 the energy
// q'^T D q' / 2 + f1 (1 + cos th1) + f2 (1 + cos th2) and the horizontal momentum
// (first row of D q') are conserved.
#ifndef ESTLAB_MODELS_DIPC_H_
#define ESTLAB_MODELS_DIPC_H_

#include <array>
#include <cmath>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab::models {

struct Dipc {
  static constexpr const char* kName = "dipc";
  static constexpr const char* kDescription =
      "double inverted pendulum on a cart (paper 001), uniform rods, angles from upright, input u";
  static constexpr int kStateDim = 6;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  // Rhs and every Eval are branch-free in T: points are moved in packets
  // (src/core/packet.h).
  static constexpr bool kPacketRhs = true;
  static constexpr std::array<const char*, 6> kStateNames = {"x",      "v",      "theta1",
                                                             "omega1", "theta2", "omega2"};
  // Unit of each state ("" = dimensionless), for axis labels and reports.
  static constexpr std::array<const char*, 6> kStateUnits = {"m",     "m/s", "rad",
                                                             "rad/s", "rad", "rad/s"};
  static constexpr std::array<bool, 6> kAngleStates = {false, false, true, false, true, false};
  static constexpr std::array<std::pair<int, int>, 3> kPositionRatePairs = {
      {{0, 1}, {2, 3}, {4, 5}}};

  struct Params {
    double m0 = 1.5;
    double m1 = 0.5;
    double m2 = 0.75;
    double L1 = 0.5;
    double L2 = 0.75;
    double g = 9.8;
  };
  static constexpr std::array<ParamSpec<Params>, 6> kParams = {{
      {"m0", &Params::m0, "cart mass [kg]", Constraint::kPositive},
      {"m1", &Params::m1, "lower rod mass [kg]", Constraint::kPositive},
      {"m2", &Params::m2, "upper rod mass [kg]", Constraint::kPositive},
      {"L1", &Params::L1, "lower rod length [m]", Constraint::kPositive},
      {"L2", &Params::L2, "upper rod length [m]", Constraint::kPositive},
      {"g", &Params::g, "gravity [m/s^2]", Constraint::kPositive},
  }};

  struct Coefficients {
    double d1, d2, d3, d4, d5, d6, f1, f2;
  };
  static Coefficients Coeffs(const Params& p) {
    return {p.m0 + p.m1 + p.m2,
            (0.5 * p.m1 + p.m2) * p.L1,
            0.5 * p.m2 * p.L2,
            (p.m1 / 3.0 + p.m2) * p.L1 * p.L1,
            0.5 * p.m2 * p.L1 * p.L2,
            p.m2 * p.L2 * p.L2 / 3.0,
            (0.5 * p.m1 + p.m2) * p.L1 * p.g,
            0.5 * p.m2 * p.L2 * p.g};
  }

  template <class T>
  static Vec<T, 6> Rhs(const T& /*t*/, const Vec<T, 6>& x, double u, const Params& p) {
    using std::cos;
    using std::sin;
    const Coefficients k = Coeffs(p);
    const T& v = x(1);
    const T& th1 = x(2);
    const T& w1 = x(3);
    const T& th2 = x(4);
    const T& w2 = x(5);
    const T c1 = cos(th1), s1 = sin(th1), c2 = cos(th2), s2 = sin(th2);
    const T c12 = cos(th1 - th2), s12 = sin(th1 - th2);
    // Symmetric D = [a b c; b d e; c e f].
    const double a = k.d1, d = k.d4, f = k.d6;
    const T b = k.d2 * c1, c = k.d3 * c2, e = k.d5 * c12;
    // r = H u - C q' - G
    const T r0 = u + k.d2 * s1 * w1 * w1 + k.d3 * s2 * w2 * w2;
    const T r1 = -k.d5 * s12 * w2 * w2 + k.f1 * s1;
    const T r2 = k.d5 * s12 * w1 * w1 + k.f2 * s2;
    // q'' = D^{-1} r by cofactors (D is symmetric positive definite).
    const T A00 = d * f - e * e, A01 = c * e - b * f, A02 = b * e - c * d;
    const T A11 = a * f - c * c, A12 = b * c - a * e, A22 = a * d - b * b;
    const T det = a * A00 + b * A01 + c * A02;
    Vec<T, 6> dx;
    dx(0) = v;
    dx(1) = (A00 * r0 + A01 * r1 + A02 * r2) / det;
    dx(2) = w1;
    dx(3) = (A01 * r0 + A11 * r1 + A12 * r2) / det;
    dx(4) = w2;
    dx(5) = (A02 * r0 + A12 * r1 + A22 * r2) / det;
    return dx;
  }

  static constexpr std::array<const char*, 2> kInvariantNames = {"energy", "momentum_x"};
  static bool InvariantsHold(const Params& /*p*/, double u) { return u == 0.0; }
  static Vec<double, 2> Invariants(const Vec<double, 6>& x, const Params& p) {
    const Coefficients k = Coeffs(p);
    const double v = x(1), th1 = x(2), w1 = x(3), th2 = x(4), w2 = x(5);
    const double b = k.d2 * std::cos(th1), c = k.d3 * std::cos(th2), e = k.d5 * std::cos(th1 - th2);
    const double kinetic = 0.5 * (k.d1 * v * v + k.d4 * w1 * w1 + k.d6 * w2 * w2) + b * v * w1 +
                           c * v * w2 + e * w1 * w2;
    // Potential measured from the hanging position (theta = pi), so V >= 0.
    const double potential = k.f1 * (1.0 + std::cos(th1)) + k.f2 * (1.0 + std::cos(th2));
    const double momentum = k.d1 * v + b * w1 + c * w2;
    return Vec<double, 2>(kinetic + potential, momentum);
  }

  struct XAngles {
    static constexpr const char* kName = "x-angles";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"x", "theta1", "theta2"};
    static constexpr std::array<bool, 3> kAngleOutputs = {false, true, true};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 6>& x, const Params& /*p*/) {
      return Vec<T, 3>(x(0), x(2), x(4));
    }
  };
  using Measurements = std::tuple<XAngles>;
};

}  // namespace estlab::models

#endif  // ESTLAB_MODELS_DIPC_H_
