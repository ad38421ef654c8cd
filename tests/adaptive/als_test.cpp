// Tests of autocovariance least squares (adaptive/als.h, Estimator::kAls):
//   * the 3-state example of Odelson, Rajamani & Rawlings (Automatica 2006):
//     over 50 simulated datasets of 5000 samples the mean ALS estimate of
//     every element of Q and R is within 3 Monte Carlo standard errors of
//     the truth, from a deliberately wrong initial gain;
//   * the model autocovariances S_j(Q, R) against a hand-written stationary
//     formula (Odelson's C_j) on a long run;
//   * the identifiability report: lags that cannot separate Q from R are
//     named, enough lags identify every element;
//   * filters and rows ALS does not take are refused.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "adaptive/tuner.h"
#include "adaptive/tuner_impl.h"
#include "src/core/params.h"
#include "src/core/random.h"
#include "src/ode/transition_impl.h"  // MakeTransition for the test-only model

namespace estlab {
namespace {

// x_{k+1} = A x_k + w_k, y_k = x_k + v_k (G = C = I), one step per unit time.
struct Odelson {
  static constexpr const char* kName = "odelson";
  static constexpr const char* kDescription = "Odelson et al. 2006, 3-state example (test model)";
  static constexpr int kStateDim = 3;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 3> kStateNames = {"x1", "x2", "x3"};
  static constexpr std::array<const char*, 3> kStateUnits = {"-", "-", "-"};
  static constexpr std::array<bool, 3> kAngleStates = {false, false, false};
  static constexpr std::array<std::pair<int, int>, 0> kPositionRatePairs = {};
  struct Params {};
  static constexpr std::array<ParamSpec<Params>, 0> kParams = {};
  static Mat<3, 3> A() {
    return (Mat<3, 3>() << 0.1, 0.1, 0.1, 0.0, 0.2, 0.0, 0.0, 0.0, 0.3).finished();
  }
  template <class T>
  static Vec<T, 3> Step(const T& /*t*/, const Vec<T, 3>& x, double /*dt*/, double /*u*/,
                        const Params& /*p*/) {
    return A().template cast<T>() * x;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 3>&, const Params&) {
    return Vec<double, 0>();
  }
  struct All {
    static constexpr const char* kName = "all";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"y1", "y2", "y3"};
    static constexpr std::array<bool, 3> kAngleOutputs = {false, false, false};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 3>& x, const Params&) {
      return x;
    }
  };
  using Measurements = std::tuple<All>;
};
using O = Odelson;

const Vec<double, 3> kQTrue(0.5, 0.2, 0.1);
const Vec<double, 3> kRTrue(0.5, 0.2, 0.8);

FilterData SimulateOdelson(int samples, uint64_t seed) {
  Rng rng(seed);
  FilterData d;
  d.m = 3;
  d.path = "odelson-" + std::to_string(seed) + ".csv";
  Vec<double, 3> x = Vec<double, 3>::Zero();
  for (int k = 0; k < samples; ++k) {
    d.t.push_back(k);
    d.lines.push_back(k + 2);
    for (int i = 0; i < 3; ++i) d.z.push_back(x(i) + std::sqrt(kRTrue(i)) * rng.Normal());
    Vec<double, 3> w;
    for (int i = 0; i < 3; ++i) w(i) = std::sqrt(kQTrue(i)) * rng.Normal();
    x = O::A() * x + w;
  }
  return d;
}

// The deliberately suboptimal KF: Q0 = 0.01 I, R0 = 2 I.
FilterSpec WrongGainSpec() {
  FilterSpec spec;
  spec.measurement = "all";
  spec.filter = KfOptions{};
  spec.transition.integrator = Integrator::kDiscrete;
  spec.x0 = {0.0, 0.0, 0.0};
  spec.p0 = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  spec.q = {0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01};
  spec.r = {2, 0, 0, 0, 2, 0, 0, 0, 2};
  return spec;
}

TunerOptions AlsOptions(int lags) {
  TunerOptions o;
  o.estimator = Estimator::kAls;
  o.q_param = NoiseParam::kDiag;
  o.r_param = NoiseParam::kDiag;
  o.als_lags = lags;
  o.burn_in = 100;
  return o;
}

TEST(AlsOdelson, RecoversQAndRWithinThreeMonteCarloStandardErrors) {
  const FilterSpec spec = WrongGainSpec();
  const TunerOptions options = AlsOptions(15);
  constexpr int kRuns = 50;
  Eigen::Matrix<double, 6, kRuns> est;
  for (int run = 0; run < kRuns; ++run) {
    const std::vector<FilterData> data = {SimulateOdelson(5000, DeriveSeed({2006, uint64_t(run)}))};
    const TuneResult r = TuneWith<O, O::All>(spec, options, data);
    ASSERT_TRUE(r.IsSolutionUsable()) << r.message;
    for (int i = 0; i < 3; ++i) {
      est(i, run) = r.q[i * 3 + i];
      est(3 + i, run) = r.r[i * 3 + i];
    }
  }
  const char* names[6] = {"q1", "q2", "q3", "r1", "r2", "r3"};
  const double truth[6] = {kQTrue(0), kQTrue(1), kQTrue(2), kRTrue(0), kRTrue(1), kRTrue(2)};
  for (int i = 0; i < 6; ++i) {
    const double mean = est.row(i).mean();
    const double sd = std::sqrt((est.row(i).array() - mean).square().sum() / double(kRuns - 1));
    const double se = sd / std::sqrt(double(kRuns));
    std::printf("  %s: truth %.3f  ALS mean %.4f  sd %.4f  (mean - truth) / SE %+.2f\n", names[i],
                truth[i], mean, sd, (mean - truth[i]) / se);
    EXPECT_LE(std::abs(mean - truth[i]), 3.0 * se) << names[i];
    EXPECT_LT(sd, 0.5 * truth[i]) << names[i] << ": the estimate should be informative";
  }
}

// A precise sensor: the same data in units 10^4 times larger (every
// variance 1e-8 times as large), from the same start scaled alike, gives the
// same estimate scaled by 1e-8. ALS used to stop at its start on such data
// (residuals ~1e-9, gradient below the absolute tolerance), "converged".
TEST(AlsOdelson, ScaleFreeOnAPreciseSensor) {
  const TunerOptions options = AlsOptions(15);
  const FilterData data = SimulateOdelson(5000, 2026);
  const TuneResult ref = TuneWith<O, O::All>(WrongGainSpec(), options, {data});
  ASSERT_TRUE(ref.IsSolutionUsable()) << ref.message;
  constexpr double kScale = 1e-8;
  FilterData small = data;
  for (double& z : small.z) z *= std::sqrt(kScale);
  FilterSpec spec = WrongGainSpec();
  for (double& v : spec.q) v *= kScale;
  for (double& v : spec.r) v *= kScale;
  for (double& v : spec.p0) v *= kScale;
  const TuneResult r = TuneWith<O, O::All>(spec, options, {small});
  ASSERT_TRUE(r.IsSolutionUsable()) << r.message;
  EXPECT_GT(r.iterations, 1) << r.termination;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(r.q[i * 3 + i] / kScale, ref.q[i * 3 + i], 1e-6 * ref.q[i * 3 + i]) << "q" << i;
    EXPECT_NEAR(r.r[i * 3 + i] / kScale, ref.r[i * 3 + i], 1e-6 * ref.r[i * 3 + i]) << "r" << i;
  }
}

// Odelson's stationary autocovariances, written out by hand:
//   Abar = A - A L C,  P = Abar P Abar^T + G Q G^T + A L R L^T A^T,
//   C_0 = C P C^T + R,  C_j = C Abar^j P C^T - C Abar^(j-1) A L R.
TEST(AlsOdelson, ModelAutocovariancesEqualTheStationaryFormula) {
  const FilterSpec spec = WrongGainSpec();
  const FilterData d = SimulateOdelson(3000, 7);
  auto steps = als_internal::RecordFilter<O, O::All>(spec, d);
  ASSERT_EQ(steps.size(), 3000u);
  const Mat<3, 3> L = steps[1500].K;  // the gain has long converged
  const Mat<3, 3> A = O::A(), I = Mat<3, 3>::Identity();
  EXPECT_LT((steps[1500].H - I).norm(), 1e-10);  // H recovered from K S
  EXPECT_LT((steps[1500].F - A).norm(), 1e-10);  // F recovered from the cross-covariance
  const Mat<3, 3> Q = kQTrue.asDiagonal(), R = kRTrue.asDiagonal();
  const Mat<3, 3> Abar = A - A * L;
  Mat<3, 3> P = I;
  for (int it = 0; it < 500; ++it)
    P = Abar * P * Abar.transpose() + Q + A * L * R * L.transpose() * A.transpose();
  const int lags = 4, burn_in = 1000;
  steps[burn_in].P = P;  // start the recursion in the stationary state
  Eigen::VectorXd s = Eigen::VectorXd::Zero(lags * 9);
  als_internal::AddModelAutocov(
      steps, burn_in, lags, [&](double) { return Q; }, R, true, &s);
  const int count = int(steps.size()) - burn_in;
  Mat<3, 3> Abar_pow = I;
  for (int j = 0; j < lags; ++j) {
    const Mat<3, 3> expected =
        j == 0 ? Mat<3, 3>(P + R) : Mat<3, 3>(Abar_pow * Abar * P - Abar_pow * A * L * R);
    if (j > 0) Abar_pow = Abar_pow * Abar;
    const Mat<3, 3> got = Eigen::Map<const Mat<3, 3>>(s.data() + j * 9) / double(count - j);
    EXPECT_LT((got - expected).norm(), 1e-9 * expected.norm()) << "lag " << j << "\n"
                                                               << got << "\n"
                                                               << expected;
  }
}

TEST(AlsOdelson, ReportsWhatTheLagsIdentify) {
  const FilterSpec spec = WrongGainSpec();
  const std::vector<FilterData> data = {SimulateOdelson(2000, 11)};
  const TuneResult diag = TuneWith<O, O::All>(spec, AlsOptions(15), data);
  ASSERT_TRUE(diag.IsSolutionUsable()) << diag.message;
  ASSERT_FALSE(diag.identifiability.empty());
  EXPECT_NE(diag.identifiability[0].find("identifies q_x1, q_x2, q_x3, r_y1, r_y2, r_y3"),
            std::string::npos)
      << diag.identifiability[0];
  TunerOptions full = AlsOptions(1);
  full.q_param = NoiseParam::kFull;
  full.r_param = NoiseParam::kFull;
  const TuneResult f = TuneWith<O, O::All>(spec, full, data);
  bool blind = false;
  for (const std::string& s : f.identifiability) {
    std::printf("  lags 1, full Q and R: %s\n", s.c_str());
    blind = blind || s.find("does not see 6 of the 12 directions") != std::string::npos;
  }
  EXPECT_TRUE(blind);
}

TEST(AlsInput, RefusesOtherFiltersAndMissingRows) {
  std::vector<FilterData> data = {SimulateOdelson(500, 3)};
  FilterSpec ukf = WrongGainSpec();
  ukf.filter = SigmaPointOptions{};
  EXPECT_THROW((TuneWith<O, O::All>(ukf, AlsOptions(5), data)), InputError);
  data[0].z[3 * 200 + 1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((TuneWith<O, O::All>(WrongGainSpec(), AlsOptions(5), data)), InputError);
  TunerOptions zero = AlsOptions(0);
  std::string error;
  EXPECT_FALSE(zero.IsValid(&error));
}

}  // namespace
}  // namespace estlab
