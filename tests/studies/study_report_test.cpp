// The shipped studies, the engine options added for the papers (Poisson
// measurement noise, R = diag(std), noise roles, report tables) and the
// hand / auto / oracle section of report.md.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../cli/cli_test_util.h"
#include "src/core/types.h"
#include "studies/config/study_config.h"
#include "studies/run/study_runner.h"
#include "study_test_util.h"

namespace estlab::testing {
namespace {

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

TEST(ShippedStudies, EveryConfigParses) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  for (const char* name :
       {"paper000_noise_grid", "paper001_dipc", "paper002_pendulum_mc",
        "paper003_double_pendulum_sweep", "paper004_cartpole_kf_ekf", "tuning_hand_vs_auto"}) {
    const std::string path = std::string(ESTLAB_SOURCE_DIR) + "/studies/" + name + ".ini";
    StudyConfig c;
    ASSERT_NO_THROW(c = LoadStudyConfig(path)) << path;
    EXPECT_EQ(c.study.name, name);
  }
}

TEST(ShippedStudies, TuningStudyHasHandAutoAndOracleEverywhere) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const StudyConfig c =
      LoadStudyConfig(std::string(ESTLAB_SOURCE_DIR) + "/studies/tuning_hand_vs_auto.ini");
  EXPECT_GE(c.study.runs, 100);
  ASSERT_EQ(c.scenarios.size(), 6u);
  for (const ScenarioConfig& sc : c.scenarios) {
    bool hand = false, tuned = false, oracle = false;
    for (const Combo& cb : sc.combos) {
      const NoiseRole role = c.noises[cb.noise].role;
      hand |= role == NoiseRole::kHand;
      tuned |= role == NoiseRole::kTuned && cb.tune;
      oracle |= role == NoiseRole::kOracle;
    }
    EXPECT_TRUE(hand && tuned && oracle) << sc.name;
    // An oracle Q must mean something: every truth has process noise.
    double q = 0;
    for (double v : sc.oracle_q) q += std::abs(v);
    EXPECT_GT(q, 0.0) << sc.name;
  }
}

TEST(StudyOptions, PoissonNoiseOracleStdAndRoles) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  std::string text = TinyStudy(3);
  text = Replace(text, "meas-noise-var = 0.01\n", "meas-noise-var = 0.01\nmeas-noise = poisson\n");
  text =
      Replace(text, "[noise.hand]\n", "[noise.std]\nq = oracle\nr = oracle-std\n\n[noise.hand]\n");
  const StudyConfig c = ParseStudyConfig(text, "s.ini");
  const ScenarioConfig& sc = c.scenarios[0];
  EXPECT_TRUE(sc.poisson_meas);
  ASSERT_EQ(sc.poisson_lambda.size(), 1u);
  EXPECT_EQ(sc.poisson_lambda[0], 0.01);
  EXPECT_EQ(sc.truth.meas_noise_var[0], 0.0);  // the runner adds the counts
  EXPECT_EQ(sc.oracle_r[0], 0.01);             // their variance
  for (const Combo& cb : sc.combos) {
    const std::string& noise = c.noises[cb.noise].name;
    if (noise == "std") {
      EXPECT_DOUBLE_EQ(cb.spec.r[0], 0.1);  // sqrt(0.01): paper 003's R
    }
    if (noise == "oracle") {
      EXPECT_DOUBLE_EQ(cb.spec.r[0], 0.01);
    }
  }
  std::vector<std::string> roles;
  for (const auto& n : c.noises) roles.push_back(n.name + ":" + NoiseRoleName(n.role));
  EXPECT_EQ(roles, (std::vector<std::string>{"oracle:oracle", "std:hand", "hand:hand"}));
}

TEST(StudyOptions, BadNewKeysNameFileLineAndKey) {
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"meas-noise-var = 0.01\n", "meas-noise-var = 0.01\nmeas-noise = laplace\n",
       "s.ini:18: [scenario.pend] meas-noise: expected gaussian or poisson, got 'laplace'"},
      {"[noise.hand]\n", "[noise.hand]\nrole = best\n",
       "[noise.hand] role: expected hand, tuned, oracle or other, got 'best'"},
      {"[noise.hand]\nq-diag = 1e-3,1e-2\nr-diag = 0.02\n",
       "[noise.hand]\nq-diag = 1e-3,1e-2\nr-diag = oracle-std\n",
       "[noise.hand] r-diag: 'oracle-std' goes in key r"},
      {"[report]\n", "[report]\ntables = rmse,mean\n",
       "[report] tables: expected rmse, mse or mae, got 'mean'"},
      {"[report]\n", "[report]\noverview = rmse_alpha\n",
       "[report] overview: unknown metric 'rmse_alpha'"},
  };
  for (const Case& c : cases) {
    const std::string text = Replace(TinyStudy(3), c.from, c.to);
    try {
      ParseStudyConfig(text, "s.ini");
      ADD_FAILURE() << "no error for " << c.to;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("s.ini:", 0), 0u) << msg;
      EXPECT_NE(msg.find(c.expect), std::string::npos) << "got: " << msg;
    }
  }
}

TEST(StudyOptions, PoissonCountsHaveMeanAndVarianceLambda) {
  Rng rng(42);
  const int n = 200000;
  for (double lambda : {0.1, 2.0}) {
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
      const double k = PoissonCount(rng, lambda);
      sum += k;
      sum2 += k * k;
    }
    const double mean = sum / n, var = sum2 / n - mean * mean;
    EXPECT_NEAR(mean, lambda, 5 * std::sqrt(lambda / n)) << lambda;
    EXPECT_NEAR(var, lambda, 0.02 * lambda + 5 * std::sqrt(2 * lambda * lambda / n)) << lambda;
  }
  EXPECT_EQ(PoissonCount(rng, 0.0), 0);
}

// End to end: a tuned setting beside hand and oracle settings gives the
// comparison section; tables = rmse,mse adds the MSE table; Poisson noise runs.
TEST(StudyReport, HandAutoOracleSectionAndMseTable) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  TempDir dir;
  std::string text = TinyStudy(4, 25, 100, /*tuned=*/true);
  text = Replace(text, "[report]\n", "[report]\ntables = rmse,mse\n");
  WriteText(dir.File("s.ini"), text);
  const auto r = RunEstlab("study s.ini --out t --jobs 2 --quiet", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = ReadFile(dir.File("t/report.md"));
  EXPECT_NE(report.find("## Hand-tuned vs auto-tuned vs oracle Q/R"), std::string::npos);
  // No paper in [report]: the hand settings are the config's, not a paper's.
  EXPECT_NE(report.find("Each filter with the config's hand noise settings, with Q/R"),
            std::string::npos);
  EXPECT_EQ(report.find("the paper's hand-tuned"), std::string::npos);
  EXPECT_NE(report.find("| pend | ekf | `hand` | "), std::string::npos) << report;
  EXPECT_NE(report.find("| pend | ekf | theta | "), std::string::npos) << report;
  EXPECT_NE(report.find("auto ≤ 1.1 × oracle holds in "), std::string::npos);
  EXPECT_NE(report.find(" of 2 scenario × filter cases; auto ≤ best hand in "), std::string::npos);
  EXPECT_NE(report.find(" MSE theta |"), std::string::npos);
  // The paper's numbers as one row per group, metrics as columns.
  EXPECT_NE(report.find("| rmse_theta mean paper | estlab | rmse_theta var paper | estlab |"),
            std::string::npos);

  // A hand setting equal to the truth's noise is marked as the oracle.
  std::string same = Replace(TinyStudy(3, 25, 100, /*tuned=*/true),
                             "[noise.hand]\nq-diag = 1e-3,1e-2\nr-diag = 0.02\n",
                             "[noise.hand]\nq-white-accel = 0.5\nr-diag = 0.01\n");
  WriteText(dir.File("same.ini"), same);
  ASSERT_EQ(RunEstlab("study same.ini --out same --jobs 2 --quiet", dir.path()).exit_code, 0);
  EXPECT_NE(ReadFile(dir.File("same/report.md")).find("| pend | ekf | `hand` (= oracle) |"),
            std::string::npos);

  std::string poisson = Replace(TinyStudy(3), "meas-noise-var = 0.01\n",
                                "meas-noise-var = 0.05\nmeas-noise = poisson\n");
  WriteText(dir.File("p.ini"), poisson);
  const auto p = RunEstlab("study p.ini --out p --jobs 1 --quiet", dir.path());
  ASSERT_EQ(p.exit_code, 0) << p.err;
  // The counts come from each run's own stream: --jobs does not change them.
  ASSERT_EQ(RunEstlab("study p.ini --out p2 --jobs 2 --quiet", dir.path()).exit_code, 0);
  EXPECT_EQ(ReadFile(dir.File("p/runs.csv")), ReadFile(dir.File("p2/runs.csv")));
  EXPECT_NE(ReadFile(dir.File("p/report.md")).find("Poisson counts with lambda [0.05]"),
            std::string::npos);
}

// With [report] paper = ..., the hand settings are the paper's.
TEST(StudyReport, HandSettingsAreThePapersOnlyWhenReportNamesAPaper) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  TempDir dir;
  WriteText(dir.File("s.ini"), Replace(TinyStudy(3, 25, 100, /*tuned=*/true), "[report]\n",
                                       "[report]\npaper = 002\n"));
  const auto r = RunEstlab("study s.ini --out t --jobs 2 --quiet", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = ReadFile(dir.File("t/report.md"));
  EXPECT_NE(report.find("Each filter with the paper's hand-tuned noise settings, with Q/R"),
            std::string::npos)
      << report;
  EXPECT_EQ(report.find("the config's hand noise settings"), std::string::npos);
}

// A section expanded over one key into >= 3 scenarios gets an RMSE-vs-key
// figure; every kept run a sigma-over-time figure; axis labels carry units.
TEST(StudyFigures, SweepSigmaAndUnits) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  TempDir dir;
  const std::string text =
      Replace(TinyStudy(3), "meas-noise-var = 0.01\n", "meas-noise-var = 0.01 | 0.02 | 0.04\n");
  WriteText(dir.File("s.ini"), text);
  ASSERT_EQ(RunEstlab("study s.ini --out r --quiet", dir.path()).exit_code, 0);
  const auto f = RunEstlab("figures r --no-render", dir.path());
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_TRUE(dir.Exists("r/figures/pend_rmse_vs_meas-noise-var.gp"));
  EXPECT_TRUE(dir.Exists("r/figures/pend_rmse_vs_meas-noise-var.dat"));
  EXPECT_TRUE(dir.Exists("r/figures/pend.0.01_sigma_run0.gp"));
  const std::string gp = ReadFile(dir.File("r/figures/pend.0.01_rmse_time.gp"));
  EXPECT_NE(gp.find("RMSE theta [rad]"), std::string::npos) << gp;
  EXPECT_NE(gp.find("RMSE omega [rad/s]"), std::string::npos) << gp;
  // The sweep's data: one block per state x filter x noise, three levels each.
  const std::string dat = ReadFile(dir.File("r/figures/pend_rmse_vs_meas-noise-var.dat"));
  EXPECT_NE(dat.find("2 \"0.04\" "), std::string::npos) << dat;
}

}  // namespace
}  // namespace estlab::testing
