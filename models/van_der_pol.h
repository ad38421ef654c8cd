// Van der Pol oscillator in Lienard-free form, stiff for large mu:
//
//   x' = y
//   y' = mu (1 - x^2) y - x
//
// With mu = 1000 the relaxation period is about (3 - 2 ln 2) mu ~ 1614 and the
// Jacobian has an eigenvalue near -mu (x^2 - 1) on the slow branch, so
// explicit methods need steps of order 1/mu. CVODES BDF is the default here.
#ifndef ESTLAB_MODELS_VAN_DER_POL_H_
#define ESTLAB_MODELS_VAN_DER_POL_H_

#include <array>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab::models {

struct VanDerPol {
  static constexpr const char* kName = "van-der-pol";
  static constexpr const char* kDescription = "stiff Van der Pol oscillator";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = true;
  // Rhs and every Eval are branch-free in T: points are moved in packets
  // (src/core/packet.h).
  static constexpr bool kPacketRhs = true;
  static constexpr std::array<const char*, 2> kStateNames = {"x", "y"};
  // Unit of each state ("" = dimensionless), for axis labels and reports.
  static constexpr std::array<const char*, 2> kStateUnits = {"", ""};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};

  struct Params {
    double mu = 1000.0;
  };
  static constexpr std::array<ParamSpec<Params>, 1> kParams = {{
      {"mu", &Params::mu, "damping (stiffness) parameter", Constraint::kNonNegative},
  }};

  template <class T>
  static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, double /*u*/, const Params& p) {
    Vec<T, 2> dx;
    dx(0) = x(1);
    dx(1) = p.mu * (1.0 - x(0) * x(0)) * x(1) - x(0);
    return dx;
  }

  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params& /*p*/, double /*u*/) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>& /*x*/, const Params& /*p*/) {
    return Vec<double, 0>();
  }

  struct X {
    static constexpr const char* kName = "x";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"x"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static Vec<T, 1> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      return Vec<T, 1>(x(0));
    }
  };
  using Measurements = std::tuple<X>;
};

}  // namespace estlab::models

#endif  // ESTLAB_MODELS_VAN_DER_POL_H_
