// Vector inputs (kInputDim = 2: InputOf = Vec<double, 2>) and measurements that
// see the input (Eval(x, u, p), h(x, u)), end to end, each against a reference
// written here from the equations (never from the code under test):
//   * the truth simulation of a continuous two-input model over an uneven
//     record, u_k held over [t_k, t_k+1): RK4 equals a hand-written RK4 with
//     the same hold to 1e-12, CVODES a fine hand RK4 to 1e-8; the input
//     columns are the record's, and z_k = h(x_k, u_k) with the row's own input;
//   * the Jacobians at several (x, u): H = dh/dx (AD) is the analytic one and
//     a central difference of Eval, D = dh/du and B = df/du (central
//     differences) the analytic ones; D of a measurement without input is 0;
//   * the EKF on a discrete-time two-input model equals a hand EKF (analytic
//     F and H, Joseph form) at every step in mean, covariance and
//     log-likelihood, driven with the loop's convention (src/run/step_loop.h:
//     u_{k-1} held over the step into row k, u_k seen by row k's update); a
//     hand EKF whose h sees u_{k-1} instead is far off, so the comparison sees
//     the convention;
//   * RunFilterWith on the same data (two input columns) gives the hand EKF's
//     estimates and the sum of its log-likelihoods;
//   * the KF on a linear two-input map with a feedthrough D (z = C x + D u)
//     equals a hand linear KF; dropping D from the reference is far off;
//   * input widths that do not fit the model are refused with InputError.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "src/core/params.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/linearize.h"
#include "src/ode/transition_impl.h"
#include "src/run/filter_run_impl.h"
#include "src/sim/simulator_impl.h"
#include "tests/error_text.h"

namespace estlab {
namespace {

using V2 = Vec<double, 2>;
using M2 = Mat<2, 2>;

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

// A cart on a nonlinear spring, pushed by a force F and a disturbance w that
// enters squared (so that df/du depends on u):
//   p' = v,  v' = -k sin(p) - c v + F / m + 0.1 w^2
// measured: the position, and the motor current g v + a F (sees the input).
struct Cart2 {
  static constexpr const char* kName = "cart2-test";
  static constexpr const char* kDescription = "cart with two inputs (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 2;
  static constexpr std::array<const char*, 2> kInputNames = {"F", "w"};
  static constexpr std::array<const char*, 2> kInputUnits = {"N", "m/s^2"};
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 2> kStateNames = {"p", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};
  struct Params {
    double k = 2.0, c = 0.4, m = 1.5, g = 0.8, a = 0.3;
  };
  static constexpr std::array<ParamSpec<Params>, 5> kParams = {{
      {"k", &Params::k, "spring [1/s^2]", Constraint::kAny},
      {"c", &Params::c, "damping [1/s]", Constraint::kNonNegative},
      {"m", &Params::m, "mass [kg]", Constraint::kPositive},
      {"g", &Params::g, "current per speed [A s/m]", Constraint::kAny},
      {"a", &Params::a, "current per force [A/N]", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, const Vec<double, 2>& u,
                       const Params& p) {
    using std::sin;
    Vec<T, 2> dx;
    dx(0) = x(1);
    dx(1) = -p.k * sin(x(0)) - p.c * x(1) + u(0) / p.m + 0.1 * u(1) * u(1);
    return dx;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, const Vec<double, 2>&) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct PosCurrent {
    static constexpr const char* kName = "pos-current";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"p", "current"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const Vec<double, 2>& u, const Params& p) {
      return Vec<T, 2>(x(0), p.g * x(1) + p.a * u(0));
    }
  };
  struct Pos {
    static constexpr const char* kName = "pos";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"p"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static Vec<T, 1> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      return Vec<T, 1>(x(0));
    }
  };
  using Measurements = std::tuple<PosCurrent, Pos>;
};

// The same cart as a discrete-time map (explicit Euler in v, the disturbance
// as a velocity kick e w per step):
//   p+ = p + dt v
//   v+ = v + dt (-k sin(p) - c v + F) + e w
// measured: (p, g v + a F).
struct Disc2 {
  static constexpr const char* kName = "disc2-test";
  static constexpr const char* kDescription = "discrete cart with two inputs (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 2;
  static constexpr std::array<const char*, 2> kInputNames = {"F", "w"};
  static constexpr std::array<const char*, 2> kInputUnits = {"N", "m/s^2"};
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 2> kStateNames = {"p", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};
  struct Params {
    double k = 1.5, c = 0.3, e = 0.05, g = 0.8, a = 0.25;
  };
  static constexpr std::array<ParamSpec<Params>, 5> kParams = {{
      {"k", &Params::k, "spring [1/s^2]", Constraint::kAny},
      {"c", &Params::c, "damping [1/s]", Constraint::kNonNegative},
      {"e", &Params::e, "kick per disturbance [s]", Constraint::kAny},
      {"g", &Params::g, "current per speed [A s/m]", Constraint::kAny},
      {"a", &Params::a, "current per force [A/N]", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double dt, const Vec<double, 2>& u,
                        const Params& p) {
    using std::sin;
    Vec<T, 2> next;
    next(0) = x(0) + dt * x(1);
    next(1) = x(1) + dt * (-p.k * sin(x(0)) - p.c * x(1) + u(0)) + p.e * u(1);
    return next;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, const Vec<double, 2>&) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct PosCurrent {
    static constexpr const char* kName = "pos-current";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"p", "current"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const Vec<double, 2>& u, const Params& p) {
      return Vec<T, 2>(x(0), p.g * x(1) + p.a * u(0));
    }
  };
  using Measurements = std::tuple<PosCurrent>;
};

// A linear two-input map with feedthrough (the numbers fixed, a and b the
// diagonal of A):
//   x+ = A x + G u,  z = C x + D u.
struct Lin2 {
  static constexpr const char* kName = "lin2-test";
  static constexpr const char* kDescription = "linear two-input map with feedthrough (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 2;
  static constexpr std::array<const char*, 2> kInputNames = {"u1", "u2"};
  static constexpr std::array<const char*, 2> kInputUnits = {"", ""};
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 2> kStateNames = {"x1", "x2"};
  static constexpr std::array<const char*, 2> kStateUnits = {"", ""};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 0> kPositionRatePairs = {};
  struct Params {
    double a = 0.95, b = 0.9;
  };
  static constexpr std::array<ParamSpec<Params>, 2> kParams = {{
      {"a", &Params::a, "A(0, 0)", Constraint::kAny},
      {"b", &Params::b, "A(1, 1)", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double /*dt*/, const Vec<double, 2>& u,
                        const Params& p) {
    Vec<T, 2> next;
    next(0) = p.a * x(0) + 0.1 * x(1) + 0.05 * u(0);
    next(1) = -0.2 * x(0) + p.b * x(1) + 0.1 * u(0) - 0.03 * u(1);
    return next;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, const Vec<double, 2>&) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct Out {
    static constexpr const char* kName = "out";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"z1", "z2"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const Vec<double, 2>& u, const Params& /*p*/) {
      return Vec<T, 2>(x(0) + 0.5 * u(1), 0.3 * x(0) + x(1) - 0.4 * u(0));
    }
  };
  using Measurements = std::tuple<Out>;
};

static_assert(DynamicModel<Cart2> && kAllMeasurementsOf<Cart2> && !kDiscreteTime<Cart2>);
static_assert(DynamicModel<Disc2> && kAllMeasurementsOf<Disc2> && kDiscreteTime<Disc2>);
static_assert(DynamicModel<Lin2> && kAllMeasurementsOf<Lin2> && kDiscreteTime<Lin2>);
static_assert(std::is_same_v<InputOf<Cart2>, Vec<double, 2>>);
static_assert(MeasurementSeesInput<Cart2::PosCurrent, Cart2> &&
              !MeasurementSeesInput<Cart2::Pos, Cart2>);

template <class Derived>
double MaxAbs(const Eigen::MatrixBase<Derived>& a) {
  return a.cwiseAbs().maxCoeff();
}

// ---------------------------------------------------------------------------
// The equations again, written out for the references.

// Cart2: f(x, u) and h(x, u).
V2 CartF(const V2& x, const V2& u, const Cart2::Params& p) {
  return V2(x(1), -p.k * std::sin(x(0)) - p.c * x(1) + u(0) / p.m + 0.1 * u(1) * u(1));
}
V2 CartH(const V2& x, const V2& u, const Cart2::Params& p) {
  return V2(x(0), p.g * x(1) + p.a * u(0));
}

// Disc2: the map, its Jacobian F = dmap/dx, h(x, u) and H = dh/dx.
V2 Disc2Map(const V2& x, double dt, const V2& u, const Disc2::Params& p) {
  return V2(x(0) + dt * x(1), x(1) + dt * (-p.k * std::sin(x(0)) - p.c * x(1) + u(0)) + p.e * u(1));
}
M2 Disc2F(const V2& x, double dt, const Disc2::Params& p) {
  return (M2() << 1.0, dt, -dt * p.k * std::cos(x(0)), 1.0 - dt * p.c).finished();
}
V2 Disc2H(const V2& x, const V2& u, const Disc2::Params& p) {
  return V2(x(0), p.g * x(1) + p.a * u(0));
}
M2 Disc2Hx(const Disc2::Params& p) { return (M2() << 1.0, 0.0, 0.0, p.g).finished(); }

// Lin2: A, G, C, D.
M2 Lin2A(const Lin2::Params& p) { return (M2() << p.a, 0.1, -0.2, p.b).finished(); }
M2 Lin2G() { return (M2() << 0.05, 0.0, 0.1, -0.03).finished(); }
M2 Lin2C() { return (M2() << 1.0, 0.0, 0.3, 1.0).finished(); }
M2 Lin2D() { return (M2() << 0.0, 0.5, -0.4, 0.0).finished(); }

// ---------------------------------------------------------------------------
// Test A: the truth simulation.

// Classical RK4 on Cart2 with `substeps` equal steps per interval, u_k held
// over [t_k, t_k+1).
std::vector<V2> CartRk4(const std::vector<double>& t, const std::vector<V2>& u, V2 x,
                        int substeps) {
  const Cart2::Params p;
  std::vector<V2> out = {x};
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    const double h = (t[k + 1] - t[k]) / substeps;
    for (int s = 0; s < substeps && h > 0; ++s) {
      const V2 k1 = CartF(x, u[k], p);
      const V2 k2 = CartF(V2(x + h / 2 * k1), u[k], p);
      const V2 k3 = CartF(V2(x + h / 2 * k2), u[k], p);
      const V2 k4 = CartF(V2(x + h * k3), u[k], p);
      x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    out.push_back(x);
  }
  return out;
}

// An uneven record of 200 rows (steps 0.04 s and 0.1 s, one repeated time)
// with both inputs changing at every row.
void CartRecord(std::vector<double>* t, std::vector<V2>* u) {
  double time = 0.0;
  for (int k = 0; k < 200; ++k) {
    t->push_back(time);
    u->push_back(V2(2.0 * std::sin(0.15 * k) + ((k / 25) % 2 ? 1.0 : -1.0),
                    1.5 * std::cos(0.09 * k) + 0.3 * (k % 7)));
    time += (k == 60) ? 0.0 : (k % 3 ? 0.1 : 0.04);
  }
}

const V2 kCartX0(0.3, -0.2);

SimulationSpec CartSpec(const std::vector<double>& t, const std::vector<V2>& u) {
  const Cart2::Params p;
  SimulationSpec s;
  s.params = {p.k, p.c, p.m, p.g, p.a};
  s.x0 = {kCartX0(0), kCartX0(1)};
  s.times = t;
  for (const V2& uk : u) {
    s.inputs.push_back(uk(0));
    s.inputs.push_back(uk(1));
  }
  s.input_columns = {InputName<Cart2>(0), InputName<Cart2>(1)};
  s.measurement = "pos-current";
  return s;
}

TEST(VectorInput, SimulationRk4EqualsTheHandRk4AndZSeesTheRowsInput) {
  std::vector<double> t;
  std::vector<V2> u;
  CartRecord(&t, &u);
  SimulationSpec s = CartSpec(t, u);
  s.transition.integrator = Integrator::kRk4;
  s.transition.substeps = 3;
  const SimulationResult r = Simulate<Cart2>(s);
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.columns, (std::vector<std::string>{"t", "p", "v", "F", "w", "z_p", "z_current"}));
  ASSERT_EQ(r.rows.size(), t.size());
  const std::vector<V2> ref = CartRk4(t, u, kCartX0, 3);
  const Cart2::Params p;
  double worst = 0.0, worst_z = 0.0, reach = 0.0;
  for (size_t k = 0; k < t.size(); ++k) {
    ASSERT_EQ(r.rows[k].size(), 7u);
    EXPECT_EQ(r.rows[k][0], t[k]);
    EXPECT_EQ(r.rows[k][3], u[k](0));
    EXPECT_EQ(r.rows[k][4], u[k](1));
    const V2 x(r.rows[k][1], r.rows[k][2]);
    worst = std::max(worst, MaxAbs(x - ref[k]));
    // z_k = h(x_k, u_k): the row's own input, noise-free.
    const V2 z(r.rows[k][5], r.rows[k][6]);
    worst_z = std::max(worst_z, MaxAbs(z - CartH(x, u[k], p)));
    reach = std::max(reach, std::abs(ref[k](0)));
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(worst_z, 1e-14);
  EXPECT_GT(reach, 0.3);  // the sine spring is away from its linear range
  // Holding the next row's input instead moves the state by far more: the
  // comparison sees the hold.
  std::vector<V2> early(u.begin() + 1, u.end());
  early.push_back(u.back());
  const std::vector<V2> shifted = CartRk4(t, early, kCartX0, 3);
  double apart = 0.0;
  for (size_t k = 0; k < t.size(); ++k) apart = std::max(apart, MaxAbs(shifted[k] - ref[k]));
  EXPECT_GT(apart, 1e-3);
}

TEST(VectorInput, SimulationCvodesEqualsAFineHandRk4) {
  std::vector<double> t;
  std::vector<V2> u;
  CartRecord(&t, &u);
  SimulationSpec s = CartSpec(t, u);
  s.transition.integrator = Integrator::kCvodes;
  s.transition.rtol = 1e-12;
  s.transition.atol = 1e-14;
  const SimulationResult r = Simulate<Cart2>(s);
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.columns, (std::vector<std::string>{"t", "p", "v", "F", "w", "z_p", "z_current"}));
  ASSERT_EQ(r.rows.size(), t.size());
  const std::vector<V2> ref = CartRk4(t, u, kCartX0, 200);
  double worst = 0.0;
  for (size_t k = 0; k < t.size(); ++k)
    worst = std::max(worst, MaxAbs(V2(r.rows[k][1], r.rows[k][2]) - ref[k]));
  EXPECT_LT(worst, 1e-8);
}

// ---------------------------------------------------------------------------
// Test B: the Jacobians.

// dh/dx of Cart2::PosCurrent by a central difference of its Eval.
M2 MeasurementDifferenceInX(const V2& x, const V2& u, const Cart2::Params& p) {
  const double step = 1e-6;
  M2 H;
  for (int j = 0; j < 2; ++j) {
    V2 plus = x, minus = x;
    plus(j) += step;
    minus(j) -= step;
    H.col(j) = (Cart2::PosCurrent::Eval<double>(plus, u, p) -
                Cart2::PosCurrent::Eval<double>(minus, u, p)) /
               (plus(j) - minus(j));
  }
  return H;
}

TEST(VectorInput, JacobiansInTheStateAndInTheInput) {
  const Cart2::Params p;
  const std::array<V2, 3> xs = {V2(0.3, -0.2), V2(-1.2, 0.7), V2(2.5, 1.4)};
  const std::array<V2, 3> us = {V2(0.5, -0.3), V2(-2.0, 1.1), V2(3.0, 0.0)};
  const M2 H_exact = (M2() << 1.0, 0.0, 0.0, p.g).finished();
  const M2 D_exact = (M2() << 0.0, 0.0, p.a, 0.0).finished();
  for (const V2& x : xs) {
    for (const V2& u : us) {
      SCOPED_TRACE(::testing::Message()
                   << "x = (" << x(0) << ", " << x(1) << "), u = (" << u(0) << ", " << u(1) << ")");
      M2 H;
      const V2 h = MeasurementAndJacobian<Cart2, Cart2::PosCurrent>(0.0, x, u, p, &H);
      EXPECT_LT(MaxAbs(h - CartH(x, u, p)), 1e-15);
      EXPECT_LT(MaxAbs(H - H_exact), 1e-12);
      EXPECT_LT(MaxAbs(H - MeasurementDifferenceInX(x, u, p)), 1e-8);
      // D = dh/du: the current sees the force only.
      const M2 D = MeasurementInputJacobian<Cart2, Cart2::PosCurrent>(0.0, x, u, p);
      EXPECT_LT(MaxAbs(D - D_exact), 1e-8);
      // B = df/du: dv'/dF = 1/m, dv'/dw = d(0.1 w^2)/dw = 0.2 w.
      const M2 B = InputJacobian<Cart2>(x, u, p);
      const M2 B_exact = (M2() << 0.0, 0.0, 1.0 / p.m, 0.2 * u(1)).finished();
      EXPECT_LT(MaxAbs(B - B_exact), 1e-8);
      // The measurement without input: h = p, H = [1, 0], D exactly zero.
      Mat<1, 2> H_pos;
      const Vec<double, 1> h_pos = MeasurementAndJacobian<Cart2, Cart2::Pos>(0.0, x, u, p, &H_pos);
      EXPECT_EQ(h_pos(0), x(0));
      EXPECT_EQ(H_pos(0, 0), 1.0);
      EXPECT_EQ(H_pos(0, 1), 0.0);
      const Mat<1, 2> D_pos = MeasurementInputJacobian<Cart2, Cart2::Pos>(0.0, x, u, p);
      EXPECT_EQ(D_pos(0, 0), 0.0);
      EXPECT_EQ(D_pos(0, 1), 0.0);
    }
  }
}

// ---------------------------------------------------------------------------
// Tests C to F: filters, on data simulated here.

// A dataset: per row the time, the input u_k (held over [t_k, t_k+1), seen
// by z_k) and the measurement z_k.
struct Record {
  std::vector<double> t;
  std::vector<V2> u;
  std::vector<V2> z;
};

// The prior, the noise and the truth's start of one model's tests.
struct Scenario {
  V2 prior;
  M2 P0;
  M2 Q;  // per step
  M2 R;
  V2 truth0;
};

Scenario Disc2Setup() {
  Scenario s;
  s.prior = V2(0.2, -0.1);
  s.P0 = (M2() << 0.05, 0.0, 0.0, 0.1).finished();
  s.Q = (M2() << 1e-5, 0.0, 0.0, 4e-4).finished();
  s.R = (M2() << 4e-4, 1e-4, 1e-4, 1e-3).finished();
  s.truth0 = V2(0.35, 0.1);
  return s;
}

Scenario Lin2Setup() {
  Scenario s;
  s.prior = V2(1.0, -0.5);
  s.P0 = (M2() << 0.2, 0.05, 0.05, 0.3).finished();
  s.Q = (M2() << 1e-3, 2e-4, 2e-4, 5e-4).finished();
  s.R = (M2() << 0.01, 0.002, 0.002, 0.02).finished();
  s.truth0 = V2(0.8, -0.2);
  return s;
}

// L with L L^T = A for a 2 x 2 positive definite A.
M2 Cholesky2(const M2& A) {
  const double l00 = std::sqrt(A(0, 0));
  const double l10 = A(1, 0) / l00;
  return (M2() << l00, 0.0, l10, std::sqrt(A(1, 1) - l10 * l10)).finished();
}

// Strictly increasing times, steps 0.05 s and 0.1 s.
std::vector<double> FilterTimes(int rows) {
  std::vector<double> t;
  double time = 0.0;
  for (int k = 0; k < rows; ++k) {
    t.push_back(time);
    time += (k % 4 == 3) ? 0.1 : 0.05;
  }
  return t;
}

// Both inputs change at every row.
std::vector<V2> VaryingInputs(int rows) {
  std::vector<V2> u;
  for (int k = 0; k < rows; ++k)
    u.push_back(V2(1.5 * std::sin(0.21 * k) + ((k % 20) < 10 ? 0.5 : -0.5),
                   0.8 * std::cos(0.13 * k) + 0.2));
  return u;
}

// x_{k+1} = map(x_k, t_{k+1} - t_k, u_k) + w_k,  z_k = h(x_k, u_k) + v_k,
// w ~ N(0, Q), v ~ N(0, R), from a fixed seed.
template <class MapFn, class MeasureFn>
Record SimulateRecord(MapFn map, MeasureFn measure, const Scenario& s, int rows, uint32_t seed) {
  Record rec;
  rec.t = FilterTimes(rows);
  rec.u = VaryingInputs(rows);
  std::mt19937 gen(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto draw = [&] {
    V2 n;
    n(0) = normal(gen);
    n(1) = normal(gen);
    return n;
  };
  const M2 Lq = Cholesky2(s.Q), Lr = Cholesky2(s.R);
  V2 x = s.truth0;
  for (int k = 0; k < rows; ++k) {
    if (k > 0) x = V2(map(x, rec.t[k] - rec.t[k - 1], rec.u[k - 1]) + Lq * draw());
    rec.z.push_back(V2(measure(x, rec.u[k]) + Lr * draw()));
  }
  return rec;
}

Record Disc2Record(const Scenario& s, int rows) {
  const Disc2::Params p;
  return SimulateRecord([&](const V2& x, double dt, const V2& u) { return Disc2Map(x, dt, u, p); },
                        [&](const V2& x, const V2& u) { return Disc2H(x, u, p); }, s, rows, 2024);
}

Record Lin2Record(const Scenario& s, int rows) {
  const Lin2::Params p;
  return SimulateRecord(
      [&](const V2& x, double /*dt*/, const V2& u) { return V2(Lin2A(p) * x + Lin2G() * u); },
      [&](const V2& x, const V2& u) { return V2(Lin2C() * x + Lin2D() * u); }, s, rows, 77);
}

// The reference's belief after row k's update, and that update's
// log-likelihood.
struct HandStep {
  V2 x;
  M2 P;
  double loglik;
};

// A Kalman filter over a record, written from the equations:
//   row k > 0:  x- = f(x, t_k - t_{k-1}, u_{k-1}),  P- = F P F^T + Q  (F = df/dx at x)
//   every row:  nu = z_k - h(x-, u_seen_k),  S = H P- H^T + R,  K = P- H^T S^-1,
//               x+ = x- + K nu,  P+ = (I - K H) P- (I - K H)^T + K R K^T  (Joseph),
//               loglik = -1/2 (log det S + nu^T S^-1 nu + 2 log 2 pi)
// predict(x, dt, u, &F) returns f and sets F; measure(x, u, &H) returns h and
// sets H. u_seen: the input h sees at each row (the record's own, or another
// for the checks that must fail).
template <class PredictFn, class MeasureFn>
std::vector<HandStep> HandKalman(const Record& rec, const std::vector<V2>& u_seen,
                                 PredictFn predict, MeasureFn measure, const Scenario& s) {
  std::vector<HandStep> out;
  V2 x = s.prior;
  M2 P = s.P0;
  for (size_t k = 0; k < rec.t.size(); ++k) {
    if (k > 0) {
      M2 F;
      const V2 x_pred = predict(x, rec.t[k] - rec.t[k - 1], rec.u[k - 1], &F);
      P = F * P * F.transpose() + s.Q;
      x = x_pred;
    }
    M2 H;
    const V2 nu = rec.z[k] - measure(x, u_seen[k], &H);
    const M2 S = H * P * H.transpose() + s.R;
    const M2 S_inv = S.inverse();
    const M2 K = P * H.transpose() * S_inv;
    const M2 IKH = M2::Identity() - K * H;
    x += K * nu;
    P = IKH * P * IKH.transpose() + K * s.R * K.transpose();
    const double loglik =
        -0.5 * (std::log(S.determinant()) + nu.dot(S_inv * nu) + 2.0 * std::log(kTwoPi));
    out.push_back({x, P, loglik});
  }
  return out;
}

// The hand EKF of Disc2 (analytic F and H).
std::vector<HandStep> HandDisc2Ekf(const Record& rec, const std::vector<V2>& u_seen,
                                   const Scenario& s) {
  const Disc2::Params p;
  return HandKalman(
      rec, u_seen,
      [&](const V2& x, double dt, const V2& u, M2* F) {
        *F = Disc2F(x, dt, p);
        return Disc2Map(x, dt, u, p);
      },
      [&](const V2& x, const V2& u, M2* H) {
        *H = Disc2Hx(p);
        return Disc2H(x, u, p);
      },
      s);
}

// The hand linear KF of Lin2; with_feedthrough false drops D u from h.
std::vector<HandStep> HandLin2Kf(const Record& rec, const Scenario& s, bool with_feedthrough) {
  const Lin2::Params p;
  return HandKalman(
      rec, rec.u,
      [&](const V2& x, double /*dt*/, const V2& u, M2* F) {
        *F = Lin2A(p);
        return V2(Lin2A(p) * x + Lin2G() * u);
      },
      [&](const V2& x, const V2& u, M2* H) {
        *H = Lin2C();
        return V2(Lin2C() * x + (with_feedthrough ? 1.0 : 0.0) * (Lin2D() * u));
      },
      s);
}

// The rows' inputs one row late: u_{k-1} at row k (u_0 at row 0).
std::vector<V2> OneRowLate(const std::vector<V2>& u) {
  std::vector<V2> late = {u.front()};
  late.insert(late.end(), u.begin(), u.end() - 1);
  return late;
}

// The largest difference between two references' means.
double MeansApart(const std::vector<HandStep>& a, const std::vector<HandStep>& b) {
  double apart = 0.0;
  for (size_t k = 0; k < a.size() && k < b.size(); ++k)
    apart = std::max(apart, MaxAbs(a[k].x - b[k].x));
  return apart;
}

struct Deviation {
  double x = 0.0, P = 0.0, loglik = 0.0;
};

// Runs `filter` over the record with the loop's convention (src/run/
// step_loop.h: u_{k-1} set before the predict into row k, u_k before row k's
// update) and returns its largest difference from the reference.
template <class FilterT>
Deviation CompareWithHand(FilterT* filter, const Record& rec, const std::vector<HandStep>& ref,
                          const Scenario& s) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Deviation d;
  filter->Initialize(s.prior, s.P0);
  for (size_t k = 0; k < rec.t.size(); ++k) {
    if (k > 0) {
      filter->SetInput(rec.u[k - 1]);
      const FilterStatus status = filter->Predict(rec.t[k - 1], rec.t[k], s.Q);
      if (status != FilterStatus::kOk) {
        ADD_FAILURE() << "predict into row " << k << ": " << FilterStatusName(status) << " "
                      << filter->last_error();
        return {kInf, kInf, kInf};
      }
    }
    filter->SetInput(rec.u[k]);
    const StepResult<2> r = filter->Update(rec.z[k], s.R);
    if (r.status != FilterStatus::kOk) {
      ADD_FAILURE() << "update of row " << k << ": " << r.message;
      return {kInf, kInf, kInf};
    }
    d.x = std::max(d.x, MaxAbs(filter->mean() - ref[k].x));
    d.P = std::max(d.P, MaxAbs(filter->cov() - ref[k].P));
    d.loglik = std::max(d.loglik, std::abs(r.log_likelihood - ref[k].loglik));
  }
  return d;
}

TEST(VectorInput, EkfEqualsTheHandEkfWithTheLoopsInputs) {
  const Scenario s = Disc2Setup();
  const Record rec = Disc2Record(s, 150);
  const Disc2::Params p;
  TransitionOptions o;
  o.integrator = Integrator::kDiscrete;
  auto transition = MakeTransition<Disc2>(p, o);
  Ekf<Disc2, Disc2::PosCurrent> ekf(transition.get(), p, EkfOptions{});
  const std::vector<HandStep> ref = HandDisc2Ekf(rec, rec.u, s);
  const Deviation d = CompareWithHand(&ekf, rec, ref, s);
  EXPECT_LT(d.x, 1e-10);
  EXPECT_LT(d.P, 1e-10);
  EXPECT_LT(d.loglik, 1e-10);
  // A measurement that saw the previous row's input (the input not set
  // before the update) gives a different filter: the comparison sees it.
  EXPECT_GT(MeansApart(ref, HandDisc2Ekf(rec, OneRowLate(rec.u), s)), 1e-3);
}

// ---------------------------------------------------------------------------
// Test D: the same through the run loop.

std::vector<double> RowMajor(const M2& A) { return {A(0, 0), A(0, 1), A(1, 0), A(1, 1)}; }

// The record as a data file would give it, with the first `nu` input columns.
FilterData ToFilterData(const Record& rec, int nu) {
  FilterData d;
  d.path = "vector-input.csv";
  d.t = rec.t;
  d.m = 2;
  d.nu = nu;
  for (size_t k = 0; k < rec.t.size(); ++k) {
    d.z.push_back(rec.z[k](0));
    d.z.push_back(rec.z[k](1));
    for (int i = 0; i < nu; ++i) d.u.push_back(rec.u[k](i));
  }
  return d;
}

FilterSpec Disc2Spec(const Scenario& s) {
  const Disc2::Params p;
  FilterSpec spec;
  spec.params = {p.k, p.c, p.e, p.g, p.a};
  spec.measurement = "pos-current";
  spec.transition.integrator = Integrator::kDiscrete;
  spec.filter = EkfOptions{};
  spec.x0 = {s.prior(0), s.prior(1)};
  spec.p0 = RowMajor(s.P0);
  spec.q = RowMajor(s.Q);
  spec.r = RowMajor(s.R);
  return spec;
}

TEST(VectorInput, RunFilterWithTwoInputColumnsGivesTheHandEkf) {
  const Scenario s = Disc2Setup();
  const Record rec = Disc2Record(s, 150);
  const std::vector<HandStep> ref = HandDisc2Ekf(rec, rec.u, s);
  const FilterRunOutput out =
      RunFilterWith<Disc2, Disc2::PosCurrent>(Disc2Spec(s), ToFilterData(rec, 2));
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  EXPECT_EQ(out.summary.filter, "ekf");
  EXPECT_EQ(out.summary.updates, long(rec.t.size()));
  double sum = 0.0;
  for (const HandStep& h : ref) sum += h.loglik;
  EXPECT_NEAR(out.summary.loglik, sum, 1e-9 * std::abs(sum));
  // The rows: the estimates and the per-row log-likelihood.
  auto col = [&](const std::string& name) {
    return size_t(std::find(out.columns.begin(), out.columns.end(), name) - out.columns.begin());
  };
  const size_t p_est = col("p_est"), v_est = col("v_est"), loglik = col("loglik");
  ASSERT_LT(p_est, out.columns.size());
  ASSERT_LT(v_est, out.columns.size());
  ASSERT_LT(loglik, out.columns.size());
  ASSERT_EQ(out.rows.size(), rec.t.size());
  double worst_x = 0.0, worst_ll = 0.0;
  for (size_t k = 0; k < ref.size(); ++k) {
    worst_x = std::max(worst_x, MaxAbs(V2(out.rows[k][p_est], out.rows[k][v_est]) - ref[k].x));
    worst_ll = std::max(worst_ll, std::abs(out.rows[k][loglik] - ref[k].loglik));
  }
  EXPECT_LT(worst_x, 1e-10);
  EXPECT_LT(worst_ll, 1e-10);
}

// ---------------------------------------------------------------------------
// Test E: the KF with a feedthrough.

TEST(VectorInput, KfWithFeedthroughEqualsTheHandLinearKf) {
  const Scenario s = Lin2Setup();
  const Record rec = Lin2Record(s, 120);
  const Lin2::Params p;
  LinearizedKf<Lin2, Lin2::Out> kf(p, KfOptions{});  // about the prior mean, u* = 0
  const std::vector<HandStep> ref = HandLin2Kf(rec, s, true);
  const Deviation d = CompareWithHand(&kf, rec, ref, s);
  EXPECT_LT(d.x, 1e-10);
  EXPECT_LT(d.P, 1e-10);
  EXPECT_LT(d.loglik, 1e-10);
  // The linearisation: H = C, D = dh/du, Gamma = dmap/du (the last predict's).
  EXPECT_LT(MaxAbs(kf.H() - Lin2C()), 1e-12);
  EXPECT_LT(MaxAbs(kf.linearization().D - Lin2D()), 1e-9);
  EXPECT_LT(MaxAbs(kf.Phi() - Lin2A(p)), 1e-12);
  EXPECT_LT(MaxAbs(kf.Gamma() - Lin2G()), 1e-9);
  // Without D u in h the reference is another filter: the comparison sees D.
  EXPECT_GT(MeansApart(ref, HandLin2Kf(rec, s, false)), 1e-3);
}

// ---------------------------------------------------------------------------
// Test F: widths that do not fit.

TEST(VectorInput, InputWidthsThatDoNotFitTheModelAreRefused) {
  const Scenario s = Disc2Setup();
  const Record rec = Disc2Record(s, 20);
  const FilterSpec spec = Disc2Spec(s);
  // One input column for a model with two inputs.
  const std::string narrow = testing::ErrorText(
      [&] { (void)RunFilterWith<Disc2, Disc2::PosCurrent>(spec, ToFilterData(rec, 1)); },
      "(no InputError)");
  EXPECT_NE(narrow.find("input"), std::string::npos) << narrow;
  EXPECT_NE(narrow.find("1 input columns for a model with 2 inputs"), std::string::npos) << narrow;
  // A constant input of three values, without input columns.
  FilterSpec three = spec;
  three.input = {0.1, 0.2, 0.3};
  const std::string constant = testing::ErrorText(
      [&] { (void)RunFilterWith<Disc2, Disc2::PosCurrent>(three, ToFilterData(rec, 0)); },
      "(no InputError)");
  EXPECT_NE(constant.find("input"), std::string::npos) << constant;

  // The simulator: a constant input of three values, recorded inputs not in
  // rows of two.
  const Cart2::Params p;
  SimulationSpec sim;
  sim.params = {p.k, p.c, p.m, p.g, p.a};
  sim.x0 = {kCartX0(0), kCartX0(1)};
  sim.t_end = 1.0;
  sim.dt = 0.1;
  sim.transition.integrator = Integrator::kRk4;
  sim.measurement = "pos-current";
  sim.input = {1.0, 2.0, 3.0};
  const std::string sim_three =
      testing::ErrorText([&] { (void)Simulate<Cart2>(sim); }, "(no InputError)");
  EXPECT_NE(sim_three.find("input"), std::string::npos) << sim_three;
  sim.input.clear();
  sim.times = {0.0, 0.1, 0.2};
  sim.inputs = {1.0, 2.0, 3.0, 4.0, 5.0};
  const std::string odd =
      testing::ErrorText([&] { (void)Simulate<Cart2>(sim); }, "(no InputError)");
  EXPECT_NE(odd.find("input"), std::string::npos) << odd;
  // Two values is the model's width: it runs.
  sim.inputs.clear();
  sim.times.clear();
  sim.input = {1.0, 2.0};
  const SimulationResult ok = Simulate<Cart2>(sim);
  EXPECT_TRUE(ok.ok) << ok.error;
}

}  // namespace
}  // namespace estlab
