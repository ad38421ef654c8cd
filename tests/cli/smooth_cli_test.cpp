// `estlab smooth` end to end: every filter's smoother from the command line,
// the smoothed rows against the filter's own (the last step's smoothed
// belief is the filtered one), the printed RMSE against the errors written,
// the JSON layout, bad input (exit 2, no file) and divergence (exit 1, the
// rows before kept).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

const std::string kSmoothArgs =
    "smooth" + std::string(kPendulumFilter).substr(std::string("filter").size()) + "--data d.csv ";
const std::string kFilterArgs = std::string(kPendulumFilter) + "--data d.csv ";

std::vector<double> Fields(const std::string& line) {
  std::vector<double> v;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) v.push_back(cell.empty() ? std::nan("") : std::stod(cell));
  return v;
}

// The number after the last `"rmse": {"theta": ` (the smoother's; the
// forward filter's nested object comes first).
double LastRmseTheta(const std::string& json) {
  const std::string key = "\"rmse\": {\"theta\": ";
  const size_t at = json.rfind(key);
  return at == std::string::npos ? std::nan("") : std::stod(json.substr(at + key.size()));
}

TEST(SmoothCli, EverySmootherEndsOnItsFilterAndPrintsTheRmseItWrites) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const std::pair<const char*, const char*> kinds[] = {
      {"kf", "rts"},      {"ekf", "erts"},      {"iekf", "iekf-rts"}, {"ukf", "urts"},
      {"ckf", "ckf-rts"}, {"ghkf", "ghkf-rts"}, {"pf", "pf-bs"}};
  for (const auto& [filter, smoother] : kinds) {
    const std::string extra = std::string(filter) == "pf" ? "--particles 500 " : "";
    const RunResult f =
        RunEstlab(kFilterArgs + "--filter " + filter + " " + extra + "--out f.csv", dir.path());
    ASSERT_EQ(f.exit_code, 0) << filter << ": " << f.err;
    const RunResult s = RunEstlab(
        kSmoothArgs + "--filter " + filter + " " + extra + "--out s.csv --json", dir.path());
    ASSERT_EQ(s.exit_code, 0) << filter << ": " << s.err;
    EXPECT_NE(s.out.find("\"smoother\": \"" + std::string(smoother) + "\""), std::string::npos)
        << s.out;
    EXPECT_NE(s.out.find("\"filter\": {\"filter\": \"" + std::string(filter) + "\""),
              std::string::npos)
        << s.out;
    const auto f_lines = SplitLines(ReadFile(dir.File("f.csv")));
    const auto s_lines = SplitLines(ReadFile(dir.File("s.csv")));
    ASSERT_EQ(s_lines.size(), 402u) << filter;
    EXPECT_EQ(s_lines[0], "t,theta_est,omega_est,theta_var,omega_var,theta_err,omega_err,nees");
    // RMSE of theta from the written errors = the printed one.
    double sq = 0.0;
    for (size_t k = 1; k < s_lines.size(); ++k) sq += std::pow(Fields(s_lines[k])[5], 2);
    EXPECT_NEAR(std::sqrt(sq / 401.0), LastRmseTheta(s.out), 1e-9 * LastRmseTheta(s.out)) << filter;
    if (std::string(filter) == "pf") continue;  // pf-bs' last step is a sample mean
    // The last smoothed belief is the filtered one (x^s_K = x_K, P^s_K = P_K).
    const auto fl = Fields(f_lines.back()), sl = Fields(s_lines.back());
    for (int i = 1; i <= 4; ++i) EXPECT_NEAR(sl[i], fl[i], 1e-12 * (1 + std::abs(fl[i]))) << i;
    // Smoothing uses later data: its angle error is below the filter's.
    const RunResult fj =
        RunEstlab(kFilterArgs + "--filter " + filter + " " + extra + "--json", dir.path());
    EXPECT_LT(LastRmseTheta(s.out), LastRmseTheta(fj.out)) << filter;
  }
}

// Rows at one time share one smoothed belief (it conditions on both
// measurements); a missing measurement is smoothed through; a prior before
// the first row is a step of its own; the last row is the filtered belief.
TEST(SmoothCli, RepeatedTimesMissingValuesAndAnEarlierPrior) {
  TempDir dir;
  {
    std::ofstream f(dir.File("lab.csv"));
    f << "t,z_theta\n0,0.5\n0.01,0.49\n0.01,0.51\n0.02,\n0.03,0.47\n0.05,0.46\n";
  }
  const std::string args =
      "--model pendulum --measure angle --filter ekf --data lab.csv --x0 theta=0.4 "
      "--q-diag 1e-4,1e-2 --r-diag 0.01 --t0 -0.02 ";
  ASSERT_EQ(RunEstlab("filter " + args + "--out f.csv", dir.path()).exit_code, 0);
  const RunResult s = RunEstlab("smooth " + args + "--out s.csv", dir.path());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto f_lines = SplitLines(ReadFile(dir.File("f.csv")));
  const auto s_lines = SplitLines(ReadFile(dir.File("s.csv")));
  ASSERT_EQ(s_lines.size(), 7u);
  EXPECT_EQ(s_lines[2], s_lines[3]);  // t = 0.01 twice: one smoothed belief
  EXPECT_NE(f_lines[2].substr(0, 30), f_lines[3].substr(0, 30));  // the filter's differ
  // t = 0.02 has no measurement: the later ones make its smoothed angle
  // variance strictly smaller than the filter's prediction variance.
  EXPECT_LT(Fields(s_lines[4])[3], 0.9 * Fields(f_lines[4])[3]);
  const auto fl = Fields(f_lines.back()), sl = Fields(s_lines.back());
  for (int i = 1; i <= 4; ++i) EXPECT_NEAR(sl[i], fl[i], 1e-12 * (1 + std::abs(fl[i]))) << i;
  // Every smoothed variance is at most the filtered one.
  for (size_t k = 1; k < s_lines.size(); ++k)
    for (int i = 3; i <= 4; ++i)
      EXPECT_LE(Fields(s_lines[k])[i], Fields(f_lines[k])[i] * (1 + 1e-12)) << k << " " << i;
}

TEST(SmoothCli, FullCovWritesTheLagOneCovariances) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const RunResult s = RunEstlab(kSmoothArgs + "--filter ukf --full-cov --out s.csv", dir.path());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_NE(s.out.find("smoother      urts (forward filter ukf)"), std::string::npos) << s.out;
  const auto lines = SplitLines(ReadFile(dir.File("s.csv")));
  EXPECT_EQ(lines[0],
            "t,theta_est,omega_est,theta_var,omega_var,cov_theta_omega,lag1_theta_theta,"
            "lag1_theta_omega,lag1_omega_theta,lag1_omega_omega,theta_err,omega_err,nees");
  // Cov(theta_k, theta_k+1) is close to Var(theta_k) at dt 0.0125 and
  // bounded by Cauchy-Schwarz; the last row has no next step.
  const auto first = Fields(lines[1]), next = Fields(lines[2]);
  EXPECT_GT(first[6], 0.5 * first[3]);
  EXPECT_LE(first[6] * first[6], first[3] * next[3] * (1 + 1e-9));
  const auto last = Fields(lines.back());
  for (int i = 6; i <= 9; ++i) EXPECT_TRUE(std::isnan(last[i])) << i;
}

TEST(SmoothCli, BadInputExitsTwoWithoutOutput) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const std::pair<std::string, std::string> cases[] = {
      {kSmoothArgs + "--filter pf --smoother-trajectories 1 --out e.csv",
       "--smoother-trajectories must be in 2..100000, got 1"},
      {kSmoothArgs + "--filter bogus --out e.csv", "bogus"},
      {"smooth --model pendulum --measure sin --data nothere.csv --q-diag 1,1 --r-diag 1 --out "
       "e.csv",
       "nothere.csv"},
      {"smooth --model pendulum --measure sin --filter pf --data d.csv --q-diag 0,1e-4 "
       "--r-diag 0.1 --out e.csv",
       "positive definite"},
      {kSmoothArgs + "--filter ukf --out d.csv", "d.csv"},
  };
  for (const auto& [args, expect] : cases) {
    const RunResult r = RunEstlab(args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error: "), std::string::npos) << args;
    EXPECT_NE(r.err.find(expect), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(dir.Exists("e.csv")) << args;
  }
  const RunResult help = RunEstlab("smooth --help", dir.path());
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("Examples:"), std::string::npos);
  EXPECT_NE(help.out.find("--smoother-trajectories"), std::string::npos);
}

TEST(SmoothCli, DivergenceExitsOneAndSmoothsTheRowsBefore) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kDivergingVanDerPolSimulate, dir.path()).exit_code, 0);
  const std::string model = kDivergingVanDerPolFilter;
  const RunResult f = RunEstlab("filter " + model + "--out f.csv", dir.path());
  const RunResult s = RunEstlab("smooth " + model + "--out s.csv", dir.path());
  EXPECT_EQ(s.exit_code, 1) << s.err;
  EXPECT_NE(s.err.find("stopped at step"), std::string::npos) << s.err;
  const auto f_lines = SplitLines(ReadFile(dir.File("f.csv")));
  const auto s_lines = SplitLines(ReadFile(dir.File("s.csv")));
  EXPECT_GT(s_lines.size(), 1u);
  EXPECT_EQ(s_lines.size(), f_lines.size());
}

}  // namespace
}  // namespace estlab::testing
