// A study scenario driven by an input signal (`input = prbs(...)`,
// src/sim/input_signal.h): the truth's schedule holds the signal's samples,
// the runs' data carry them, and a filter with the oracle noise is
// consistent on them (mean NIS within its bounds) while the same filter
// without the input is not, so the truth and the filter see one input.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "error_text.h"
#include "src/sim/input_signal.h"
#include "studies/config/study_config.h"
#include "studies/report/study_metrics.h"
#include "studies/run/study_runner_parts.h"
#include "study_test_util.h"

namespace estlab {
namespace {

const char kSignal[] = "prbs(amplitude=2, period=0.2, order=7, seed=5)";

std::string CartStudy(const std::string& model, const std::string& input) {
  return "[study]\nname = cart\nseed = 5\nruns = 1\n\n"
         "[scenario.cart]\nmodel = " +
         model +
         "\nx0 = theta=0.1\ndt = 0.02\nsteps = 500\ntruth-integrator = rk4\n"
         "process-noise = diag 1e-8,1e-6,1e-8,1e-6\nmeasurement = x-theta\n"
         "meas-noise-var = 1e-4,1e-4\nprior-p0-diag = 1e-4,1e-4,1e-4,1e-4\ninput = " +
         input +
         "\n\n[filter.ekf]\nkind = ekf\nintegrator = rk4\n\n"
         "[noise.oracle]\nq = oracle\nr = oracle\n";
}

TEST(StudyInputSignal, TruthAndFilterSeeTheSameHeldSignal) {
  if (!testing::FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const StudyConfig c = ParseStudyConfig(CartStudy("cart-pole", kSignal), "s.ini");
  const ScenarioConfig& sc = c.scenarios[0];
  const InputSignal signal = ParseInputSignal(kSignal, "input");
  ASSERT_EQ(sc.truth.times.size(), 501u);
  ASSERT_EQ(sc.truth.inputs.size(), 501u);
  for (size_t k = 1; k < sc.truth.inputs.size(); ++k)
    ASSERT_EQ(sc.truth.inputs[k], signal.At(sc.truth.times[k])) << k;
  // Before the first measurement (t = 0.02) the first measurement's sample,
  // as a filter whose prior is at t = 0 holds the first row's input.
  EXPECT_EQ(sc.truth.inputs[0], sc.truth.inputs[1]);
  EXPECT_NE(sc.truth_description.find("input prbs("), std::string::npos) << sc.truth_description;

  SimulationSpec sim = sc.truth;
  sim.seed = 11;
  const SimulationResult truth = sc.model->simulate(sim);
  ASSERT_TRUE(truth.ok) << truth.error;
  FilterData data = study_runner::DataFromTruth(sc, truth, "run 0", 11);
  ASSERT_EQ(data.nu, 1);
  ASSERT_EQ(data.u.size(), 500u);
  for (size_t k = 0; k < data.u.size(); ++k) ASSERT_EQ(data.u[k], sc.truth.inputs[k + 1]) << k;

  // 500 updates of 2 outputs: mean NIS = chi-square(1000) / 500, sd 0.089.
  const FilterSpec& spec = sc.combos[0].spec;
  const FilterRunOutput with = sc.model->run_filter(spec, data);
  ASSERT_TRUE(with.summary.ok) << with.summary.message;
  const double nis = ComputeNoTruthMetrics(with, {"x", "theta"}, 0).mean_nis;
  EXPECT_GT(nis, 2 - 0.3) << nis;
  EXPECT_LT(nis, 2 + 0.3) << nis;
  data.nu = 0;  // the filter without the signal (u = 0)
  data.u.clear();
  const FilterRunOutput without = sc.model->run_filter(spec, data);
  const double wrong =
      without.summary.ok ? ComputeNoTruthMetrics(without, {"x", "theta"}, 0).mean_nis : INFINITY;
  EXPECT_GT(wrong, 10.0) << "the input should matter: mean NIS " << wrong;
  std::printf("  mean NIS with the signal %.3f, without it %.3g\n", nis, wrong);
}

// Signals are scenario values like any other: alternatives with labels
// expand into scenarios, and a signal's own ':' is not taken for a label.
TEST(StudyInputSignal, AlternativesExpandIntoScenarios) {
  if (!testing::FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const StudyConfig c = ParseStudyConfig(
      CartStudy("cart-pole", std::string("prbs: ") + kSignal +
                                 " | steps(0, 2:1.5) | ms: multisine(rms=1, band=0.1:2, sines=4)"),
      "s.ini");
  ASSERT_EQ(c.scenarios.size(), 3u);
  EXPECT_EQ(c.scenarios[0].name, "cart.prbs");
  EXPECT_EQ(c.scenarios[2].name, "cart.ms");
  const ScenarioConfig& steps = c.scenarios[1];
  EXPECT_EQ(steps.truth.inputs[99], 0.0);   // t = 1.98
  EXPECT_EQ(steps.truth.inputs[100], 1.5);  // t = 2.00
  EXPECT_EQ(steps.truth.inputs[500], 1.5);
}

// input = file(...): relative to the config file's folder, sampled and held
// like a signal; a record shorter than the runs is refused at the key.
TEST(StudyInputSignal, RecordedInputFileRelativeToTheConfig) {
  if (!testing::FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const std::string dir = ::testing::TempDir() + "/estlab_study_input";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/force.csv") << "t,F\n0,0\n3,1.5\n6,-1\n10,0\n";
  const StudyConfig c =
      ParseStudyConfig(CartStudy("cart-pole", "file(force.csv, F)"), dir + "/s.ini");
  const ScenarioConfig& sc = c.scenarios[0];
  ASSERT_EQ(sc.truth.inputs.size(), 501u);  // t = 0 .. 10
  EXPECT_EQ(sc.truth.inputs[149], 0.0);     // t = 2.98
  EXPECT_EQ(sc.truth.inputs[150], 1.5);     // t = 3.00
  EXPECT_EQ(sc.truth.inputs[300], -1.0);    // t = 6.00
  EXPECT_EQ(sc.truth.inputs[500], 0.0);     // t = 10
  std::ofstream(dir + "/short.csv") << "t,u\n0,0\n5,1\n";
  const std::string error = testing::ErrorText(
      [&] { ParseStudyConfig(CartStudy("cart-pole", "file(short.csv)"), dir + "/s.ini"); });
  EXPECT_NE(error.find("[scenario.cart] input: the input of"), std::string::npos) << error;
  EXPECT_NE(error.find("covers t = 0 .. 5, not 0 .. 10"), std::string::npos) << error;
}

TEST(StudyInputSignal, ErrorsNameTheScenarioKey) {
  if (!testing::FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  std::string pendulum = CartStudy("pendulum", kSignal);
  pendulum = testing::Replace(pendulum, "x-theta", "angle");
  pendulum = testing::Replace(pendulum, "diag 1e-8,1e-6,1e-8,1e-6", "diag 1e-8,1e-6");
  pendulum = testing::Replace(pendulum, "meas-noise-var = 1e-4,1e-4", "meas-noise-var = 1e-4");
  pendulum = testing::Replace(pendulum, "1e-4,1e-4,1e-4,1e-4", "1e-4,1e-4");
  const std::string no_input = testing::ErrorText([&] { ParseStudyConfig(pendulum, "s.ini"); });
  EXPECT_NE(no_input.find("[scenario.cart] input: model 'pendulum' has no input"),
            std::string::npos)
      << no_input;
  const std::string bad = testing::ErrorText(
      [] { ParseStudyConfig(CartStudy("cart-pole", "prbs(period=1)"), "s.ini"); });
  EXPECT_NE(bad.find("s.ini:"), std::string::npos) << bad;
  EXPECT_NE(bad.find("input prbs(...): 'amplitude=' is required"), std::string::npos) << bad;
}

}  // namespace
}  // namespace estlab
