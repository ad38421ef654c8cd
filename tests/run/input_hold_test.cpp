// The input between samples (--input-hold, src/ode/input_path.h): zero-order
// hold (u_k over [t_k, t_k+1)) and linear hold (the line from u_k to u_k+1),
// each against a reference written here from the equations:
//   * the truth simulation of a nonlinear two-input model over an uneven
//     record (one repeated time): RK4 with either hold equals a hand-written
//     RK4 with the same hold (stages at t, t + h/2, t + h) to 1e-12; CVODES
//     equals a fine hand RK4 to 1e-8 under either hold; the two holds give
//     different states, so each comparison sees its hold;
//   * the EKF through the run loop with a linear hold equals a hand EKF
//     (hand RK4 with the line, its flow Jacobian by the chain rule through
//     the stages) in every estimate and in the log-likelihood;
//   * the KF on x' = a x + b u with a linear hold equals the closed-form
//     first-order-hold discretisation
//       x(h) = e^{ah} x0 + b u0 (e^{ah} - 1)/a + b (u1 - u0)/h (e^{ah} - 1 - ah)/a^2
//     to 1e-12, and a whole run equals a hand KF built on it;
//   * the tuner's NLL equals minus the sum of the filter's log-likelihoods
//     under a linear hold for the KF, the EKF and the UKF (the likelihood
//     has its own prediction code), and its CVODES gradient in theta (the
//     input's line inside the sensitivity callbacks) matches central
//     differences;
//   * CVODES over constant stretches (where it continues without a restart)
//     and ramps equals the fine hand RK4 too; equal ends are the held input
//     bit for bit in RK4, CVODES and the KF.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "adaptive/likelihood.h"
#include "adaptive/tuner_fixture.h"
#include "src/core/params.h"
#include "src/filters/kalman.h"
#include "src/ode/transition_impl.h"
#include "src/run/filter_run_impl.h"
#include "src/sim/simulator_impl.h"
#include "tests/error_text.h"

namespace estlab {
namespace {

using V2 = Vec<double, 2>;
using M2 = Mat<2, 2>;

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

// A level x1 filled by a pump u1 and a squared disturbance u2, draining into
// a pendulum-like x2 that both inputs push together:
//   x1' = -k x1 + b u1 + 0.2 u2^2
//   x2' = x1 - c sin(x2) + d u1 u2
// measured: y = x2 + e u2 (sees the input).
struct Tank2 {
  static constexpr const char* kName = "tank2-test";
  static constexpr const char* kDescription = "two-input nonlinear test model";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 2;
  static constexpr std::array<const char*, 2> kInputNames = {"q", "w"};
  static constexpr std::array<const char*, 2> kInputUnits = {"", ""};
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 2> kStateNames = {"x1", "x2"};
  static constexpr std::array<const char*, 2> kStateUnits = {"", ""};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 0> kPositionRatePairs = {};
  struct Params {
    double k = 0.7, b = 0.9, c = 1.3, d = 0.25, e = 0.4;
  };
  static constexpr std::array<ParamSpec<Params>, 5> kParams = {{
      {"k", &Params::k, "outflow", Constraint::kAny},
      {"b", &Params::b, "pump gain", Constraint::kAny},
      {"c", &Params::c, "restoring", Constraint::kAny},
      {"d", &Params::d, "coupling", Constraint::kAny},
      {"e", &Params::e, "sensor offset per w", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, const Vec<double, 2>& u,
                       const Params& p) {
    using std::sin;
    Vec<T, 2> dx;
    dx(0) = -p.k * x(0) + p.b * u(0) + 0.2 * u(1) * u(1);
    dx(1) = x(0) - p.c * sin(x(1)) + p.d * u(0) * u(1);
    return dx;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, const Vec<double, 2>&) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct Y {
    static constexpr const char* kName = "y";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"y"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static Vec<T, 1> Eval(const Vec<T, 2>& x, const Vec<double, 2>& u, const Params& p) {
      return Vec<T, 1>(x(1) + p.e * u(1));
    }
  };
  using Measurements = std::tuple<Y>;
};

// x' = a x + b u, z = x: one state, one input.
struct Lin1 {
  static constexpr const char* kName = "lin1-test";
  static constexpr const char* kDescription = "scalar linear test model";
  static constexpr int kStateDim = 1;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 1> kStateNames = {"x"};
  static constexpr std::array<const char*, 1> kStateUnits = {""};
  static constexpr std::array<bool, 1> kAngleStates = {false};
  static constexpr std::array<std::pair<int, int>, 0> kPositionRatePairs = {};
  // Generic over the scalar, so that b can be estimated (model_params.h).
  template <class S = double>
  struct ParamsT {
    S a = S(-0.8);
    S b = S(1.7);
  };
  using Params = ParamsT<>;
  static constexpr std::array<ParamSpec<Params>, 2> kParams = {{
      {"a", &Params::a, "pole", Constraint::kAny},
      {"b", &Params::b, "gain", Constraint::kAny},
  }};
  template <class T, class P>
  static Vec<T, 1> Rhs(const T& /*t*/, const Vec<T, 1>& x, double u, const P& p) {
    return Vec<T, 1>(p.a * x(0) + p.b * u);
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 1>&, const Params&) {
    return Vec<double, 0>();
  }
  struct X {
    static constexpr const char* kName = "x";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"x"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T, class P>
    static Vec<T, 1> Eval(const Vec<T, 1>& x, const P& /*p*/) {
      return x;
    }
  };
  using Measurements = std::tuple<X>;
};

static_assert(DynamicModel<Tank2> && kAllMeasurementsOf<Tank2>);
static_assert(DynamicModel<Lin1> && kAllMeasurementsOf<Lin1> && EstimableParams<Lin1>);

template <class Derived>
double MaxAbs(const Eigen::MatrixBase<Derived>& a) {
  return a.cwiseAbs().maxCoeff();
}

// ---------------------------------------------------------------------------
// Tank2's equations again, for the references.

V2 TankF(const V2& x, const V2& u, const Tank2::Params& p) {
  return V2(-p.k * x(0) + p.b * u(0) + 0.2 * u(1) * u(1),
            x(0) - p.c * std::sin(x(1)) + p.d * u(0) * u(1));
}
M2 TankJ(const V2& x, const Tank2::Params& p) {
  return (M2() << -p.k, 0.0, 1.0, -p.c * std::cos(x(1))).finished();
}

// The input at time t of step [t0, t1] from u0 to u1.
V2 Line(const V2& u0, const V2& u1, double t0, double t1, double t, bool linear) {
  if (!linear || t1 <= t0) return u0;
  return u0 + (t - t0) / (t1 - t0) * (u1 - u0);
}

// Hand RK4 from t0 to t1 in `substeps` steps under either hold; *F (when not
// null) = dx(t1)/dx(t0) by the chain rule through the stages.
V2 TankRk4(V2 x, double t0, double t1, const V2& u0, const V2& u1, bool linear, int substeps,
           M2* F) {
  const Tank2::Params p;
  const double h = (t1 - t0) / substeps;
  M2 flow = M2::Identity();
  for (int s = 0; s < substeps; ++s) {
    const double t = t0 + s * h;
    const V2 ua = Line(u0, u1, t0, t1, t, linear);
    const V2 ub = Line(u0, u1, t0, t1, t + 0.5 * h, linear);
    const V2 uc = Line(u0, u1, t0, t1, t + h, linear);
    const V2 k1 = TankF(x, ua, p);
    const V2 x2 = x + 0.5 * h * k1;
    const V2 k2 = TankF(x2, ub, p);
    const V2 x3 = x + 0.5 * h * k2;
    const V2 k3 = TankF(x3, ub, p);
    const V2 x4 = x + h * k3;
    const V2 k4 = TankF(x4, uc, p);
    const M2 K1 = TankJ(x, p);
    const M2 K2 = TankJ(x2, p) * (M2::Identity() + 0.5 * h * K1);
    const M2 K3 = TankJ(x3, p) * (M2::Identity() + 0.5 * h * K2);
    const M2 K4 = TankJ(x4, p) * (M2::Identity() + h * K3);
    flow = (M2::Identity() + h / 6.0 * (K1 + 2.0 * K2 + 2.0 * K3 + K4)) * flow;
    x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
  if (F != nullptr) *F = flow;
  return x;
}

// An uneven record (steps 0.05 s and 0.2 s, one repeated time) with both
// inputs changing at every row.
struct Record {
  std::vector<double> t;
  std::vector<V2> u;
};
Record TankRecord(int rows) {
  Record r;
  double time = 0.0;
  for (int k = 0; k < rows; ++k) {
    r.t.push_back(time);
    r.u.push_back(V2(1.0 + std::sin(0.21 * k) + ((k / 20) % 2 ? 0.5 : -0.5),
                     0.8 * std::cos(0.13 * k) + 0.1 * (k % 5)));
    time += (k == 40) ? 0.0 : (k % 3 ? 0.2 : 0.05);
  }
  return r;
}

// Even steps of 0.1 s where the inputs stay constant for 8 rows, then ramp
// for 8 rows, and so on: CVODES continues through the constant stretches
// (the same held input under either hold) and must restart where a ramp
// begins or ends.
Record StretchRecord(int rows) {
  Record r;
  for (int k = 0; k < rows; ++k) {
    r.t.push_back(0.1 * k);
    const int block = k / 8, within = k % 8;
    const double level = 0.5 * std::sin(1.3 * block);
    const double ramp = (block % 2) ? 0.2 * within : 0.0;
    r.u.push_back(V2(1.0 + level + ramp, 0.4 - 0.5 * level + 0.5 * ramp));
  }
  return r;
}

const V2 kTankX0(0.5, -0.3);

std::vector<V2> HandTrajectory(const Record& r, bool linear, int substeps) {
  std::vector<V2> out = {kTankX0};
  V2 x = kTankX0;
  for (size_t k = 0; k + 1 < r.t.size(); ++k) {
    if (r.t[k + 1] > r.t[k])
      x = TankRk4(x, r.t[k], r.t[k + 1], r.u[k], r.u[k + 1], linear, substeps, nullptr);
    out.push_back(x);
  }
  return out;
}

SimulationSpec TankSimulation(const Record& r, Integrator integrator, InputHold hold) {
  const Tank2::Params p;
  SimulationSpec s;
  s.params = {p.k, p.b, p.c, p.d, p.e};
  s.x0 = {kTankX0(0), kTankX0(1)};
  s.times = r.t;
  for (const V2& u : r.u) s.inputs.insert(s.inputs.end(), {u(0), u(1)});
  s.input_columns = {"q", "w"};
  s.measurement = "y";
  s.transition.integrator = integrator;
  s.transition.input_hold = hold;
  s.transition.substeps = 3;
  s.transition.rtol = 1e-12;
  s.transition.atol = 1e-14;
  return s;
}

double WorstState(const SimulationResult& sim, const std::vector<V2>& ref) {
  double worst = 0.0;
  for (size_t k = 0; k < ref.size(); ++k)
    worst = std::max(worst, MaxAbs(V2(sim.rows[k][1], sim.rows[k][2]) - ref[k]));
  return worst;
}

TEST(InputHold, SimulationRk4EqualsTheHandRk4WithTheSameHold) {
  const Record r = TankRecord(150);
  for (const bool linear : {false, true}) {
    SCOPED_TRACE(linear ? "linear" : "zoh");
    const SimulationResult sim = Simulate<Tank2>(
        TankSimulation(r, Integrator::kRk4, linear ? InputHold::kLinear : InputHold::kZoh));
    ASSERT_TRUE(sim.ok) << sim.error;
    ASSERT_EQ(sim.rows.size(), r.t.size());
    EXPECT_LT(WorstState(sim, HandTrajectory(r, linear, 3)), 1e-12);
    // The other hold is far off: the comparison sees the hold.
    EXPECT_GT(WorstState(sim, HandTrajectory(r, !linear, 3)), 1e-3);
    // z_k = h(x_k, u_k) with the row's own sample under either hold.
    const Tank2::Params p;
    for (size_t k = 0; k < r.t.size(); ++k)
      EXPECT_NEAR(sim.rows[k][5], sim.rows[k][2] + p.e * r.u[k](1), 1e-15);
  }
}

TEST(InputHold, SimulationCvodesEqualsAFineHandRk4WithTheSameHold) {
  for (const Record& r : {TankRecord(150), StretchRecord(160)}) {
    for (const bool linear : {false, true}) {
      SCOPED_TRACE(std::string(linear ? "linear" : "zoh") +
                   (r.t.size() == 160 ? ", constant stretches" : ", changing every row"));
      const SimulationResult sim = Simulate<Tank2>(
          TankSimulation(r, Integrator::kCvodes, linear ? InputHold::kLinear : InputHold::kZoh));
      ASSERT_TRUE(sim.ok) << sim.error;
      EXPECT_LT(WorstState(sim, HandTrajectory(r, linear, 200)), 1e-8);
      EXPECT_GT(WorstState(sim, HandTrajectory(r, !linear, 200)), 1e-3);
    }
  }
}

// A step whose ends are equal is bit for bit the held SetInput, in RK4,
// CVODES and the KF; unequal ends are not.
TEST(InputHold, EqualEndsAreTheHeldInput) {
  const Tank2::Params p;
  for (const Integrator integrator : {Integrator::kRk4, Integrator::kCvodes}) {
    SCOPED_TRACE(IntegratorName(integrator));
    TransitionOptions o;
    o.integrator = integrator;
    auto a = MakeTransition<Tank2>(p, o);
    auto b = MakeTransition<Tank2>(p, o);
    a->SetInput(V2(0.4, -0.7));
    b->SetInput(V2(0.4, -0.7), V2(0.4, -0.7));
    EXPECT_EQ(a->Step(kTankX0, 0.0, 0.3), b->Step(kTankX0, 0.0, 0.3));
    b->SetInput(V2(0.4, -0.7), V2(0.5, -0.7));
    EXPECT_NE(a->Step(kTankX0, 0.0, 0.3), b->Step(kTankX0, 0.0, 0.3));
  }
  KfOptions options;
  options.operating_point = {0.0};
  LinearizedKf<Lin1, Lin1::X> held(Lin1::Params{}, options), path(Lin1::Params{}, options);
  for (auto* kf : {&held, &path}) kf->Initialize(Vec<double, 1>(0.6), Mat<1, 1>::Constant(0.4));
  held.SetInput(1.5);
  path.SetInputPath(1.5, 1.5);
  ASSERT_EQ(held.Predict(0.0, 0.3, Mat<1, 1>::Constant(0.01)), FilterStatus::kOk);
  ASSERT_EQ(path.Predict(0.0, 0.3, Mat<1, 1>::Constant(0.01)), FilterStatus::kOk);
  EXPECT_EQ(held.mean(), path.mean());
  EXPECT_EQ(held.cov(), path.cov());
}

// ---------------------------------------------------------------------------
// The EKF under a linear hold, through the run loop.

FilterData TankData(const Record& r, const std::vector<double>& z) {
  FilterData d;
  d.path = "input-hold.csv";
  d.t = r.t;
  d.m = 1;
  d.nu = 2;
  d.z = z;
  for (const V2& u : r.u) d.u.insert(d.u.end(), {u(0), u(1)});
  return d;
}

TEST(InputHold, LinearHoldEkfEqualsTheHandEkf) {
  const Record r = TankRecord(120);
  const Tank2::Params p;
  // Measurements from the linear-hold truth plus a fixed pattern.
  const std::vector<V2> truth = HandTrajectory(r, true, 3);
  std::vector<double> z;
  for (size_t k = 0; k < r.t.size(); ++k)
    z.push_back(truth[k](1) + p.e * r.u[k](1) + 0.05 * std::sin(1.7 * k));
  const M2 Q = (M2() << 1e-3, 2e-4, 2e-4, 5e-4).finished();
  const double R = 2.5e-3;
  const V2 prior(0.3, 0.0);
  const M2 P0 = (M2() << 0.2, 0.0, 0.0, 0.3).finished();

  FilterSpec spec;
  spec.params = {p.k, p.b, p.c, p.d, p.e};
  spec.measurement = "y";
  spec.transition.integrator = Integrator::kRk4;
  spec.transition.input_hold = InputHold::kLinear;
  spec.filter = EkfOptions{};
  spec.x0 = {prior(0), prior(1)};
  spec.p0 = {P0(0, 0), P0(0, 1), P0(1, 0), P0(1, 1)};
  spec.q = {Q(0, 0), Q(0, 1), Q(1, 0), Q(1, 1)};
  spec.r = {R};
  const FilterRunOutput out = RunFilterWith<Tank2, Tank2::Y>(spec, TankData(r, z));
  ASSERT_TRUE(out.summary.ok) << out.summary.message;

  // The hand EKF: predict into row k along the line u_{k-1} -> u_k, update
  // row k with h(x, u_k).
  V2 x = prior;
  M2 P = P0;
  double loglik = 0.0;
  const Vec<double, 2> H(0.0, 1.0);
  std::vector<V2> means;
  for (size_t k = 0; k < r.t.size(); ++k) {
    if (k > 0 && r.t[k] > r.t[k - 1]) {
      M2 F;
      x = TankRk4(x, r.t[k - 1], r.t[k], r.u[k - 1], r.u[k], true, 1, &F);
      P = F * P * F.transpose() + Q;
    }
    const double S = H.dot(P * H) + R;
    const V2 K = P * H / S;
    const double nu = z[k] - (x(1) + p.e * r.u[k](1));
    x += K * nu;
    const M2 IKH = M2::Identity() - K * H.transpose();
    P = IKH * P * IKH.transpose() + K * R * K.transpose();
    loglik += -0.5 * (std::log(kTwoPi * S) + nu * nu / S);
    means.push_back(x);
  }
  EXPECT_NEAR(out.summary.loglik, loglik, 1e-10 * std::abs(loglik));
  auto col = [&](const std::string& name) {
    return size_t(std::find(out.columns.begin(), out.columns.end(), name) - out.columns.begin());
  };
  const size_t x1 = col("x1_est"), x2 = col("x2_est");
  ASSERT_LT(x1, out.columns.size());
  ASSERT_LT(x2, out.columns.size());
  ASSERT_EQ(out.rows.size(), means.size());
  double worst = 0.0;
  for (size_t k = 0; k < means.size(); ++k)
    worst = std::max(worst, MaxAbs(V2(out.rows[k][x1], out.rows[k][x2]) - means[k]));
  EXPECT_LT(worst, 1e-10);
}

// ---------------------------------------------------------------------------
// The KF's first-order-hold discretisation.

// e^{ah} - 1 - ah without the cancellation of small ah.
double ExpTail(double ah) {
  if (std::abs(ah) > 0.1) return std::expm1(ah) - ah;
  double term = ah * ah / 2.0, sum = 0.0;  // sum of (ah)^n / n!, n >= 2
  for (int n = 3; n < 30 && std::abs(term) > 1e-300; ++n) {
    sum += term;
    term *= ah / n;
  }
  return sum;
}

double ClosedForm(double x0, double h, double u0, double u1) {
  const Lin1::Params p;
  const double e = std::exp(p.a * h);
  return e * x0 + p.b * u0 * std::expm1(p.a * h) / p.a +
         p.b * (u1 - u0) / h * ExpTail(p.a * h) / (p.a * p.a);
}

TEST(InputHold, KfPredictionIsTheClosedFormFirstOrderHold) {
  const Lin1::Params p;
  KfOptions options;
  options.operating_point = {0.0};
  LinearizedKf<Lin1, Lin1::X> kf(p, options);
  const Vec<double, 1> x0(0.6);
  for (const double h : {0.01, 0.3, 2.0}) {
    SCOPED_TRACE(h);
    kf.Initialize(x0, Mat<1, 1>::Constant(0.4));
    kf.SetInputPath(1.5, -2.0);
    ASSERT_EQ(kf.Predict(1.0, 1.0 + h, Mat<1, 1>::Constant(0.01)), FilterStatus::kOk);
    const double expected = ClosedForm(x0(0), h, 1.5, -2.0);
    EXPECT_NEAR(kf.mean()(0), expected, 1e-12 * std::max(1.0, std::abs(expected)));
    EXPECT_NEAR(kf.cov()(0, 0), std::exp(2 * p.a * h) * 0.4 + 0.01, 1e-12);
    // Held (zoh): the first two terms only.
    kf.Initialize(x0, Mat<1, 1>::Constant(0.4));
    kf.SetInput(1.5);
    ASSERT_EQ(kf.Predict(1.0, 1.0 + h, Mat<1, 1>::Constant(0.01)), FilterStatus::kOk);
    EXPECT_NEAR(kf.mean()(0), ClosedForm(x0(0), h, 1.5, 1.5), 1e-12);
  }
}

FilterSpec Lin1Spec(FilterKindOptions kind) {
  const Lin1::Params p;
  FilterSpec spec;
  spec.params = {p.a, p.b};
  spec.measurement = "x";
  spec.transition.integrator = Integrator::kRk4;
  spec.transition.substeps = 4;
  spec.transition.input_hold = InputHold::kLinear;
  spec.filter = kind;
  spec.x0 = {0.2};
  spec.p0 = {0.5};
  spec.q = {0.02};
  spec.r = {0.01};
  return spec;
}

FilterData Lin1Data(int rows) {
  FilterData d;
  d.path = "lin1.csv";
  d.m = 1;
  d.nu = 1;
  double t = 0.0;
  for (int k = 0; k < rows; ++k) {
    d.t.push_back(t);
    d.u.push_back(std::sin(0.4 * k) + (k % 4 == 0 ? 1.0 : 0.0));
    d.z.push_back(0.5 * std::cos(0.3 * k) + 0.1 * (k % 3));
    t += k % 2 ? 0.25 : 0.1;
  }
  return d;
}

TEST(InputHold, LinearHoldKfRunEqualsTheHandKf) {
  const FilterData d = Lin1Data(80);
  const FilterRunOutput out = RunFilterWith<Lin1, Lin1::X>(Lin1Spec(KfOptions{}), d);
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  const Lin1::Params p;
  double x = 0.2, P = 0.5, loglik = 0.0;
  for (size_t k = 0; k < d.t.size(); ++k) {
    if (k > 0) {
      const double h = d.t[k] - d.t[k - 1];
      x = ClosedForm(x, h, d.u[k - 1], d.u[k]);
      P = std::exp(2 * p.a * h) * P + 0.02;
    }
    const double S = P + 0.01, nu = d.z[k] - x;
    loglik += -0.5 * (std::log(kTwoPi * S) + nu * nu / S);
    x += P / S * nu;
    P = P * 0.01 / S;
  }
  EXPECT_NEAR(out.summary.loglik, loglik, 1e-10 * std::abs(loglik));
}

// The likelihood's own prediction (KF with Gamma1, EKF and UKF through
// FixedPropagate with the line) against the filter run.
TEST(InputHold, TunerNllIsMinusTheFiltersLogLikelihoodUnderALinearHold) {
  const FilterData d = Lin1Data(60);
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{})}) {
    const FilterSpec spec = Lin1Spec(kind);
    const FilterRunOutput out = RunFilterWith<Lin1, Lin1::X>(spec, d);
    ASSERT_TRUE(out.summary.ok) << out.summary.message;
    TunerOptions options;
    options.q_param = NoiseParam::kFixed;
    options.r_param = NoiseParam::kFixed;
    const std::vector<FilterData> datasets = {d};
    const InnovationLikelihood<Lin1, Lin1::X> lik(spec, options, datasets);
    const std::vector<double> theta = lik.InitialTheta();
    double nll = 0.0;
    ASSERT_TRUE(lik.Nll<double>(theta.data(), &nll));
    SCOPED_TRACE(out.summary.filter);
    EXPECT_NEAR(nll, -out.summary.loglik, 1e-10 * std::abs(nll));
  }
}

// CVODES under a linear hold: the tuner's gradient from the sensitivities
// in theta (src/ode/cvodes_theta_flow.h, the input's line in its callbacks)
// against fourth-order central differences of the double NLL (the separate
// CvodesTransition), with the pump gain b estimated so that the flow
// depends on theta.
TEST(InputHold, CvodesThetaFlowGradientUnderALinearHold) {
  const std::vector<FilterData> data = {Lin1Data(60)};
  TunerOptions options;
  options.q_param = NoiseParam::kDiag;
  options.r_param = NoiseParam::kDiag;
  options.estimate.push_back(EstimatedParam{.name = "b"});
  uint64_t seed = 90;
  for (const FilterKindOptions& kind :
       {FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{.rule = SigmaRule::kCubature})}) {
    FilterSpec spec = Lin1Spec(kind);
    spec.transition.integrator = Integrator::kCvodes;
    spec.transition.rtol = 1e-12;
    spec.transition.atol = 1e-14;
    const InnovationLikelihood<Lin1, Lin1::X> lik(spec, options, data);
    ASSERT_TRUE(lik.UsesCvodes());
    ASSERT_EQ(lik.NumParams(), 3);
    testing::CheckGradient(lik, seed++, "linear hold", {.h = 1e-3, .fourth_order = true});
  }
}

}  // namespace
}  // namespace estlab
