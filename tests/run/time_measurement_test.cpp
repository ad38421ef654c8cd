// Measurements that see the time, h(t, x, u, p) (issue 34; models/model.h
// MeasurementSeesTime, EvalMeasurement), each against a reference written
// here from the equations:
//   * h and H = dh/dx from MeasurementAndJacobian equal the measurement's
//     Eval and fourth-order central differences of it to 1e-8 at several
//     times, and D = dh/du the hand derivative (both depend on t);
//   * the EKF through the run loop (RunFilterWith) equals a hand EKF that
//     evaluates h at each row's time, in every estimate and log-likelihood,
//     to 1e-10; a hand EKF that evaluates h at t = 0 is far off;
//   * the linearised KF on a linear model with a rotating sensor
//     z = cos(w t) x1 + sin(w t) x2 equals a hand time-varying KF to 1e-10
//     (h* and H re-linearised at each update's time);
//   * the tuner's NLL equals minus the sum of the filter's log-likelihoods
//     for the KF, the EKF, the IEKF and the UKF (the likelihood has its own
//     update code) to 1e-10, and its gradient in Q and R (ceres::Jet, the
//     EKF's nested Jet) matches central differences;
//   * the particle filter's log-likelihood is near the KF's on the linear
//     model, and far from that of a KF that ignores the time;
//   * `simulate` writes y_k = h(t_k, x_k, u_k).
#include <gtest/gtest.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "adaptive/likelihood.h"
#include "adaptive/tuner_fixture.h"
#include "src/core/params.h"
#include "src/filters/linearize.h"
#include "src/ode/transition_impl.h"
#include "src/run/filter_run_impl.h"
#include "src/sim/simulator_impl.h"

namespace estlab {
namespace {

using V2 = Vec<double, 2>;
using M2 = Mat<2, 2>;

constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

// A damped oscillator pushed by u, as a discrete-time map (linear in x):
//   x+ = x + dt (A x + b u),  A = [0 1; -k -c],  b = [0; 1]
// measured by
//   sensor: h(t, x, u) = [x1 + d t, (sin(x2) + e u) cos(w t)]  (a drifting
//           position and a tachometer whose gain turns with the time);
//   rot:    h(t, x)    = cos(w t) x1 + sin(w t) x2            (linear in x).
struct Drift {
  static constexpr const char* kName = "drift-test";
  static constexpr const char* kDescription = "oscillator with time-varying sensors (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 2> kStateNames = {"x1", "x2"};
  static constexpr std::array<const char*, 2> kStateUnits = {"", ""};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 0> kPositionRatePairs = {};
  struct Params {
    double k = 1.4, c = 0.3, d = 0.05, w = 0.7, e = 0.4;
  };
  static constexpr std::array<ParamSpec<Params>, 5> kParams = {{
      {"k", &Params::k, "spring", Constraint::kAny},
      {"c", &Params::c, "damping", Constraint::kAny},
      {"d", &Params::d, "sensor drift per second", Constraint::kAny},
      {"w", &Params::w, "sensor turn rate", Constraint::kAny},
      {"e", &Params::e, "tachometer offset per input", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double dt, double u, const Params& p) {
    Vec<T, 2> next;
    next(0) = x(0) + dt * x(1);
    next(1) = x(1) + dt * (-p.k * x(0) - p.c * x(1) + u);
    return next;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct Sensor {
    static constexpr const char* kName = "sensor";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"pos", "tach"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const T& t, const Vec<T, 2>& x, double u, const Params& p) {
      using std::cos;
      using std::sin;
      return Vec<T, 2>(x(0) + p.d * t, (sin(x(1)) + p.e * u) * cos(p.w * t));
    }
  };
  struct Rot {
    static constexpr const char* kName = "rot";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"r"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static Vec<T, 1> Eval(const T& t, const Vec<T, 2>& x, double /*u*/, const Params& p) {
      using std::cos;
      using std::sin;
      return Vec<T, 1>(cos(p.w * t) * x(0) + sin(p.w * t) * x(1));
    }
  };
  // clock: h(t, x) = x1 + log(t), undefined at t = 0 (a record starting at
  // t = 1 never asks for it there).
  struct Clock {
    static constexpr const char* kName = "clock";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"c"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static Vec<T, 1> Eval(const T& t, const Vec<T, 2>& x, double /*u*/, const Params& /*p*/) {
      using std::log;
      return Vec<T, 1>(x(0) + log(t));
    }
  };
  using Measurements = std::tuple<Sensor, Rot, Clock>;
};

static_assert(DynamicModel<Drift> && kAllMeasurementsOf<Drift>);
static_assert(MeasurementSeesTime<Drift::Sensor, Drift> && MeasurementSeesTime<Drift::Rot, Drift>);
static_assert(!MeasurementSeesInput<Drift::Sensor, Drift>);

template <class Derived>
double MaxAbs(const Eigen::MatrixBase<Derived>& a) {
  return a.cwiseAbs().maxCoeff();
}

// ---------------------------------------------------------------------------
// The equations again, for the references.

M2 StepMatrix(double dt, const Drift::Params& p) {
  return (M2() << 1.0, dt, -p.k * dt, 1.0 - p.c * dt).finished();
}
V2 StepInputColumn(double dt) { return V2(0.0, dt); }

V2 SensorH(double t, const V2& x, double u, const Drift::Params& p) {
  return V2(x(0) + p.d * t, (std::sin(x(1)) + p.e * u) * std::cos(p.w * t));
}
M2 SensorJ(double t, const V2& x, const Drift::Params& p) {
  return (M2() << 1.0, 0.0, 0.0, std::cos(x(1)) * std::cos(p.w * t)).finished();
}
Mat<1, 2> RotH(double t, const Drift::Params& p) {
  return (Mat<1, 2>() << std::cos(p.w * t), std::sin(p.w * t)).finished();
}

// An uneven record (steps 0.1 and 0.25) from x0 = (1, 0) driven by a
// multisine, with deterministic disturbances and sensor errors.
struct Record {
  std::vector<double> t, u;
  std::vector<V2> x, z_sensor;
  std::vector<double> z_rot;
};

Record MakeRecord(int n) {
  const Drift::Params p;
  Record r;
  V2 x(1.0, 0.0);
  double t = 0.0;
  for (int k = 0; k < n; ++k) {
    if (k > 0) {
      const double dt = t - r.t.back();
      x = StepMatrix(dt, p) * x + StepInputColumn(dt) * r.u.back() +
          0.02 * V2(std::sin(1.3 * k), std::cos(0.7 * k));
    }
    r.t.push_back(t);
    r.u.push_back(0.8 * std::sin(0.9 * t) + 0.3 * std::sin(2.3 * t));
    r.x.push_back(x);
    r.z_sensor.push_back(SensorH(t, x, r.u.back(), p) +
                         0.05 * V2(std::sin(3.1 * k), std::cos(2.9 * k)));
    r.z_rot.push_back(RotH(t, p).dot(x) + 0.05 * std::sin(1.9 * k));
    t += k % 2 ? 0.25 : 0.1;
  }
  return r;
}

const V2 kPrior(0.8, 0.1);
const M2 kP0 = (M2() << 0.2, 0.0, 0.0, 0.2).finished();
const M2 kQ = (M2() << 1e-3, 0.0, 0.0, 2e-3).finished();

struct HandStep {
  V2 x;
  M2 P;
  double loglik = 0.0;
};

// The EKF and the KF by hand: h(t, x, u) at each row's own time, or at
// t = 0 when time_seen is false (the reference a filter that drops the
// time would match).
template <int M, class H, class J>
std::vector<HandStep> HandFilter(const Record& r, const Mat<M, M>& R, const H& h, const J& jac) {
  const Drift::Params p;
  V2 x = kPrior;
  M2 P = kP0;
  std::vector<HandStep> out;
  for (size_t k = 0; k < r.t.size(); ++k) {
    if (k > 0) {
      const double dt = r.t[k] - r.t[k - 1];
      const M2 A = StepMatrix(dt, p);
      x = A * x + StepInputColumn(dt) * r.u[k - 1];
      P = A * P * A.transpose() + kQ;
    }
    const auto [nu, Hk] = std::pair{h(k, x), jac(k, x)};
    const Mat<M, M> S = Hk * P * Hk.transpose() + R;
    const Mat<2, M> K = P * Hk.transpose() * S.inverse();
    x += K * nu;
    const M2 I_KH = M2::Identity() - K * Hk;
    P = I_KH * P * I_KH.transpose() + K * R * K.transpose();
    const double loglik =
        -0.5 * (std::log(std::pow(kTwoPi, M) * S.determinant()) + nu.dot(S.inverse() * nu));
    out.push_back({x, P, loglik});
  }
  return out;
}

std::vector<HandStep> HandSensorEkf(const Record& r, bool time_seen) {
  const Drift::Params p;
  const M2 R = 0.01 * M2::Identity();
  return HandFilter<2>(
      r, R,
      [&](size_t k, const V2& x) -> V2 {
        return r.z_sensor[k] - SensorH(time_seen ? r.t[k] : 0.0, x, r.u[k], p);
      },
      [&](size_t k, const V2& x) -> M2 { return SensorJ(time_seen ? r.t[k] : 0.0, x, p); });
}

std::vector<HandStep> HandRotKf(const Record& r, bool time_seen) {
  const Drift::Params p;
  const Mat<1, 1> R = Mat<1, 1>::Constant(0.01);
  return HandFilter<1>(
      r, R,
      [&](size_t k, const V2& x) -> Vec<double, 1> {
        return Vec<double, 1>(r.z_rot[k] - RotH(time_seen ? r.t[k] : 0.0, p).dot(x));
      },
      [&](size_t k, const V2&) -> Mat<1, 2> { return RotH(time_seen ? r.t[k] : 0.0, p); });
}

double SumLoglik(const std::vector<HandStep>& steps) {
  double sum = 0.0;
  for (const HandStep& s : steps) sum += s.loglik;
  return sum;
}

// ---------------------------------------------------------------------------
// The run loop's inputs.

FilterData SensorData(const Record& r, bool rot) {
  FilterData d;
  d.path = "time-measurement.csv";
  d.t = r.t;
  d.m = rot ? 1 : 2;
  d.nu = 1;
  for (size_t k = 0; k < r.t.size(); ++k) {
    if (rot) {
      d.z.push_back(r.z_rot[k]);
    } else {
      d.z.push_back(r.z_sensor[k](0));
      d.z.push_back(r.z_sensor[k](1));
    }
    d.u.push_back(r.u[k]);
  }
  return d;
}

FilterSpec DriftSpec(const FilterKindOptions& kind, bool rot) {
  const Drift::Params p;
  FilterSpec spec;
  spec.params = {p.k, p.c, p.d, p.w, p.e};
  spec.measurement = rot ? "rot" : "sensor";
  spec.transition.integrator = Integrator::kDiscrete;
  spec.filter = kind;
  spec.x0 = {kPrior(0), kPrior(1)};
  spec.p0 = {kP0(0, 0), kP0(0, 1), kP0(1, 0), kP0(1, 1)};
  spec.q = {kQ(0, 0), kQ(0, 1), kQ(1, 0), kQ(1, 1)};
  spec.r = rot ? std::vector<double>{0.01} : std::vector<double>{0.01, 0.0, 0.0, 0.01};
  return spec;
}

// The largest difference of the run's estimates from the reference's.
double WorstEstimate(const FilterRunOutput& out, const std::vector<HandStep>& ref) {
  auto col = [&](const std::string& name) {
    return size_t(std::find(out.columns.begin(), out.columns.end(), name) - out.columns.begin());
  };
  const size_t x1 = col("x1_est"), x2 = col("x2_est");
  if (x1 >= out.columns.size() || x2 >= out.columns.size() || out.rows.size() != ref.size())
    return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (size_t k = 0; k < ref.size(); ++k)
    worst = std::max(worst, MaxAbs(V2(out.rows[k][x1], out.rows[k][x2]) - ref[k].x));
  return worst;
}

// ---------------------------------------------------------------------------

TEST(TimeMeasurement, JacobianMatchesCentralDifferences) {
  const Drift::Params p;
  const V2 x(0.6, -0.9);
  const double u = 0.35;
  double h_apart = 0.0, H_apart = 0.0, D_apart = 0.0;
  for (const double t : {0.0, 0.8, 3.7, 11.2}) {
    SCOPED_TRACE(t);
    M2 H;
    const V2 h = MeasurementAndJacobian<Drift, Drift::Sensor>(t, x, u, p, &H);
    EXPECT_LT(MaxAbs(h - SensorH(t, x, u, p)), 1e-15);
    // Fourth-order central differences of Eval in each state.
    M2 H_cd;
    const double step = 1e-3;
    for (int j = 0; j < 2; ++j) {
      auto at = [&](double s) {
        V2 y = x;
        y(j) += s;
        return Drift::Sensor::Eval<double>(t, y, u, p);
      };
      H_cd.col(j) = (8.0 * (at(step) - at(-step)) - (at(2 * step) - at(-2 * step))) / (12 * step);
    }
    EXPECT_LT(MaxAbs(H - H_cd), 1e-8);
    EXPECT_LT(MaxAbs(H - SensorJ(t, x, p)), 1e-15);
    // D = dh/du = (0, e cos(w t)).
    const Vec<double, 2> D = MeasurementInputJacobian<Drift, Drift::Sensor>(t, x, u, p);
    EXPECT_LT(MaxAbs(D - V2(0.0, p.e * std::cos(p.w * t))), 1e-8);
    h_apart = std::max(h_apart, MaxAbs(h - SensorH(0.0, x, u, p)));
    H_apart = std::max(H_apart, MaxAbs(H - SensorJ(0.0, x, p)));
    D_apart = std::max(D_apart, std::abs(D(1) - p.e));
  }
  // The time matters: h, H and D at t = 0 would be other values.
  EXPECT_GT(h_apart, 0.1);
  EXPECT_GT(H_apart, 0.1);
  EXPECT_GT(D_apart, 0.1);
}

// The run against the reference that evaluates h at each row's time, to
// 1e-10; the reference with h at t = 0 (`timeless`) is more than a nat away,
// so the comparison sees the time.
void ExpectRunIsTheHandFilter(const FilterRunOutput& out, const std::vector<HandStep>& ref,
                              const std::vector<HandStep>& timeless) {
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  EXPECT_LT(WorstEstimate(out, ref), 1e-10);
  const double sum = SumLoglik(ref);
  EXPECT_NEAR(out.summary.loglik, sum, 1e-10 * std::abs(sum));
  EXPECT_GT(std::abs(SumLoglik(timeless) - sum), 1.0);
}

TEST(TimeMeasurement, EkfRunEqualsTheHandEkfAtEachRowsTime) {
  const Record r = MakeRecord(120);
  ExpectRunIsTheHandFilter(
      RunFilterWith<Drift, Drift::Sensor>(DriftSpec(EkfOptions{}, false), SensorData(r, false)),
      HandSensorEkf(r, true), HandSensorEkf(r, false));
}

TEST(TimeMeasurement, KfRunEqualsTheHandTimeVaryingKf) {
  const Record r = MakeRecord(120);
  ExpectRunIsTheHandFilter(
      RunFilterWith<Drift, Drift::Rot>(DriftSpec(KfOptions{}, true), SensorData(r, true)),
      HandRotKf(r, true), HandRotKf(r, false));
}

// The likelihood's own update code (KF with h* per update time, EKF, UKF)
// against the filter run.
template <class Meas>
void CheckNllIsMinusTheRunsLogLikelihood(bool rot) {
  const Record r = MakeRecord(100);
  const std::vector<FilterData> datasets = {SensorData(r, rot)};
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(EkfOptions{.iterations = 3}), FilterKindOptions(SigmaPointOptions{})}) {
    const FilterSpec spec = DriftSpec(kind, rot);
    const FilterRunOutput out = RunFilterWith<Drift, Meas>(spec, datasets[0]);
    SCOPED_TRACE(out.summary.filter + (rot ? " rot" : " sensor"));
    ASSERT_TRUE(out.summary.ok) << out.summary.message;
    TunerOptions options;
    options.q_param = NoiseParam::kFixed;
    options.r_param = NoiseParam::kFixed;
    const InnovationLikelihood<Drift, Meas> lik(spec, options, datasets);
    const std::vector<double> theta = lik.InitialTheta();
    double nll = 0.0;
    ASSERT_TRUE(lik.template Nll<double>(theta.data(), &nll));
    EXPECT_NEAR(nll, -out.summary.loglik, 1e-10 * std::abs(nll));
  }
}

TEST(TimeMeasurement, TunerNllIsMinusTheFiltersLogLikelihood) {
  CheckNllIsMinusTheRunsLogLikelihood<Drift::Sensor>(false);
  CheckNllIsMinusTheRunsLogLikelihood<Drift::Rot>(true);
}

// The gradient of the NLL in diagonal Q and R through ceres::Jet (and the
// EKF's nested Jet for H), h(t, x, u) evaluated in those scalars. The UKF
// with alpha = 0.5: at the default 1e-3 the double NLL's rounding noise
// hides the gradient from central differences (tests/adaptive/tuner_test.cpp).
TEST(TimeMeasurement, TunerGradientMatchesCentralDifferences) {
  const Record r = MakeRecord(80);
  const std::vector<FilterData> datasets = {SensorData(r, false)};
  TunerOptions options;
  options.q_param = NoiseParam::kDiag;
  options.r_param = NoiseParam::kDiag;
  uint64_t seed = 31;
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{.alpha = 0.5})}) {
    const InnovationLikelihood<Drift, Drift::Sensor> lik(DriftSpec(kind, false), options, datasets);
    ASSERT_EQ(lik.NumParams(), 4);
    testing::CheckGradient(lik, seed++, "time measurement");
  }
}

// A measurement undefined at t = 0 on a record that starts at t = 1: the KF
// run equals the hand KF, and the tuner's likelihood (whose set-up
// linearises the KF before it knows a row's time) is minus its
// log-likelihood; it used to refuse the model as "not finite at the
// operating point".
TEST(TimeMeasurement, KfLikelihoodOfAMeasurementUndefinedAtTimeZero) {
  Record r = MakeRecord(60);
  for (double& t : r.t) t += 1.0;
  for (size_t k = 0; k < r.t.size(); ++k)
    r.z_rot[k] = r.x[k](0) + std::log(r.t[k]) + 0.01 * (k % 3);
  FilterSpec spec = DriftSpec(KfOptions{}, true);
  spec.measurement = "clock";
  const FilterData data = SensorData(r, true);
  const FilterRunOutput out = RunFilterWith<Drift, Drift::Clock>(spec, data);
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  const std::vector<HandStep> hand = HandFilter<1>(
      r, Mat<1, 1>::Constant(0.01),
      [&](size_t k, const V2& x) { return Vec<double, 1>(r.z_rot[k] - x(0) - std::log(r.t[k])); },
      [](size_t, const V2&) { return Mat<1, 2>(1.0, 0.0); });
  EXPECT_LT(WorstEstimate(out, hand), 1e-10);
  EXPECT_NEAR(out.summary.loglik, SumLoglik(hand), 1e-10 * std::abs(SumLoglik(hand)));
  TunerOptions options;
  options.q_param = NoiseParam::kFixed;
  options.r_param = NoiseParam::kFixed;
  const std::vector<FilterData> datasets = {data};  // the likelihood keeps pointers to them
  const InnovationLikelihood<Drift, Drift::Clock> lik(spec, options, datasets);
  double nll = 0.0;
  std::string why;
  ASSERT_TRUE(lik.Nll<double>(lik.InitialTheta().data(), &nll, &why)) << why;
  EXPECT_NEAR(nll, -out.summary.loglik, 1e-10 * std::abs(nll));
}

// The particle filter evaluates h at each row's time: on the linear rot
// model its log-likelihood is that of the exact (Kalman) filter up to Monte
// Carlo error, and far from that of a filter that drops the time.
TEST(TimeMeasurement, ParticleFilterSeesTheTime) {
  const Record r = MakeRecord(60);
  ParticleOptions pf;
  pf.num_particles = 20000;
  pf.seed = 7;
  const FilterRunOutput out =
      RunFilterWith<Drift, Drift::Rot>(DriftSpec(pf, true), SensorData(r, true));
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  const double exact = SumLoglik(HandRotKf(r, true));
  const double timeless = SumLoglik(HandRotKf(r, false));
  ASSERT_GT(std::abs(exact - timeless), 20.0);
  EXPECT_NEAR(out.summary.loglik, exact, 2.0);
}

TEST(TimeMeasurement, SimulateWritesHAtEachRowsTime) {
  const Record r = MakeRecord(40);
  const Drift::Params p;
  SimulationSpec s;
  s.params = {p.k, p.c, p.d, p.w, p.e};
  s.x0 = {1.0, 0.0};
  s.times = r.t;
  s.inputs = r.u;
  s.input_columns = {"u"};
  s.measurement = "sensor";
  s.noise_free_outputs = true;
  s.transition.integrator = Integrator::kDiscrete;
  const SimulationResult sim = Simulate<Drift>(s);
  ASSERT_TRUE(sim.ok) << sim.error;
  ASSERT_EQ(sim.rows.size(), r.t.size());
  // Columns: t, x1, x2, u, z_pos, z_tach, y_pos, y_tach.
  ASSERT_EQ(sim.columns.size(), 8u);
  double worst = 0.0;
  for (size_t k = 0; k < r.t.size(); ++k) {
    const std::vector<double>& row = sim.rows[k];
    const V2 h = SensorH(row[0], V2(row[1], row[2]), r.u[k], p);
    worst = std::max(worst, MaxAbs(V2(row[6], row[7]) - h));
  }
  EXPECT_LT(worst, 1e-15);
}

}  // namespace
}  // namespace estlab
