// Issue 12, done-when 1 with --integrator cvodes: 10 simulated pendulum
// datasets with known L, b, qc, R, the EKF on a CVODES process model (the
// tuner's gradient from CVODES forward sensitivities in theta,
// src/ode/cvodes_theta_flow.h). Label `slow` (about 40 s): `make test` runs
// it, the sanitizer build does not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "adaptive/likelihood.h"
#include "adaptive/tuner_impl.h"
#include "models/pendulum.h"
#include "tests/adaptive/tuner_fixture.h"

namespace estlab {
namespace {

using P = models::Pendulum;

TEST(ParamEstimationCvodes, TenDatasetsCoverTheTruthAndBeatItsNll) {
  constexpr double kL = 0.5, kB = 0.3, kQc = 0.1, kR = 1e-3, kDt = 0.01;
  FilterSpec spec;
  spec.params = {9.81, 0.8, 0.1};
  spec.measurement = "angle";
  spec.filter = EkfOptions{};
  spec.transition.integrator = Integrator::kCvodes;
  spec.x0 = {1.2, 0.0};
  spec.p0 = {1e-2, 0.0, 0.0, 1e-2};
  spec.q_white_accel = true;
  spec.qc = 1e-2;
  spec.r = {1e-2};
  TunerOptions options;
  options.q_param = NoiseParam::kWhiteAccel;
  options.estimate = {{.name = "L"}, {.name = "b"}};
  const double truth[4] = {std::log(kQc), std::log(kR), std::log(kL), kB};
  const char* kNames[4] = {"log qc", "log r", "log L", "b"};
  P::Params p;
  p.L = kL;
  p.b = kB;
  int within[4] = {0, 0, 0, 0}, nll_ok = 0;
  const int datasets = 10;
  for (int d = 0; d < datasets; ++d) {
    const std::vector<FilterData> data = {testing::Simulate<P, P::Angle>(
        Integrator::kRk4, Vec<double, 2>(1.2, 0.0), kDt, 500, testing::WhiteAccel<P>(kQc, kDt),
        Mat<1, 1>::Constant(kR), DeriveSeed({91, uint64_t(d)}), p)};
    const TuneResult r = TuneWith<P, P::Angle>(spec, options, data);
    ASSERT_TRUE(r.IsSolutionUsable()) << r.message;
    ASSERT_TRUE(r.hessian_positive_definite) << d;
    for (int i = 0; i < 4; ++i)
      within[i] += std::abs(r.theta[i] - truth[i]) <= 2.0 * r.std_errors[i];
    const InnovationLikelihood<P, P::Angle> lik(spec, options, data);
    double nll_true = 0.0;
    ASSERT_TRUE(lik.Nll(truth, &nll_true));
    nll_ok += r.nll_tuned <= nll_true + 1e-6;
    std::printf("  dataset %d: L %.4f +- %.4f  b %.4f +- %.4f  NLL - true %.3f  %.1f s\n", d,
                r.param_values[0], r.param_std_errors[0], r.param_values[1], r.param_std_errors[1],
                r.nll_tuned - nll_true, r.wall_s);
  }
  for (int i = 0; i < 4; ++i) {
    std::printf("  %-6s within 2 SE: %d / %d\n", kNames[i], within[i], datasets);
    EXPECT_GE(within[i], 9) << i;
  }
  EXPECT_EQ(nll_ok, datasets);
}

}  // namespace
}  // namespace estlab
