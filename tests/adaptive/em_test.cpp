// Tests of EM for Q and R (adaptive/em.h, Estimator::kEm), against the
// likelihood tuner as the independent reference:
//   * linear model, KF, white-accel Q and R over 20 datasets: the exact
//     innovation NLL never rises from one EM iteration to the next, and EM's
//     Q, R equal the L-BFGS tuner's optimum to 1e-4 relative;
//   * diagonal Q with a full (correlated) R on two axes: the same;
//   * the pendulum with the EKF: EM's approximate E-step still lowers the
//     NLL, and the L-BFGS tuner from EM's solution is reported beside it;
//   * initial states (--estimate-x0) on the linear model with a correlated P0
//     and one state held: EM's x0 M-step reaches the L-BFGS tuner's optimum
//     in Q, R and x0 (shared over two datasets, and per file over three),
//     the NLL never rising; the prior after the first row is refused;
//   * rows with some components missing (diag, full, scalar R with a
//     correlated truth): EM's latent-z_U M-step reaches the L-BFGS
//     tuner's optimum;
//   * options that EM does not take are refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "adaptive/tuner_impl.h"
#include "models/pendulum.h"
#include "src/core/random.h"
#include "src/ode/transition_impl.h"  // MakeTransition for the test-only model
#include "tests/adaptive/constant_velocity.h"
#include "tests/adaptive/tuner_fixture.h"
#include "tests/error_text.h"

namespace estlab {
namespace {

using Cv = testing::ConstantVelocity<1>;
using Cv2 = testing::ConstantVelocity<2>;
using testing::Simulate;
using testing::WhiteAccel;

double RelDiff(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

// The largest rise of the NLL from one iteration to the next, relative to
// |NLL| (<= 0 when it never rises).
double WorstRise(const std::vector<double>& history) {
  double worst = -1e300;
  for (size_t i = 1; i < history.size(); ++i)
    worst = std::max(worst, (history[i] - history[i - 1]) / std::abs(history[i]));
  return worst;
}

// The largest |theta_EM - theta_ml| over theta's entries: absolute on the
// first `first_x0` (log-parameters), in ml's standard errors after them.
double ThetaGap(const TuneResult& e, const TuneResult& m, int first_x0) {
  double gap = 0.0;
  for (size_t i = 0; i < m.theta.size(); ++i) {
    const double d = std::abs(e.theta[i] - m.theta[i]);
    gap = std::max(gap, int(i) < first_x0 ? d : d / m.std_errors[i]);
  }
  return gap;
}

TEST(EmLinear, LikelihoodNeverFallsAndEmReachesTheLikelihoodTunersOptimum) {
  const double dt = 0.1, qc_true = 0.5, r_true = 0.04;
  const FilterSpec spec = testing::CvSpec(5.0, 1.0, KfOptions{});  // x10 and x25 off
  TunerOptions ml;
  ml.q_param = NoiseParam::kWhiteAccel;
  ml.r_param = NoiseParam::kDiag;
  TunerOptions em = ml;
  em.estimator = Estimator::kEm;
  em.em_tolerance = 1e-12;
  em.max_iterations = 5000;
  double worst_rise = -1e300, worst_gap = 0.0, worst_nll_gap = 0.0;
  int iterations = 0;
  for (int d = 0; d < 20; ++d) {
    const std::vector<FilterData> data = {Simulate<Cv, Cv::Positions>(
        Integrator::kEuler, Vec<double, 2>(0.0, 1.0), dt, 300, WhiteAccel<Cv>(qc_true, dt),
        Mat<1, 1>::Constant(r_true), DeriveSeed({21, uint64_t(d)}))};
    const TuneResult e = TuneWith<Cv, Cv::Positions>(spec, em, data);
    const TuneResult m = TuneWith<Cv, Cv::Positions>(spec, ml, data);
    ASSERT_EQ(e.status, TuneStatus::kConverged) << e.message << " " << e.termination;
    ASSERT_EQ(m.status, TuneStatus::kConverged) << m.message;
    ASSERT_EQ(e.nll_history.size(), size_t(e.iterations) + 1);
    EXPECT_EQ(e.nll_increases, 0);
    worst_rise = std::max(worst_rise, WorstRise(e.nll_history));
    const double gap = std::max(RelDiff(e.qc, m.qc), RelDiff(e.r[0], m.r[0]));
    worst_gap = std::max(worst_gap, gap);
    worst_nll_gap = std::max(worst_nll_gap, e.nll_tuned - m.nll_tuned);
    iterations = std::max(iterations, e.iterations);
    EXPECT_LT(gap, 1e-4) << "dataset " << d << ": EM qc " << e.qc << " R " << e.r[0] << ", ml qc "
                         << m.qc << " R " << m.r[0];
    EXPECT_LE(std::abs(e.nll_ml_from_em - m.nll_tuned), 1e-6 * std::abs(m.nll_tuned));
  }
  std::printf(
      "  20 datasets: worst relative NLL rise %.3g, worst |EM - ml| / ml of qc, R %.3g, "
      "NLL(EM) - NLL(ml) <= %.3g, iterations <= %d\n",
      worst_rise, worst_gap, worst_nll_gap, iterations);
  EXPECT_LE(worst_rise, 1e-11);  // rounding of a sum of 300 terms
}

// The KF on two constant-velocity axes, positions measured, from x0 =
// (0, 1, 0, -0.5) with P0 = I and a diagonal Q and R as the initial guess.
FilterSpec TwoAxisSpec() {
  FilterSpec spec;
  spec.measurement = "positions";
  spec.filter = KfOptions{};
  spec.transition.integrator = Integrator::kEuler;
  spec.x0 = {0.0, 1.0, 0.0, -0.5};
  spec.p0 = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  spec.q = {1e-3, 0, 0, 0, 0, 0.1, 0, 0, 0, 0, 1e-3, 0, 0, 0, 0, 0.1};
  spec.r = {0.2, 0.0, 0.0, 0.2};
  return spec;
}

TEST(EmLinear, DiagonalQAndCorrelatedFullR) {
  const double dt = 0.1;
  Mat<4, 4> Q = Vec<double, 4>(0.01, 0.01, 0.02, 0.02).asDiagonal();
  Mat<2, 2> R;
  R << 0.04, 0.018, 0.018, 0.09;  // correlation 0.3
  const FilterSpec spec = TwoAxisSpec();
  const std::vector<FilterData> data = {Simulate<Cv2, Cv2::Positions>(
      Integrator::kEuler, Vec<double, 4>(0.0, 1.0, 0.0, -0.5), dt, 3000, Q, R, 77)};
  TunerOptions ml;
  ml.q_param = NoiseParam::kDiag;
  ml.r_param = NoiseParam::kFull;
  TunerOptions em = ml;
  em.estimator = Estimator::kEm;
  em.em_tolerance = 1e-12;
  em.max_iterations = 20000;
  const TuneResult e = TuneWith<Cv2, Cv2::Positions>(spec, em, data);
  const TuneResult m = TuneWith<Cv2, Cv2::Positions>(spec, ml, data);
  ASSERT_TRUE(e.IsSolutionUsable()) << e.message;
  ASSERT_EQ(m.status, TuneStatus::kConverged) << m.message;
  EXPECT_EQ(e.nll_increases, 0);
  EXPECT_LE(WorstRise(e.nll_history), 1e-11);
  double gap = 0.0;
  for (int i = 0; i < 4; ++i) gap = std::max(gap, RelDiff(e.q[i * 4 + i], m.q[i * 4 + i]));
  for (int i = 0; i < 4; ++i) gap = std::max(gap, RelDiff(e.r[i], m.r[i]));
  double per_iteration = 0.0;
  for (double s : e.iteration_wall_s) per_iteration += s;
  per_iteration /= std::max<size_t>(1, e.iteration_wall_s.size());
  for (int i = 0; i < 4; ++i)
    std::printf("  q%d EM %.6g ml %.6g\n", i, e.q[i * 4 + i], m.q[i * 4 + i]);
  for (int i = 0; i < 4; ++i) std::printf("  r%d EM %.6g ml %.6g\n", i, e.r[i], m.r[i]);
  std::printf("  NLL EM %.6f ml %.6f ml-from-EM %.6f\n", e.nll_tuned, m.nll_tuned,
              e.nll_ml_from_em);
  std::printf("  diag Q, full R: %d EM iterations (%.2f ms each), worst relative gap to ml %.3g\n",
              e.iterations, 1e3 * per_iteration, gap);
  EXPECT_LT(gap, 1e-4);
}

// Rows with some components missing (issue 35): the missing z_U are
// latent, B_k = T E[e e^T] T^T + [0 0; 0 R_UU - G R_OU] with G = R_UO R_OO^-1
// (adaptive/em.h). With a correlated R (0.6) the carried G term matters for
// the full R: EM reaches the likelihood tuner's optimum (which updates with
// the observed components) only if B_k is right. Each component is missing
// in about a third of the rows, both in about a tenth (no update there).
TEST(EmMissing, PartialRowsReachTheLikelihoodTunersOptimum) {
  const double dt = 0.1;
  const Mat<4, 4> Q = Vec<double, 4>(0.01, 0.01, 0.02, 0.02).asDiagonal();
  Mat<2, 2> R;
  R << 0.04, 0.036, 0.036, 0.09;
  FilterData data = Simulate<Cv2, Cv2::Positions>(
      Integrator::kEuler, Vec<double, 4>(0.0, 1.0, 0.0, -0.5), dt, 1200, Q, R, 91);
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  Rng rng(92);
  long partial = 0, empty = 0;
  for (size_t k = 0; k < data.t.size(); ++k) {
    const bool miss0 = rng.Uniform() < 0.33, miss1 = rng.Uniform() < 0.33;
    if (miss0) data.z[2 * k] = kNaN;
    if (miss1) data.z[2 * k + 1] = kNaN;
    partial += miss0 != miss1;
    empty += miss0 && miss1;
  }
  ASSERT_GT(partial, 400);
  ASSERT_GT(empty, 60);
  const FilterSpec spec = TwoAxisSpec();
  for (const NoiseParam r_param : {NoiseParam::kFull, NoiseParam::kDiag, NoiseParam::kScalar}) {
    TunerOptions ml;
    ml.q_param = NoiseParam::kDiag;
    ml.r_param = r_param;
    TunerOptions em = ml;
    em.estimator = Estimator::kEm;
    em.em_tolerance = 1e-13;
    em.max_iterations = 20000;
    const TuneResult e = TuneWith<Cv2, Cv2::Positions>(spec, em, {data});
    const TuneResult m = TuneWith<Cv2, Cv2::Positions>(spec, ml, {data});
    SCOPED_TRACE(std::string("R ") + NoiseParamName(r_param));
    ASSERT_TRUE(e.IsSolutionUsable()) << e.message << " " << e.termination;
    ASSERT_EQ(m.status, TuneStatus::kConverged) << m.message;
    ASSERT_EQ(e.theta.size(), m.theta.size());
    EXPECT_EQ(e.nll_increases, 0);
    EXPECT_LE(WorstRise(e.nll_history), 1e-11);
    const double gap = ThetaGap(e, m, int(m.theta.size()));
    std::printf(
        "  R %s, %ld partial and %ld empty rows of 1200: %d EM iterations, NLL EM %.9f ml "
        "%.9f, largest theta gap %.3g\n",
        NoiseParamName(r_param), partial, empty, e.iterations, e.nll_tuned, m.nll_tuned, gap);
    EXPECT_LT(gap, 1e-4);
    EXPECT_LE(std::abs(e.nll_tuned - m.nll_tuned), 1e-8 * std::abs(m.nll_tuned));
  }
}

TEST(EmPendulum, ApproximateEStepLowersTheNllAndReportsTheMlOptimumBeside) {
  using P = models::Pendulum;
  const double dt = 0.01;
  const std::vector<FilterData> data = {
      Simulate<P, P::Sin>(Integrator::kRk4, Vec<double, 2>(testing::kPi / 4, 0.0), dt, 1000,
                          Vec<double, 2>(1e-6, 1e-4).asDiagonal(), Mat<1, 1>::Constant(0.01), 5)};
  FilterSpec spec;
  spec.measurement = "sin";
  spec.filter = EkfOptions{};
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = {testing::kPi / 4, 0.0};
  spec.p0 = {1e-4, 0.0, 0.0, 1e-4};
  spec.q = {1e-4, 0.0, 0.0, 1e-2};
  spec.r = {1.0};
  TunerOptions em;
  em.estimator = Estimator::kEm;
  em.q_param = NoiseParam::kDiag;
  em.r_param = NoiseParam::kDiag;
  em.max_iterations = 300;
  em.em_tolerance = 1e-7;
  const TuneResult e = TuneWith<P, P::Sin>(spec, em, data);
  ASSERT_TRUE(e.IsSolutionUsable()) << e.message;
  std::printf("  pendulum EKF: NLL %.4f -> EM %.4f (%d iterations, %d rises), ml from EM %.4f\n",
              e.nll_initial, e.nll_tuned, e.iterations, e.nll_increases, e.nll_ml_from_em);
  EXPECT_LT(e.nll_tuned, e.nll_initial - 100.0);
  ASSERT_TRUE(std::isfinite(e.nll_ml_from_em));
  EXPECT_LE(e.nll_ml_from_em, e.nll_tuned + 1e-9);
  EXPECT_NEAR(e.r[0], 0.01, 0.003);  // R is well identified
}

// EM's E-step reads the smoother's typed moments (SmoothedMoments), no row
// columns: they are the numbers `estlab smooth --full-cov` writes, column by
// column, for the ERTS and the sigma-point RTS, on a record with a skipped
// measurement; the last row's lag-one is NaN.
TEST(EmMoments, TypedMomentsAreTheSmoothFullCovColumns) {
  using P = models::Pendulum;
  std::vector<FilterData> data = {
      Simulate<P, P::Sin>(Integrator::kRk4, Vec<double, 2>(testing::kPi / 4, 0.0), 0.01, 200,
                          Vec<double, 2>(1e-6, 1e-4).asDiagonal(), Mat<1, 1>::Constant(0.01), 9)};
  data[0].z[50] = std::numeric_limits<double>::quiet_NaN();  // a skipped sample
  for (const FilterKindOptions& kind :
       {FilterKindOptions{EkfOptions{}},
        FilterKindOptions{DefaultFilterOptions(FilterKind::kUkf)}}) {
    FilterSpec spec;
    spec.measurement = "sin";
    spec.filter = kind;
    spec.transition.integrator = Integrator::kRk4;
    spec.x0 = {testing::kPi / 4, 0.0};
    spec.p0 = {1e-4, 0.0, 0.0, 1e-4};
    spec.q = {1e-6, 0.0, 0.0, 1e-4};
    spec.r = {0.01};
    spec.smooth = true;
    std::vector<SmoothedMoments<2>> moments;
    const FilterRunOutput typed = RunFilterWith<P, P::Sin>(spec, data[0], &moments);
    spec.full_cov = true;
    const FilterRunOutput columns = RunFilterWith<P, P::Sin>(spec, data[0]);
    ASSERT_TRUE(typed.summary.ok) << typed.summary.message;
    ASSERT_EQ(moments.size(), columns.rows.size());
    auto col = [&](const std::string& name) {
      return size_t(std::find(columns.columns.begin(), columns.columns.end(), name) -
                    columns.columns.begin());
    };
    const size_t x0 = col("theta_est"), x1 = col("omega_est"), v0 = col("theta_var"),
                 v1 = col("omega_var"), c01 = col("cov_theta_omega"), l00 = col("lag1_theta_theta"),
                 l01 = col("lag1_theta_omega"), l10 = col("lag1_omega_theta"),
                 l11 = col("lag1_omega_omega");
    ASSERT_LT(l11, columns.columns.size());
    for (size_t k = 0; k < moments.size(); ++k) {
      const std::vector<double>& r = columns.rows[k];
      const SmoothedMoments<2>& m = moments[k];
      EXPECT_EQ(m.x(0), r[x0]) << k;
      EXPECT_EQ(m.x(1), r[x1]) << k;
      EXPECT_EQ(m.P(0, 0), r[v0]) << k;
      EXPECT_EQ(m.P(1, 1), r[v1]) << k;
      EXPECT_EQ(m.P(0, 1), r[c01]) << k;
      if (k + 1 < moments.size()) {
        EXPECT_EQ(m.lag_one(0, 0), r[l00]) << k;
        EXPECT_EQ(m.lag_one(0, 1), r[l01]) << k;
        EXPECT_EQ(m.lag_one(1, 0), r[l10]) << k;
        EXPECT_EQ(m.lag_one(1, 1), r[l11]) << k;
      } else {
        EXPECT_TRUE(std::isnan(m.lag_one(0, 0)) && std::isnan(r[l00]));
      }
    }
  }
}

// x0's M-step, mu_S = x^s_0,S + L_SS^-1 L_SS' (x^s_0,S' - mu_S'): with a
// correlated P0 and v2 held at a wrong value the correction term matters,
// so EM reaches the likelihood optimum only if it is right.
TEST(EmLinear, InitialStatesReachTheLikelihoodTunersOptimum) {
  const double dt = 0.1;
  const Mat<4, 4> Q = WhiteAccel<Cv2>(0.5, dt);
  const Mat<2, 2> R = Vec<double, 2>(0.04, 0.04).asDiagonal();
  FilterSpec spec;
  spec.measurement = "positions";
  spec.filter = KfOptions{};
  spec.transition.integrator = Integrator::kEuler;
  spec.x0 = {0.0, 0.0, 0.0, 0.3};  // v2 held, not its truth
  Mat<4, 4> P0;
  P0 << 0.2, 0.06, 0.0, 0.08,  //
      0.06, 0.2, 0.0, 0.0,     //
      0.0, 0.0, 0.2, 0.04,     //
      0.08, 0.0, 0.04, 0.2;
  spec.p0.assign(P0.data(), P0.data() + 16);
  spec.q_white_accel = true;
  spec.qc = 2.0;
  spec.r = {0.2, 0.0, 0.0, 0.2};
  TunerOptions ml;
  ml.q_param = NoiseParam::kWhiteAccel;
  ml.r_param = NoiseParam::kDiag;
  ml.estimate_x0 = {"p1", "v1", "p2"};
  TunerOptions em = ml;
  em.estimator = Estimator::kEm;
  em.em_tolerance = 1e-13;
  em.max_iterations = 20000;
  const Vec<double, 4> truth[3] = {
      {1.0, -0.5, 2.0, -0.5}, {-1.5, 0.8, 0.5, -0.5}, {0.4, 0.0, -2.0, -0.5}};
  for (const bool per_file : {false, true}) {
    std::vector<FilterData> data;
    for (int d = 0; d < (per_file ? 3 : 2); ++d)
      data.push_back(Simulate<Cv2, Cv2::Positions>(Integrator::kEuler, truth[per_file ? d : 0], dt,
                                                   200, Q, R, DeriveSeed({57, uint64_t(d)})));
    ml.x0_per_file = em.x0_per_file = per_file;
    const TuneResult e = TuneWith<Cv2, Cv2::Positions>(spec, em, data);
    const TuneResult m = TuneWith<Cv2, Cv2::Positions>(spec, ml, data);
    ASSERT_EQ(e.status, TuneStatus::kConverged) << e.message << " " << e.termination;
    ASSERT_EQ(m.status, TuneStatus::kConverged) << m.message;
    ASSERT_EQ(e.theta.size(), m.theta.size());
    ASSERT_EQ(e.x0.size(), per_file ? 3u : 1u);
    EXPECT_EQ(e.nll_increases, 0);
    EXPECT_LE(WorstRise(e.nll_history), 1e-11);
    const double gap = ThetaGap(e, m, 3);
    std::printf(
        "  %s: %d EM iterations, NLL EM %.9f ml %.9f, largest gap %.3g "
        "(log-parameters; x0 in ml's SE)\n",
        per_file ? "x0 per file (3)" : "x0 shared (2 files)", e.iterations, e.nll_tuned,
        m.nll_tuned, gap);
    EXPECT_LT(gap, 1e-3);
    EXPECT_LE(std::abs(e.nll_tuned - m.nll_tuned), 1e-7 * std::abs(m.nll_tuned));
    for (size_t row = 0; row < e.x0.size(); ++row)
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(e.x0[row][i], e.theta[3 + 3 * row + i]);
        EXPECT_LE(std::abs(e.x0[row][i] - truth[per_file ? row : 0](i)),
                  4 * e.x0_std_errors[row][i])
            << "row " << row << " " << e.x0_names[i];
      }
    EXPECT_EQ(e.x0[0][3], 0.3);  // held
  }
  // The prior before the first row: x^s_0 is not x(t_0).
  std::vector<FilterData> data = {
      Simulate<Cv2, Cv2::Positions>(Integrator::kEuler, truth[0], dt, 50, Q, R, 3)};
  for (double& t : data[0].t) t += 0.5;
  FilterSpec late = spec;
  late.has_t0 = true;
  late.t0 = 0.0;
  em.x0_per_file = false;
  const std::string error =
      testing::ErrorText([&] { TuneWith<Cv2, Cv2::Positions>(late, em, data); });
  EXPECT_NE(error.find("--estimate-x0 with the em estimator needs the prior at the first row (t0 0 "
                       "is before the first row, t = 0.5)"),
            std::string::npos)
      << error;
}

// A filter that fails at the initial guess (a gap of 1e6 s in the record: the
// EKF's RK4 step overflows) ends EM with the step and the time where it
// failed (issue 40, item 19: it said "stopped at iteration 1" and no more).
TEST(EmInput, AFailureAtTheInitialGuessNamesTheStepAndTime) {
  using P = models::Pendulum;
  std::vector<FilterData> data = {
      Simulate<P, P::Sin>(Integrator::kRk4, Vec<double, 2>(testing::kPi / 4, 0.0), 0.01, 50,
                          Vec<double, 2>(1e-6, 1e-4).asDiagonal(), Mat<1, 1>::Constant(0.01), 7)};
  for (size_t k = 20; k < data[0].t.size(); ++k) data[0].t[k] += 1e6;
  FilterSpec spec;
  spec.measurement = "sin";
  spec.filter = EkfOptions{};
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = {testing::kPi / 4, 0.0};
  spec.p0 = {1e-4, 0.0, 0.0, 1e-4};
  spec.q = {1e-4, 0.0, 0.0, 1e-2};
  spec.r = {0.01};
  TunerOptions em;
  em.estimator = Estimator::kEm;
  em.q_param = NoiseParam::kDiag;
  em.r_param = NoiseParam::kDiag;
  const TuneResult e = TuneWith<P, P::Sin>(spec, em, data);
  EXPECT_FALSE(e.IsSolutionUsable());
  EXPECT_EQ(e.status, TuneStatus::kAllStartsFailed);
  EXPECT_NE(e.message.find("initial guess"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("at step 20"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("(t = 1"), std::string::npos) << e.message;
}

TEST(EmInput, OptionsEmDoesNotTakeAreRefused) {
  TunerOptions em;
  em.estimator = Estimator::kEm;
  std::string error;
  EXPECT_TRUE(em.IsValid(&error)) << error;
  TunerOptions burn = em;
  burn.burn_in = 5;
  EXPECT_FALSE(burn.IsValid(&error));
  EXPECT_NE(error.find("burn-in"), std::string::npos) << error;
  TunerOptions starts = em;
  starts.starts = 3;
  EXPECT_FALSE(starts.IsValid(&error));
  TunerOptions phys = em;
  phys.estimate.push_back({.name = "L"});
  EXPECT_FALSE(phys.IsValid(&error));
  TunerOptions tol = em;
  tol.em_tolerance = -1.0;
  EXPECT_FALSE(tol.IsValid(&error));
}

}  // namespace
}  // namespace estlab
