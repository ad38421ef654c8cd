// Issue 15 items 13 and 25: absurd sizes and sigma-point parameters are
// refused (exit 2, the option and its limit named, no output) instead of
// hanging, exhausting memory or running a filter that never moves.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

TEST(LimitsCli, AbsurdSizesAndSigmaPointParametersExitTwo) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const std::string filter = std::string(kFilterWithoutR) + "--r-diag 0.1 --out e.csv ";
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"--filter ukf --kappa 1e300",
       "alpha, kappa: the unscented points would lie alpha sqrt(n + kappa) = 1e+147 standard "
       "deviations from the mean; at most 1000"},
      {"--filter ukf --alpha 2000", "alpha, kappa: the unscented points would lie"},
      {"--filter ukf --beta 1e300", "beta: must be in [-1e6, 1e6], got 1e+300"},
      {"--filter ekf --substeps 1000000000", "substeps: must be in [0, 100000], got 1000000000"},
      {"--filter ekf --substeps 4294967297", "substeps: must be in [0, 100000], got 4294967297"},
      {"--filter pf --particles 1000000000", "particles: must be in [1, 10000000], got 1000000000"},
      {"--filter ghkf --gh-order 4294967299", "gh-order: must be in [0, 100000], got 4294967299"},
  };
  for (const Case& c : cases) {
    const RunResult r = RunEstlab(filter + c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(dir.Exists("e.csv")) << c.args;
  }
  // simulate's own --substeps (an int option) has the transition's limit.
  const RunResult s = RunEstlab(
      "simulate --model pendulum --integrator rk4 --substeps 1000000000 --t-end 1 --out s.csv",
      dir.path());
  EXPECT_EQ(s.exit_code, 2) << s.err;
  EXPECT_NE(s.err.find("substeps: must be in [1, 100000]"), std::string::npos) << s.err;
  EXPECT_FALSE(dir.Exists("s.csv"));
}

// Issue 40 items 16, 17 and 19: the particle smoother's trajectories and
// clouds are checked before they are allocated, an option that does not apply is
// refused, and a FIFO given as data is refused instead of blocking forever.
TEST(LimitsCli, SmootherTrajectoriesAndFifoDataAreRefusedBeforeAnyWork) {
  TempDir dir;
  const std::string simulate = kPendulumSimulate;
  ASSERT_EQ(RunEstlab(simulate, dir.path()).exit_code, 0);
  std::string long_run = simulate;  // 4001 rows
  long_run.replace(long_run.find("--t-end 5 "), 10, "--t-end 50 ");
  long_run.replace(long_run.find("--out d.csv"), 11, "--out long.csv");
  ASSERT_EQ(RunEstlab(long_run, dir.path()).exit_code, 0);
  const std::string smooth =
      "smooth" + std::string(kPendulumFilter).substr(std::string("filter").size()) + "--out e.csv ";
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"--filter pf --smoother-trajectories 1000000000",
       "--smoother-trajectories must be in 2..100000, got 1000000000"},
      {"--filter pf --smoother-trajectories 100000 --particles 100 --data long.csv",
       "--smoother-trajectories 100000 over 4001 rows of long.csv would take 5.96"},
      // 1e7 particles x 4001 rows x (2 x 2 + 1) doubles = 1490.49 GiB of clouds
      // (a regression runs until memory runs out, or is killed).
      {"--filter pf --particles 10000000 --data long.csv",
       "the particle smoother's clouds of --particles 10000000 over 4001 rows of long.csv would "
       "take 1490.49 GiB (at most 4): fewer particles, or a shorter record"},
      {"--filter ekf --smoother-trajectories 50",
       "--smoother-trajectories applies to the particle smoother (--filter pf), not ekf"},
  };
  for (const Case& c : cases) {
    const std::string data = c.args.find("--data") == std::string::npos ? "--data d.csv " : "";
    const RunResult r = RunEstlab(smooth + data + c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(dir.Exists("e.csv")) << c.args;
  }
  ASSERT_EQ(std::system(("mkfifo '" + dir.File("fifo.csv") + "'").c_str()), 0);
  // (A regression blocks on the FIFO until ctest's time-out.)
  const RunResult fifo =
      RunEstlab(std::string(kPendulumFilter) + "--data fifo.csv --out f.csv", dir.path());
  EXPECT_EQ(fifo.exit_code, 2) << fifo.err;
  EXPECT_NE(fifo.err.find("data file 'fifo.csv' is not a regular file"), std::string::npos)
      << fifo.err;
  EXPECT_FALSE(dir.Exists("f.csv"));
}

}  // namespace
}  // namespace estlab::testing
