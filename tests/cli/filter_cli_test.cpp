// `estlab filter` end to end: the simulate -> filter round trip, JSON keys,
// bad input (exit 2, file/line/column in messages), divergence (exit 1 with
// the rows computed before kept).
#include <gtest/gtest.h>

#include <cmath>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

const std::string kFilterArgs = std::string(kPendulumFilter) + "--data d.csv ";

TEST(FilterCli, RoundTripWithoutColumnMappingReportsRmse) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  for (const char* f : {"ekf", "iekf", "ukf", "ckf", "ghkf", "pf", "kf"}) {
    const RunResult r =
        RunEstlab(std::string(kFilterArgs) + "--filter " + f + " --out est.csv --json", dir.path());
    ASSERT_EQ(r.exit_code, 0) << f << ": " << r.err;
    for (const char* key : {"\"rmse\"", "\"mae\"", "\"loglik\"", "\"mean_nis\"", "\"nis_bounds95\"",
                            "\"mean_nees\"", "\"nees_bounds95\"", "\"steps\": 401", "\"wall_s\"",
                            "\"us_per_step\"", "\"status\": \"ok\""}) {
      EXPECT_NE(r.out.find(key), std::string::npos) << f << " lacks " << key << ": " << r.out;
    }
    const auto lines = SplitLines(ReadFile(dir.File("est.csv")));
    ASSERT_EQ(lines.size(), 402u) << f;
    EXPECT_EQ(lines[0],
              "t,theta_est,omega_est,theta_var,omega_var,nu_sin_theta,S_sin_theta,nis,loglik,"
              "theta_err,omega_err,nees");
  }
  // The human summary names RMSE per state.
  const RunResult r =
      RunEstlab(std::string(kFilterArgs) + "--filter ukf --out est.csv", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("RMSE"), std::string::npos);
  EXPECT_NE(r.out.find("theta"), std::string::npos);
}

TEST(FilterCli, ColumnMappingAndMissingMeasurements) {
  TempDir dir;
  {
    std::ofstream f(dir.File("lab.csv"));
    f << "time,angle_rad\n0,0.5\n0.01,\n0.02,0.49\n0.03,nan\n0.05,0.47\n";
  }
  const RunResult r = RunEstlab(
      "filter --model pendulum --measure angle --filter ekf --data lab.csv --column t=time "
      "--column z_theta=angle_rad --x0 theta=0.5 --q-diag 1e-6,1e-4 --r-diag 0.01 --out e.csv "
      "--json",
      dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"steps\": 5"), std::string::npos) << r.out;
  // Rows without a measurement have empty nis.
  const auto lines = SplitLines(ReadFile(dir.File("e.csv")));
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(lines[2].substr(lines[2].size() - 3), ",,,") << lines[2];
}

TEST(FilterCli, BadInputExitsTwoNamingTheProblem) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  struct Case {
    std::string args;
    std::string expect;
  };
  const std::string base = kFilterArgs;
  const std::vector<Case> cases = {
      {"filter --model pendulum --measure sin --data d.csv --q-diag 1,-1 --r-diag 0.1 --out e.csv",
       "Q"},
      {"filter --model pendulum --measure sin --data d.csv --q-diag 1,1 --r-diag 0 --out e.csv",
       "R"},
      {"filter --model pendulum --measure sin --data d.csv --q-diag 1,1 --r-diag 1 "
       "--p0 \"1,2;2,1\" --out e.csv",
       "P0"},
      {"filter --model pendulum --measure sin --data d.csv --q-diag 1,1,1 --r-diag 1 --out e.csv",
       "--q-diag"},
      {"filter --model pendulum --measure angle --data d.csv --q-diag 1,1 --r-diag 1 --out e.csv",
       "z_theta"},
      {"filter --model pendulum --measure sin --data nothere.csv --q-diag 1,1 --r-diag 1 --out "
       "e.csv",
       "nothere.csv"},
      {base + "--filter bogus --out e.csv", "bogus"},
      {base + "--filter ukf --resample nope --out e.csv", "nope"},
      {"filter --model pendulum --measure sin --data back.csv --q-diag 1,1 --r-diag 1 --out e.csv",
       "back.csv:4: column 1 ('t'): time goes backwards"},
      {"filter --model pendulum --measure sin --data junk.csv --q-diag 1,1 --r-diag 1 --out e.csv",
       "junk.csv:3: column 2 ('z_sin_theta')"},
  };
  {
    std::ofstream f(dir.File("back.csv"));
    f << "t,z_sin_theta\n0,0.1\n0.2,0.1\n0.1,0.1\n";
  }
  {
    std::ofstream f(dir.File("junk.csv"));
    f << "t,z_sin_theta\n0,0.1\n0.1,1.2.3\n";
  }
  for (const auto& c : cases) {
    const RunResult r = RunEstlab(c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error: "), std::string::npos) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(dir.Exists("e.csv")) << c.args;
  }
}

TEST(FilterCli, PriorTimeAfterTheFirstRowIsRefused) {
  TempDir dir;
  {
    std::ofstream f(dir.File("late.csv"));
    f << "t,z_sin_theta\n0.5,0.1\n0.6,0.1\n";
  }
  const std::string args = std::string(kPendulumFilter) + "--data late.csv --out e.csv";
  RunResult r = RunEstlab(args + " --t0 0.7", dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("estlab: error: --t0 0.7 is later than the first data row (late.csv:2, "
                       "t = 0.5)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(dir.Exists("e.csv"));
  r = RunEstlab(args + " --t0 0.5", dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(dir.Exists("e.csv"));
}

TEST(FilterCli, DivergenceExitsOneAndKeepsRows) {
  TempDir dir;
  // Van der Pol (mu = 1000) with an explicit Euler process model at dt 0.01
  // is violently unstable: the filter must stop, name the step and time, and
  // keep the rows before it.
  ASSERT_EQ(RunEstlab(kDivergingVanDerPolSimulate, dir.path()).exit_code, 0);
  const RunResult r =
      RunEstlab(std::string("filter ") + kDivergingVanDerPolFilter + "--out e.csv", dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("step"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("t = "), std::string::npos) << r.err;
  ASSERT_TRUE(dir.Exists("e.csv"));
  const auto lines = SplitLines(ReadFile(dir.File("e.csv")));
  EXPECT_GT(lines.size(), 1u);
  EXPECT_LT(lines.size(), 202u);
}

}  // namespace
}  // namespace estlab::testing
