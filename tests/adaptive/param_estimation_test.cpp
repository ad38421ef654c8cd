// Physical parameters estimated with Q and R (TunerOptions::estimate,
// adaptive/physical_params.h) and the observed-Fisher report
// (adaptive/identifiability.h):
//   * the AD gradient with respect to L, b, g and the noise against central
//     differences of the double NLL (EKF, IEKF, UKF, CKF; with a prior);
//   * 50 simulated pendulum datasets (2000 steps) with known L, b, qc, R: every estimate
//     within 2 SE of the truth in >= 90 % of them, NLL(estimate) <=
//     NLL(truth) in all;
//   * g and L together: reported as not separately identifiable, g/L named
//     and estimated;
//   * AnalyseFisher on hand-made Hessians with known answers;
//   * the option parser's errors;
//   * initial states as parameters (--estimate-x0): the NLL equals the
//     spec's with that x0 written in (per file: the sum over the files),
//     AD gradients in x0 (EKF, UKF, CVODES), a tuned x0 against the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "adaptive/identifiability.h"
#include "adaptive/likelihood.h"
#include "adaptive/tuner.h"
#include "adaptive/tuner_impl.h"
#include "models/pendulum.h"
#include "src/core/types.h"
#include "src/options/estimate_flags.h"
#include "tests/adaptive/tuner_fixture.h"
#include "tests/error_text.h"

namespace estlab {
namespace {

using P = models::Pendulum;
using testing::CheckGradient;
using testing::Simulate;
using testing::WhiteAccel;

// The simulated truth: a damped pendulum, angle measured.
constexpr double kG = 9.81, kL = 0.5, kB = 0.3, kQc = 0.1, kR = 1e-3, kDt = 0.01;

FilterData PendulumData(uint64_t seed, int steps, double g = kG) {
  P::Params p;
  p.g = g;
  p.L = kL;
  p.b = kB;
  return Simulate<P, P::Angle>(Integrator::kRk4, Vec<double, 2>(1.2, 0.0), kDt, steps,
                               WhiteAccel<P>(kQc, kDt), Mat<1, 1>::Constant(kR), seed, p);
}

// The filter starts from nominal L = 0.8, b = 0.1 and noise 10x off.
FilterSpec Spec(FilterKindOptions filter) {
  FilterSpec spec;
  spec.params = {kG, 0.8, 0.1};
  spec.measurement = "angle";
  spec.filter = filter;
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = {1.2, 0.0};
  spec.p0 = {1e-2, 0.0, 0.0, 1e-2};
  spec.q_white_accel = true;
  spec.qc = 1e-2;
  spec.r = {1e-2};
  return spec;
}

TunerOptions Options(std::vector<std::string> names) {
  TunerOptions o;
  o.q_param = NoiseParam::kWhiteAccel;
  o.r_param = NoiseParam::kDiag;
  for (const std::string& n : names) o.estimate.push_back(EstimatedParam{.name = n});
  return o;
}

TEST(ParamGradient, MatchesCentralDifferencesForEveryGaussianFilter) {
  const std::vector<FilterData> data = {PendulumData(7, 300)};
  TunerOptions options = Options({"L", "b", "g"});
  options.estimate[0].has_prior = true;  // the prior's term is differentiated too
  options.estimate[0].prior_mean = 0.6;
  options.estimate[0].prior_sd = 0.05;
  const std::vector<std::pair<FilterKindOptions, const char*>> filters = {
      {EkfOptions{}, "ekf"},
      {EkfOptions{.iterations = 3}, "iekf"},
      {SigmaPointOptions{.rule = SigmaRule::kUnscented, .alpha = 0.5}, "ukf"},
      {SigmaPointOptions{.rule = SigmaRule::kCubature}, "ckf"}};
  uint64_t seed = 50;
  for (const auto& [filter, label] : filters) {
    const InnovationLikelihood<P, P::Angle> lik(Spec(filter), options, data);
    ASSERT_EQ(lik.NumParams(), 5);
    EXPECT_EQ(lik.ParamNames()[2], "log L");
    EXPECT_EQ(lik.ParamNames()[3], "b");
    EXPECT_EQ(lik.ParamNames()[4], "log g");
    CheckGradient(lik, seed++, label);
  }
}

// --integrator cvodes: the gradient from CVODES forward sensitivities in
// theta (src/ode/cvodes_theta_flow.h: the state's and, for the EKF, the
// variational system's) against central differences of the double NLL,
// which steps the separate CvodesTransition. At rtol 1e-12 that NLL still
// moves by ~1e-8 when CVODES changes its steps, so second-order differences
// with h = 1e-5 are off by up to 8e-6 relative; the fourth-order stencil with
// h = 1e-3 is not (its noise term ~1.5e-5 absolute).
TEST(ParamGradient, CvodesSensitivitiesMatchCentralDifferences) {
  const std::vector<FilterData> data = {PendulumData(8, 200)};
  TunerOptions options = Options({"L", "b", "g"});
  const std::vector<std::pair<FilterKindOptions, const char*>> filters = {
      {EkfOptions{}, "ekf"}, {SigmaPointOptions{.rule = SigmaRule::kCubature}, "ckf"}};
  uint64_t seed = 70;
  for (const auto& [filter, label] : filters) {
    FilterSpec spec = Spec(filter);
    spec.transition.integrator = Integrator::kCvodes;
    spec.transition.rtol = 1e-12;
    spec.transition.atol = 1e-14;
    const InnovationLikelihood<P, P::Angle> lik(spec, options, data);
    ASSERT_TRUE(lik.UsesCvodes());
    CheckGradient(lik, seed++, label, {.h = 1e-3, .fourth_order = true});
  }
}

TEST(ParamEstimation, FiftyDatasetsCoverTheTruthAndBeatItsNll) {
  const FilterSpec spec = Spec(EkfOptions{});
  const TunerOptions options = Options({"L", "b"});
  const double truth[4] = {std::log(kQc), std::log(kR), std::log(kL), kB};
  const char* names[4] = {"log qc", "log r", "log L", "b"};
  int within[4] = {0, 0, 0, 0}, nll_ok = 0;
  double mean_z[4] = {0, 0, 0, 0}, mean_z2[4] = {0, 0, 0, 0};
  const int datasets = 50;
  for (int d = 0; d < datasets; ++d) {
    const std::vector<FilterData> data = {PendulumData(DeriveSeed({61, uint64_t(d)}), 2000)};
    const TuneResult r = TuneWith<P, P::Angle>(spec, options, data);
    ASSERT_TRUE(r.IsSolutionUsable()) << r.message;
    ASSERT_EQ(r.theta.size(), 4u);
    ASSERT_TRUE(r.hessian_positive_definite) << d;
    for (int i = 0; i < 4; ++i) {
      within[i] += std::abs(r.theta[i] - truth[i]) <= 2.0 * r.std_errors[i];
      const double z = (r.theta[i] - truth[i]) / r.std_errors[i];
      mean_z[i] += z / datasets;
      mean_z2[i] += z * z / datasets;
    }
    const InnovationLikelihood<P, P::Angle> lik(spec, options, data);
    double nll_true = 0.0;
    ASSERT_TRUE(lik.Nll(truth, &nll_true));
    nll_ok += r.nll_tuned <= nll_true + 1e-9;
    // The natural-scale report: L = e^theta, SE_L = L SE_log L; b itself.
    EXPECT_DOUBLE_EQ(r.param_values[0], std::exp(r.theta[2]));
    EXPECT_DOUBLE_EQ(r.param_std_errors[0], r.param_values[0] * r.std_errors[2]);
    EXPECT_DOUBLE_EQ(r.param_values[1], r.theta[3]);
    EXPECT_DOUBLE_EQ(r.tuned_spec.params[1], r.param_values[0]);
    EXPECT_DOUBLE_EQ(r.tuned_spec.params[2], r.param_values[1]);
    if (d < 5) {
      std::printf(
          "  dataset %d: L %.4f +- %.4f  b %.4f +- %.4f  qc %.4f  R %.3g  NLL - true %.3f\n", d,
          r.param_values[0], r.param_std_errors[0], r.param_values[1], r.param_std_errors[1], r.qc,
          r.r[0], r.nll_tuned - nll_true);
    }
  }
  for (int i = 0; i < 4; ++i) {
    // z = (estimate - truth) / SE: rms z near 1 says the SEs are honest.
    std::printf("  %-6s within 2 SE of the truth: %d / %d, mean z %+.2f, rms z %.2f\n", names[i],
                within[i], datasets, mean_z[i], std::sqrt(mean_z2[i]));
    EXPECT_GE(within[i], 45) << names[i];  // >= 90 %
  }
  std::printf("  NLL(estimate) <= NLL(truth): %d / %d\n", nll_ok, datasets);
  EXPECT_EQ(nll_ok, datasets);
}

TEST(ParamEstimation, GAndLTogetherAreReportedAsOnlyTheirRatio) {
  const std::vector<FilterData> data = {PendulumData(71, 1500)};
  const TuneResult r = TuneWith<P, P::Angle>(Spec(EkfOptions{}), Options({"g", "L", "b"}), data);
  ASSERT_TRUE(r.IsSolutionUsable()) << r.message;
  EXPECT_FALSE(r.hessian_positive_definite);
  ASSERT_EQ(r.param_names, (std::vector<std::string>{"g", "L", "b"}));
  EXPECT_TRUE(std::isinf(r.param_std_errors[0]));
  EXPECT_TRUE(std::isinf(r.param_std_errors[1]));
  EXPECT_TRUE(std::isfinite(r.param_std_errors[2]));
  ASSERT_EQ(r.identifiability.size(), 1u);
  const std::string& s = r.identifiability[0];
  EXPECT_NE(s.find("g and L are not separately identifiable"), std::string::npos) << s;
  EXPECT_NE(s.find("only g/L = "), std::string::npos) << s;
  // The combination itself is estimated, with a finite SE in the sentence.
  const double ratio = r.param_values[0] / r.param_values[1];
  EXPECT_NEAR(ratio, kG / kL, 0.03 * kG / kL) << s;
  EXPECT_NE(s.find("g/L = " + FormatNumber(ratio) + " (SE "), std::string::npos) << s;
  EXPECT_EQ(s.find("SE inf"), std::string::npos) << s;
  // The NLL is a function of g/L alone here: g and L scaled together leave it.
  const InnovationLikelihood<P, P::Angle> lik(Spec(EkfOptions{}), Options({"g", "L", "b"}), data);
  std::vector<double> shifted = r.theta;
  shifted[2] += 0.3;
  shifted[3] += 0.3;
  double a = 0.0, b = 0.0;
  ASSERT_TRUE(lik.Nll(r.theta.data(), &a) && lik.Nll(shifted.data(), &b));
  EXPECT_NEAR(a, b, 1e-8 * std::abs(a));
}

// H = c w w^T on (log g, log L) with w = (1, -1) (the NLL sees log g - log
// L only), and 4 on an independent third parameter.
TEST(Fisher, FlatDirectionNamesTheRatioWithItsStandardError) {
  const double c = 25.0;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(3, 3);
  H(0, 0) = H(1, 1) = c;
  H(0, 1) = H(1, 0) = -c;
  H(2, 2) = 4.0;
  const std::vector<double> theta = {std::log(9.81), std::log(0.5), 0.3};
  const FisherReport r = AnalyseFisher(H, theta, {"log g", "log L", "b"}, {true, true, false});
  EXPECT_FALSE(r.positive_definite);
  EXPECT_TRUE(std::isinf(r.std_errors[0]) && std::isinf(r.std_errors[1]));
  EXPECT_DOUBLE_EQ(r.std_errors[2], 0.5);
  EXPECT_TRUE(std::isnan(r.correlation[0 * 3 + 1]));
  EXPECT_DOUBLE_EQ(r.correlation[2 * 3 + 2], 1.0);
  ASSERT_EQ(r.sentences.size(), 1u);
  // w^T H^+ w = 1 / c: SE(log g/L) = 1 / sqrt(c), SE(g/L) = (g/L) / sqrt(c).
  const double ratio = 9.81 / 0.5;
  EXPECT_NE(r.sentences[0].find("only g/L = " + FormatNumber(ratio) + " (SE " +
                                FormatNumber(ratio / std::sqrt(c)) + ")"),
            std::string::npos)
      << r.sentences[0];
}

// A natural-scale parameter that ended at 0 (a laminar outflow at its
// bound) with a curvature the data fix: measured in its own units, s_i =
// |theta_i| ~ 1e-12 would shrink its scaled curvature to 1e-22 and call it
// flat. Measured in the units of its start (0.1) it is determined, with
// SE = 1 / sqrt(H_bb) from H^-1.
TEST(Fisher, ParameterThatEndedNearZeroIsMeasuredInTheUnitsOfItsStart) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(2, 2);
  H(0, 0) = 4.0;
  H(1, 1) = 100.0;
  const std::vector<double> theta = {std::log(0.2), 1e-12}, start = {std::log(0.3), 0.1};
  const FisherReport without = AnalyseFisher(H, theta, {"log r", "l1"}, {true, false});
  EXPECT_TRUE(std::isinf(without.std_errors[1]));  // the false "not identifiable"
  const FisherReport r = AnalyseFisher(H, theta, {"log r", "l1"}, {true, false}, start);
  EXPECT_TRUE(r.positive_definite);
  EXPECT_TRUE(r.sentences.empty());
  EXPECT_DOUBLE_EQ(r.std_errors[0], 0.5);
  EXPECT_NEAR(r.std_errors[1], 0.1, 1e-15);
  // One that moved far but stayed away from 0 keeps its own units (in the
  // start's, its curvature 1e12 would make log r look flat): the same SEs
  // as H^-1, nothing flat.
  Eigen::MatrixXd Hf = H;
  Hf(1, 1) = 1e12;  // l1 = 1e-4 +- 1e-6, started at 1
  const FisherReport far =
      AnalyseFisher(Hf, {std::log(0.2), 1e-4}, {"log r", "l1"}, {true, false}, {0.0, 1.0});
  EXPECT_TRUE(far.positive_definite);
  EXPECT_DOUBLE_EQ(far.std_errors[0], 0.5);
  EXPECT_NEAR(far.std_errors[1], 1e-6, 1e-20);
  // A parameter the data do not touch is flat whatever its start.
  H(1, 1) = 0.0;
  EXPECT_TRUE(
      std::isinf(AnalyseFisher(H, theta, {"log r", "l1"}, {true, false}, start).std_errors[1]));
}

TEST(Fisher, ProductAndSingleFlatParameterAndNegativeCurvature) {
  // The NLL sees log m + log a (m * a): the flat direction is (1, -1).
  Eigen::MatrixXd H = Eigen::MatrixXd::Constant(2, 2, 9.0);
  FisherReport r = AnalyseFisher(H, {0.0, 0.0}, {"log m2", "log a2"}, {true, true});
  ASSERT_EQ(r.sentences.size(), 1u);
  // w = (1, 1) along the eigenvalue 18 of H: w^T H^+ w = 2 / 18, SE 1/3.
  EXPECT_NE(r.sentences[0].find("only m2*a2 = 1 (SE 0.333333)"), std::string::npos)
      << r.sentences[0];
  // One parameter the data do not touch at all.
  H = Eigen::MatrixXd::Zero(2, 2);
  H(0, 0) = 1.0;
  r = AnalyseFisher(H, {0.0, 0.0}, {"log qc", "b"}, {true, false});
  ASSERT_EQ(r.sentences.size(), 1u);
  EXPECT_NE(r.sentences[0].find("do not determine b"), std::string::npos) << r.sentences[0];
  EXPECT_DOUBLE_EQ(r.std_errors[0], 1.0);
  EXPECT_TRUE(std::isinf(r.std_errors[1]));
  // A saddle: never an SE without a reason.
  H(1, 1) = -0.5;
  r = AnalyseFisher(H, {0.0, 0.0}, {"log qc", "b"}, {true, false});
  ASSERT_EQ(r.sentences.size(), 1u);
  EXPECT_NE(r.sentences[0].find("not a minimum"), std::string::npos) << r.sentences[0];
  // A positive definite H: SEs from its inverse, no sentence.
  H(1, 1) = 16.0;
  r = AnalyseFisher(H, {0.0, 0.0}, {"log qc", "b"}, {true, false});
  EXPECT_TRUE(r.positive_definite);
  EXPECT_TRUE(r.sentences.empty());
  EXPECT_DOUBLE_EQ(r.std_errors[1], 0.25);
  // A non-finite H says so.
  H(0, 1) = std::nan("");
  r = AnalyseFisher(H, {0.0, 0.0}, {"log qc", "b"}, {true, false});
  ASSERT_EQ(r.sentences.size(), 1u);
  EXPECT_NE(r.sentences[0].find("not finite"), std::string::npos);
}

TEST(ParamEstimationInput, RejectsBadNamesBoundsPriorsAndTheKf) {
  using testing::ErrorText;
  EXPECT_NE(ErrorText([] { ParseEstimatedParams("L,L", "", ""); }).find("'L' is named twice"),
            std::string::npos);
  EXPECT_NE(ErrorText([] {
              ParseEstimatedParams("L", "b=0:1", "");
            }).find("--param-bounds: 'b' is not in --estimate-param"),
            std::string::npos);
  EXPECT_NE(ErrorText([] { ParseEstimatedParams("L", "L=0.1", ""); }).find("got 'L=0.1'"),
            std::string::npos);
  EXPECT_NE(ErrorText([] { ParseEstimatedParams("L", "L=x:1", ""); }).find("'x'"),
            std::string::npos);
  EXPECT_NE(ErrorText([] {
              ParseEstimatedParams("L", "", "L=gamma:1:2");
            }).find("expected NAME=normal:MEAN:SD, got 'L=gamma:1:2'"),
            std::string::npos);
  EXPECT_NE(ErrorText([] { ParseEstimatedParams("L", "", "L=normal:1:0"); }).find("sd must be > 0"),
            std::string::npos);
  const std::vector<EstimatedParam> e =
      ParseEstimatedParams(" L , b", "b=:5, L=0.1:", "L=normal:0.5:0.1");
  ASSERT_EQ(e.size(), 2u);
  EXPECT_TRUE(std::isnan(e[0].upper) && e[0].lower == 0.1 && e[0].has_prior);
  EXPECT_TRUE(std::isnan(e[1].lower) && e[1].upper == 5.0 && !e[1].has_prior);

  const std::vector<FilterData> data = {PendulumData(3, 50)};
  auto error = [&](FilterSpec spec, TunerOptions options) {
    return ErrorText([&] { InnovationLikelihood<P, P::Angle> lik(spec, options, data); });
  };
  EXPECT_NE(
      error(Spec(EkfOptions{}), Options({"len"})).find("has no parameter 'len' (it has g, L, b)"),
      std::string::npos);
  EXPECT_NE(error(Spec(KfOptions{}), Options({"L"})).find("needs the ekf"), std::string::npos);
  TunerOptions bounded = Options({"L"});
  bounded.estimate[0].lower = 1.0;  // the initial 0.8 is outside
  EXPECT_NE(error(Spec(EkfOptions{}), bounded).find("outside its bounds"), std::string::npos);
  bounded.estimate[0].lower = -1.0;
  EXPECT_NE(error(Spec(EkfOptions{}), bounded).find("must be finite and > 0"), std::string::npos);
}

TEST(ParamEstimation, BoundsHoldAndAreFlagged) {
  const std::vector<FilterData> data = {PendulumData(81, 600)};
  TunerOptions options = Options({"L", "b"});
  options.estimate[1].upper = 0.2;  // truth 0.3
  for (MlSolver form : {MlSolver::kLbfgs, MlSolver::kLeastSquares}) {
    options.solver = form;
    const TuneResult r = TuneWith<P, P::Angle>(Spec(EkfOptions{}), options, data);
    ASSERT_TRUE(r.IsSolutionUsable()) << r.message;
    EXPECT_LE(r.param_values[1], 0.2 + 1e-12) << MlSolverName(form);
    EXPECT_TRUE(r.at_bound[3]) << MlSolverName(form);
    EXPECT_FALSE(r.at_bound[2]) << MlSolverName(form);
  }
}

// Initial states as parameters (TunerOptions::estimate_x0,
// adaptive/initial_states.h). The reference is the likelihood of the same
// spec with that x0 written in, no x0 estimated: the NLL must be the same
// number, bit for bit; with x0_per_file each dataset takes its own row, so
// the NLL is the sum of the single-dataset references. The AD gradient in
// x0 (through the whole filter run) against central differences.
TEST(InitialStateParams, NllIsTheSpecsWithThatX0AndPerFileRowsAreEachFiles) {
  const std::vector<FilterData> data = {PendulumData(9, 300), PendulumData(10, 300)};
  const std::vector<FilterData> first = {data[0]}, second = {data[1]};
  TunerOptions options = Options({"L"});
  options.estimate_x0 = {"omega", "theta"};
  TunerOptions plain = options;
  plain.estimate_x0.clear();
  const FilterSpec spec = Spec(EkfOptions{});
  auto moved = [&](double theta0, double omega0) {
    FilterSpec s = spec;
    s.x0 = {theta0, omega0};
    return s;
  };
  const InnovationLikelihood<P, P::Angle> shared(spec, options, data);
  ASSERT_EQ(shared.NumParams(), 5);
  EXPECT_EQ(shared.ParamNames()[3], "x0 omega");
  EXPECT_EQ(shared.ParamNames()[4], "x0 theta");
  std::vector<double> theta = shared.InitialTheta();
  EXPECT_EQ(theta[3], 0.0);  // the spec's x0 in the order named
  EXPECT_EQ(theta[4], 1.2);
  theta[3] = 0.3, theta[4] = 1.05;
  const InnovationLikelihood<P, P::Angle> ref(moved(1.05, 0.3), plain, data);
  double nll = 0.0, nll_ref = 0.0;
  ASSERT_TRUE(shared.Nll(theta.data(), &nll));
  ASSERT_TRUE(ref.Nll(theta.data(), &nll_ref));  // its theta: the first three
  EXPECT_EQ(nll, nll_ref);
  const double nll_start = NegLogLikelihood(shared, shared.InitialTheta().data());
  EXPECT_GT(std::abs(nll - nll_start), 1.0) << "x0 must move the NLL for this test to see it";

  options.x0_per_file = true;
  const InnovationLikelihood<P, P::Angle> per(spec, options, data);
  ASSERT_EQ(per.NumParams(), 7);
  EXPECT_EQ(per.ParamNames()[5], "x0[2] omega");
  EXPECT_EQ(per.ParamNames()[6], "x0[2] theta");
  std::vector<double> theta_per = theta;
  theta_per.push_back(-0.2);
  theta_per.push_back(1.3);
  const InnovationLikelihood<P, P::Angle> ref1(moved(1.05, 0.3), plain, first);
  const InnovationLikelihood<P, P::Angle> ref2(moved(1.3, -0.2), plain, second);
  const double sum = NegLogLikelihood(ref1, theta.data()) + NegLogLikelihood(ref2, theta.data());
  EXPECT_NEAR(NegLogLikelihood(per, theta_per.data()), sum, 1e-12 * std::abs(sum));

  uint64_t seed = 90;
  CheckGradient(shared, seed++, "ekf x0");
  CheckGradient(per, seed++, "ekf x0/file");
  const InnovationLikelihood<P, P::Angle> ukf(
      Spec(SigmaPointOptions{.rule = SigmaRule::kUnscented, .alpha = 0.5}), options, data);
  CheckGradient(ukf, seed++, "ukf x0/file");
  FilterSpec cv = spec;
  cv.transition.integrator = Integrator::kCvodes;
  cv.transition.rtol = 1e-12;
  cv.transition.atol = 1e-14;
  const std::vector<FilterData> short_data = {PendulumData(11, 150)};
  options.x0_per_file = false;
  const InnovationLikelihood<P, P::Angle> cvodes(cv, options, short_data);
  CheckGradient(cvodes, seed++, "cvodes x0", {.h = 1e-3, .fourth_order = true});
}

// The whole tuner with x0 estimated: simulated from x0 = (1.2, 0) exactly
// (P0 tiny), started at (1.0, 0.3); converged, the truth within 3 SE, the
// report's rows and the tuned spec's x0 the estimate, the NLL at the
// estimate at most the truth's.
TEST(InitialStateParams, TunerRecoversTheInitialStateAndReportsIt) {
  const std::vector<FilterData> data = {PendulumData(12, 1000)};
  FilterSpec spec = Spec(EkfOptions{});
  spec.x0 = {1.0, 0.3};
  spec.p0 = {1e-8, 0.0, 0.0, 1e-8};
  TunerOptions options = Options({"L", "b"});
  options.estimate_x0 = {"theta", "omega"};
  const TuneResult r = TuneWith<P, P::Angle>(spec, options, data);
  ASSERT_TRUE(r.IsConverged()) << r.message;
  ASSERT_EQ(r.x0.size(), 1u);
  ASSERT_EQ(r.x0_names, (std::vector<std::string>{"theta", "omega"}));
  const double truth[2] = {1.2, 0.0};
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(r.x0[0][i], r.theta[4 + i]);
    EXPECT_EQ(r.x0_std_errors[0][i], r.std_errors[4 + i]);
    EXPECT_EQ(r.x0_initial[0][i], spec.x0[i]);
    EXPECT_EQ(r.tuned_spec.x0[i], r.x0[0][i]);
    EXPECT_LE(std::abs(r.x0[0][i] - truth[i]), 3 * r.x0_std_errors[0][i]) << r.x0_names[i];
    std::printf("  x0 %s: %.5f +- %.5f (truth %.1f, start %.1f)\n", r.x0_names[i].c_str(),
                r.x0[0][i], r.x0_std_errors[0][i], truth[i], spec.x0[i]);
  }
  FilterSpec at_truth = spec;
  at_truth.x0 = {1.2, 0.0};
  TunerOptions plain = options;
  plain.estimate_x0.clear();
  const InnovationLikelihood<P, P::Angle> lik(at_truth, plain, data);
  const double theta_true[4] = {std::log(kQc), std::log(kR), std::log(kL), kB};
  EXPECT_LE(r.nll_tuned, NegLogLikelihood(lik, theta_true) + 1e-9);
}

TEST(InitialStateParams, BadNamesAndEstimatorsAreRefused) {
  const std::vector<FilterData> data = {PendulumData(13, 50)};
  auto error = [&](TunerOptions o) {
    return testing::ErrorText(
        [&] { InnovationLikelihood<P, P::Angle> lik(Spec(EkfOptions{}), o, data); });
  };
  TunerOptions o = Options({});
  o.estimate_x0 = {"phi"};
  EXPECT_NE(error(o).find("--estimate-x0: 'phi' is not a state of model 'pendulum' (theta, omega)"),
            std::string::npos)
      << error(o);
  o.estimate_x0 = {"theta", "theta"};
  EXPECT_NE(error(o).find("'theta' is named twice"), std::string::npos);
  o.estimate_x0 = {"theta"};
  o.x0_per_file = true;  // one dataset
  EXPECT_NE(error(o).find("--x0-per-file needs two --data files or more"), std::string::npos);
  std::string why;
  o.x0_per_file = false;
  o.estimator = Estimator::kAls;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_EQ(why, "--estimate-x0 applies to the ml, em and output-error estimators, not als");
  o.estimator = Estimator::kEm;
  EXPECT_TRUE(o.IsValid(&why)) << why;
  EXPECT_EQ(ParseEstimatedStates(" theta , omega"), (std::vector<std::string>{"theta", "omega"}));
  EXPECT_THROW(ParseEstimatedStates("theta,,omega"), InputError);
}

}  // namespace
}  // namespace estlab
