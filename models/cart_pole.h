// Inverted pendulum on a cart (paper 004). State [x, v, theta, omega], theta
// from the downward vertical (theta = pi is upright); input F on the cart.
//
//   (M + m) x'' + b x' + m l theta'' cos(theta) - m l theta'^2 sin(theta) = F
//   (I + m l^2) theta'' + m g l sin(theta) = -m l x'' cos(theta)
//
// solved for (x'', theta'') as a 2x2 linear system whose determinant
// (M + m)(I + m l^2) - m^2 l^2 cos^2(theta) >= I (M + m) + M m l^2 > 0.
// Energy and horizontal momentum are conserved when b = 0 and F = 0.
#ifndef ESTLAB_MODELS_CART_POLE_H_
#define ESTLAB_MODELS_CART_POLE_H_

#include <array>
#include <cmath>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab::models {

struct CartPole {
  static constexpr const char* kName = "cart-pole";
  static constexpr const char* kDescription =
      "inverted pendulum on a cart (paper 004), theta from the downward vertical, input F";
  static constexpr int kStateDim = 4;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  // Rhs and every Eval are branch-free in T: points are moved in packets
  // (src/core/packet.h).
  static constexpr bool kPacketRhs = true;
  static constexpr std::array<const char*, 4> kStateNames = {"x", "v", "theta", "omega"};
  // Unit of each state ("" = dimensionless), for axis labels and reports.
  static constexpr std::array<const char*, 4> kStateUnits = {"m", "m/s", "rad", "rad/s"};
  static constexpr std::array<bool, 4> kAngleStates = {false, false, true, false};
  static constexpr std::array<std::pair<int, int>, 2> kPositionRatePairs = {{{0, 1}, {2, 3}}};

  struct Params {
    double M = 1.0;
    double m = 1.0;
    double b = 1.0;
    double I = 1.0;
    double l = 1.0;
    double g = 1.0;
  };
  static constexpr std::array<ParamSpec<Params>, 6> kParams = {{
      {"M", &Params::M, "cart mass [kg]", Constraint::kPositive},
      {"m", &Params::m, "pole mass [kg]", Constraint::kPositive},
      {"b", &Params::b, "cart friction [N s/m]", Constraint::kNonNegative},
      {"I", &Params::I, "pole inertia about its centre of mass [kg m^2]", Constraint::kNonNegative},
      {"l", &Params::l, "pivot to pole centre of mass [m]", Constraint::kPositive},
      {"g", &Params::g, "gravity [m/s^2]", Constraint::kPositive},
  }};

  template <class T>
  static Vec<T, 4> Rhs(const T& /*t*/, const Vec<T, 4>& x, double u, const Params& p) {
    using std::cos;
    using std::sin;
    const T& v = x(1);
    const T& th = x(2);
    const T& w = x(3);
    const T s = sin(th);
    const T c = cos(th);
    // [a11 a12; a12 a22] [x''; theta''] = [r1; r2]
    const double a11 = p.M + p.m;
    const T a12 = p.m * p.l * c;
    const double a22 = p.I + p.m * p.l * p.l;
    const T r1 = u - p.b * v + p.m * p.l * w * w * s;
    const T r2 = -p.m * p.g * p.l * s;
    const T det = a11 * a22 - a12 * a12;
    Vec<T, 4> dx;
    dx(0) = v;
    dx(1) = (a22 * r1 - a12 * r2) / det;
    dx(2) = w;
    dx(3) = (a11 * r2 - a12 * r1) / det;
    return dx;
  }

  static constexpr std::array<const char*, 2> kInvariantNames = {"energy", "momentum_x"};
  static bool InvariantsHold(const Params& p, double u) { return p.b == 0.0 && u == 0.0; }
  static Vec<double, 2> Invariants(const Vec<double, 4>& x, const Params& p) {
    const double v = x(1), th = x(2), w = x(3);
    const double kinetic = 0.5 * (p.M + p.m) * v * v + p.m * p.l * v * w * std::cos(th) +
                           0.5 * (p.I + p.m * p.l * p.l) * w * w;
    const double potential = p.m * p.g * p.l * (1.0 - std::cos(th));  // 0 hanging
    const double momentum = (p.M + p.m) * v + p.m * p.l * w * std::cos(th);
    return Vec<double, 2>(kinetic + potential, momentum);
  }

  struct XTheta {
    static constexpr const char* kName = "x-theta";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"x", "theta"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, true};
    // Two sensors, e.g. a slow position fix and a fast pole encoder, each
    // with its own R and rate (--measure position,encoder; docs/multirate.md).
    static constexpr std::array<OutputGroupSpec, 2> kGroups = {
        {{"position", 0, 1}, {"encoder", 1, 1}}};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 4>& x, const Params& /*p*/) {
      return Vec<T, 2>(x(0), x(2));
    }
  };
  using Measurements = std::tuple<XTheta>;
};

}  // namespace estlab::models

#endif  // ESTLAB_MODELS_CART_POLE_H_
