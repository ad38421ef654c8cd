// Issue 15 items 13 and 25: absurd sizes and sigma-point parameters are
// refused (exit 2, the option and its limit named, no output) instead of
// hanging, exhausting memory or running a filter that never moves.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace estlab::testing
