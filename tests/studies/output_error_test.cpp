// Free simulation and output-error least squares (studies/run/output_error.h) on
// pendulum data simulated here: windows started from exact states reproduce
// the trajectory, the fit recovers L and b from angle data with known noise,
// and data it cannot use is an error naming the file and line.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "src/core/random.h"
#include "src/registry/registry.h"
#include "studies/run/output_error.h"
#include "tests/error_text.h"

namespace estlab {
namespace {

constexpr double kL = 0.5, kB = 0.3, kSigma = 1e-3;

// Noise-free simulation with L = 0.5, b = 0.3 from theta = 1.2, its states
// as the truth columns and theta + N(0, sigma^2) (sigma = 0 here or 1e-3)
// as z_theta.
FilterData Pendulum(double sigma, double t_end = 10.0) {
  const ModelEntry& model = FindModel("pendulum");
  SimulationSpec s;
  s.params = model.ResolveParams({{"L", kL}, {"b", kB}});
  s.x0 = {1.2, 0.0};
  s.t_end = t_end;
  s.dt = 0.01;
  s.transition.integrator = Integrator::kRk4;
  const SimulationResult r = model.simulate(s);
  EXPECT_TRUE(r.ok) << r.error;
  FilterData d;
  d.path = "sim.csv";
  d.m = 1;
  d.has_truth = true;
  Rng rng(5);
  for (size_t k = 0; k < r.rows.size(); ++k) {
    d.t.push_back(r.rows[k][0]);
    d.lines.push_back(long(k) + 2);
    d.truth.push_back(r.rows[k][1]);
    d.truth.push_back(r.rows[k][2]);
    d.z.push_back(r.rows[k][1] + sigma * rng.Normal());
  }
  return d;
}

FilterSpec Spec(double L, double b) {
  const ModelEntry& model = FindModel("pendulum");
  FilterSpec spec;
  spec.measurement = "angle";
  spec.params = model.ResolveParams({{"L", L}, {"b", b}});
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = {0.0, 0.0};
  spec.p0 = {1.0, 0.0, 0.0, 1.0};
  spec.q = {0.0, 0.0, 0.0, 1e-4};
  spec.r = {1e-6};
  return spec;
}

TEST(FreeSimulation, WindowsFromExactStatesReproduceTheTrajectory) {
  const ModelEntry& model = FindModel("pendulum");
  const FilterData d = Pendulum(0.0);
  for (double horizon : {0.1, 0.5, 3.0}) {
    const std::vector<double> rmse = FreeSimulationRmse(model, Spec(kL, kB), d, horizon);
    ASSERT_EQ(rmse.size(), 1u);
    EXPECT_LT(rmse[0], 1e-12) << horizon;
  }
  // A wrong length shows, and more so over a longer horizon.
  const double short_h = FreeSimulationRmse(model, Spec(0.55, kB), d, 0.1)[0];
  const double long_h = FreeSimulationRmse(model, Spec(0.55, kB), d, 1.0)[0];
  EXPECT_GT(short_h, 1e-4);
  EXPECT_GT(long_h, 5.0 * short_h);
}

TEST(OutputError, RecoversLengthAndDampingWithinThreeStandardErrors) {
  const ModelEntry& model = FindModel("pendulum");
  const std::vector<FilterData> runs = {Pendulum(kSigma, 20.0)};
  const std::vector<EstimatedParam> estimate = {{.name = "L"}, {.name = "b"}};
  const OutputErrorResult r = FitOutputError(model, Spec(0.8, 0.1), estimate, runs, {});
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(r.converged) << r.message;
  ASSERT_EQ(r.param_names, (std::vector<std::string>{"L", "b"}));
  EXPECT_EQ(r.names, (std::vector<std::string>{"log L", "b"}));
  EXPECT_LT(std::abs(r.param_values[0] - kL), 3.0 * r.param_std_errors[0]) << r.param_values[0];
  EXPECT_LT(std::abs(r.param_values[1] - kB), 3.0 * r.param_std_errors[1]) << r.param_values[1];
  EXPECT_LT(r.param_std_errors[0], 1e-3);
  // The residuals are the added noise: sd ~ sigma.
  EXPECT_NEAR(r.residual_sd, kSigma, 0.1 * kSigma);
  EXPECT_NEAR(r.rmse[0], r.residual_sd, 0.01 * kSigma);
  EXPECT_DOUBLE_EQ(r.fitted_spec.params[1], r.param_values[0]);
  EXPECT_TRUE(r.identifiability.empty());
  std::printf("  L %.6f +- %.2g, b %.5f +- %.2g, residual sd %.3g, %d iterations, %.2f s\n",
              r.param_values[0], r.param_std_errors[0], r.param_values[1], r.param_std_errors[1],
              r.residual_sd, r.iterations, r.wall_s);
}

// Without state columns and with the initial state estimated, the whole
// record is simulated from x0 (uneven sampling allowed): L, b and theta(0),
// omega(0) come back within 3 standard errors, and the whole-record RMSE at
// the fit is the noise level.
TEST(OutputError, WholeRecordFitRecoversParametersAndInitialState) {
  const ModelEntry& model = FindModel("pendulum");
  FilterData d = Pendulum(kSigma, 5.0);
  d.has_truth = false;
  d.truth.clear();
  FilterSpec spec = Spec(0.6, 0.2);
  spec.x0 = {1.0, 0.3};
  OutputErrorOptions options;
  options.estimate_x0 = {"theta", "omega"};
  const OutputErrorResult r =
      FitOutputError(model, spec, {{.name = "L"}, {.name = "b"}}, {d}, options);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.start, "the whole record from the estimated x0");
  EXPECT_EQ(r.names, (std::vector<std::string>{"log L", "b", "x0 theta", "x0 omega"}));
  EXPECT_LT(std::abs(r.param_values[0] - kL), 3.0 * r.param_std_errors[0]);
  EXPECT_LT(std::abs(r.param_values[1] - kB), 3.0 * r.param_std_errors[1]);
  ASSERT_EQ(r.x0.size(), 1u);
  EXPECT_LT(std::abs(r.x0[0][0] - 1.2), 3.0 * r.x0_std_errors[0][0]) << r.x0[0][0];
  EXPECT_LT(std::abs(r.x0[0][1] - 0.0), 3.0 * r.x0_std_errors[0][1]) << r.x0[0][1];
  EXPECT_LE(r.cost, r.cost_initial);
  EXPECT_NEAR(WholeRecordRmse(model, r.fitted_spec, d, r.x0[0])[0], kSigma, 0.1 * kSigma);
  std::printf("  L %.6f +- %.2g, theta0 %.6f +- %.2g, %d iterations\n", r.param_values[0],
              r.param_std_errors[0], r.x0[0][0], r.x0_std_errors[0][0], r.iterations);
}

// Issue 40 item 2: missing measurements are left out, not zero residuals.
// With every other z_theta NaN, the fit's N is the measured cells, its RMSE
// is the one over them (recomputed here from the free simulation at the
// fit) and sigma^2 = sum e^2 / (N - p); before, the NaN cells counted as
// zero errors (RMSE 0.0214 instead of 0.0317 in the issue) and all-NaN data
// fitted "501 residuals" with RMSE 0.
TEST(OutputError, MissingMeasurementsAreLeftOutNotCountedAsZero) {
  const ModelEntry& model = FindModel("pendulum");
  FilterData d = Pendulum(kSigma, 5.0);
  d.has_truth = false;
  d.truth.clear();
  const FilterData full = d;
  long measured = 0;
  for (size_t k = 0; k < d.z.size(); ++k) {
    if (k % 2 == 1) d.z[k] = std::nan("");
    measured += std::isfinite(d.z[k]);
  }
  FilterSpec spec = Spec(0.6, 0.2);
  spec.x0 = {1.2, 0.0};
  const OutputErrorResult r = FitOutputError(model, spec, {{.name = "L"}, {.name = "b"}}, {d}, {});
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_EQ(r.residuals, measured);
  const FreeSimulation sim = WholeRecordSimulation(model, r.fitted_spec, full, spec.x0);
  ASSERT_TRUE(sim.ok) << sim.why;
  double sum = 0.0;
  for (size_t k = 0; k < d.z.size(); k += 2) sum += (d.z[k] - sim.y[k]) * (d.z[k] - sim.y[k]);
  EXPECT_NEAR(r.rmse[0], std::sqrt(sum / double(measured)), 1e-10 * kSigma);
  EXPECT_NEAR(r.residual_sd, std::sqrt(sum / double(measured - 2)), 1e-10 * kSigma);
  EXPECT_NEAR(r.residual_sd, kSigma, 0.15 * kSigma);  // the noise, not sqrt(1/2) of it
  const FreeSimulation half = WholeRecordSimulation(model, r.fitted_spec, d, spec.x0);
  ASSERT_TRUE(half.ok) << half.why;
  EXPECT_NEAR(half.rmse[0], r.rmse[0], 1e-10 * kSigma);

  for (double& z : d.z) z = std::nan("");
  const std::string e = testing::ErrorText([&] {
    FitOutputError(model, spec, {{.name = "L"}, {.name = "b"}}, {d}, {});
  });
  EXPECT_NE(e.find("output-error: the data have no finite measurement to fit"), std::string::npos)
      << e;
  EXPECT_FALSE(WholeRecordSimulation(model, spec, d, spec.x0).ok);
}

TEST(OutputError, RejectsDataItCannotUse) {
  const ModelEntry& model = FindModel("pendulum");
  const std::vector<EstimatedParam> estimate = {{.name = "L"}};
  FilterData uneven = Pendulum(0.0, 1.0);
  uneven.t[7] += 0.004;
  std::string e =
      testing::ErrorText([&] { FitOutputError(model, Spec(0.8, 0.1), estimate, {uneven}, {}); });
  EXPECT_NE(e.find("sim.csv:9: free-simulation windows need evenly sampled data"),
            std::string::npos)
      << e;
  // One row: the windows' message, not the estimator's (issue 40 item 19:
  // --validate onerow.csv spoke of output-error).
  FilterData one = Pendulum(0.0, 1.0);
  one.t.resize(1);
  one.z.resize(1);
  one.truth.resize(2);
  one.lines.resize(1);
  e = testing::ErrorText([&] { FreeSimulationRmse(model, Spec(0.8, 0.1), one, 0.5); });
  EXPECT_NE(e.find("sim.csv: free-simulation windows need at least two rows, the file has 1"),
            std::string::npos)
      << e;
  // Without state columns the windows have no start: FreeSimulationRmse says
  // so; the fit simulates the whole record from x0 instead (next test).
  FilterData no_states = Pendulum(0.0, 1.0);
  no_states.has_truth = false;
  e = testing::ErrorText([&] { FreeSimulationRmse(model, Spec(0.8, 0.1), no_states, 0.5); });
  EXPECT_NE(e.find("need a column per state"), std::string::npos) << e;
  OutputErrorOptions x0;
  x0.estimate_x0 = {"phi"};
  e = testing::ErrorText([&] { FitOutputError(model, Spec(0.8, 0.1), estimate, {no_states}, x0); });
  EXPECT_NE(e.find("--estimate-x0: 'phi' is not a state of model 'pendulum' (theta, omega)"),
            std::string::npos)
      << e;
  x0.estimate_x0 = {"theta"};
  x0.x0_per_file = true;
  e = testing::ErrorText([&] { FitOutputError(model, Spec(0.8, 0.1), estimate, {no_states}, x0); });
  EXPECT_NE(e.find("--x0-per-file needs two --data files"), std::string::npos) << e;
  e = testing::ErrorText(
      [&] { FitOutputError(model, Spec(0.8, 0.1), {{.name = "len"}}, {Pendulum(0.0, 1.0)}, {}); });
  EXPECT_NE(e.find("has no parameter 'len'"), std::string::npos) << e;
  // Checked and scaled as in the ML fit (adaptive/theta_scale.h): a
  // negative bound of a positive parameter used to become log(-1) = NaN.
  EstimatedParam negative{.name = "L"};
  negative.lower = -1.0;
  e = testing::ErrorText(
      [&] { FitOutputError(model, Spec(0.8, 0.1), {negative}, {Pendulum(0.0, 1.0)}, {}); });
  EXPECT_NE(e.find("--param-bounds: the lower bound of L must be finite and > 0, got -1"),
            std::string::npos)
      << e;
  e = testing::ErrorText([&] {
    FitOutputError(model, Spec(0.8, 0.1), {{.name = "L"}, {.name = "L"}}, {Pendulum(0.0, 1.0)}, {});
  });
  EXPECT_NE(e.find("'L' is named twice"), std::string::npos) << e;
  OutputErrorOptions bad;
  bad.horizon = 0.0;
  e = testing::ErrorText(
      [&] { FitOutputError(model, Spec(0.8, 0.1), estimate, {Pendulum(0.0, 1.0)}, bad); });
  EXPECT_NE(e.find("--horizon must be > 0"), std::string::npos) << e;
}

}  // namespace
}  // namespace estlab
