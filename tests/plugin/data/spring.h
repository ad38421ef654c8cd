// A user's C++ model header, in the form of models/pendulum.h (the contract:
// docs/models.md): a linear spring-mass-damper, x'' = -k x - c x'.
#include <array>
#include <tuple>
#include <utility>

#include "src/core/params.h"
#include "src/core/types.h"

namespace lab {

struct Spring {
  static constexpr const char* kName = "spring";
  static constexpr const char* kDescription = "spring-mass-damper (user header)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 2> kStateNames = {"x", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};

  struct Params {
    double k = 4.0;
    double c = 0.1;
  };
  static constexpr std::array<estlab::ParamSpec<Params>, 2> kParams = {{
      {"k", &Params::k, "stiffness [1/s^2]", estlab::Constraint::kPositive},
      {"c", &Params::c, "damping [1/s]", estlab::Constraint::kNonNegative},
  }};

  template <class T>
  static estlab::Vec<T, 2> Rhs(const T& /*t*/, const estlab::Vec<T, 2>& x, double /*u*/,
                               const Params& p) {
    estlab::Vec<T, 2> dx;
    dx(0) = x(1);
    dx(1) = -p.k * x(0) - p.c * x(1);
    return dx;
  }

  static constexpr std::array<const char*, 1> kInvariantNames = {"energy"};
  static bool InvariantsHold(const Params& p, double /*u*/) { return p.c == 0.0; }
  static estlab::Vec<double, 1> Invariants(const estlab::Vec<double, 2>& x, const Params& p) {
    return estlab::Vec<double, 1>(0.5 * x(1) * x(1) + 0.5 * p.k * x(0) * x(0));
  }

  struct Position {
    static constexpr const char* kName = "position";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"x"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static estlab::Vec<T, 1> Eval(const estlab::Vec<T, 2>& x, const Params& /*p*/) {
      return estlab::Vec<T, 1>(x(0));
    }
  };
  using Measurements = std::tuple<Position>;
};

}  // namespace lab

#define ESTLAB_MODEL_TYPE lab::Spring
