// Issue 14, "the first hour with your own data": what a new user meets on
// the command line. filter without --out (summary only), units in
// 'estlab list', 'estlab tune --help' showing only the options tune reads.
#include <gtest/gtest.h>

#include <cstdlib>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

const std::string kFilterArgs = kFilterWithoutR;  // each test adds its --r-diag

TEST(FirstHourCli, FilterWithoutOutPrintsTheSummaryAndWritesNoFile) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const RunResult r = RunEstlab(std::string(kFilterArgs) + "--r-diag 0.1 --filter ekf", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("mean NIS"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
  EXPECT_EQ(dir.Files(), (std::vector<std::string>{"d.csv", "d.csv.json"}));  // simulate's
  // With --out the file is written and named.
  const RunResult w =
      RunEstlab(std::string(kFilterArgs) + "--r-diag 0.1 --filter ekf --out e.csv", dir.path());
  ASSERT_EQ(w.exit_code, 0) << w.err;
  EXPECT_NE(w.out.find("wrote           e.csv"), std::string::npos) << w.out;
  EXPECT_TRUE(dir.Exists("e.csv"));
}

TEST(FirstHourCli, ListPrintsParameterUnits) {
  TempDir dir;
  const RunResult r = RunEstlab("list", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("g=9.81 [m/s^2], L=1 [m], b=0 [1/s]"), std::string::npos) << r.out;
  const RunResult one = RunEstlab("list --model pendulum", dir.path());
  EXPECT_NE(one.out.find("L=1 [m]"), std::string::npos) << one.out;
}

TEST(FirstHourCli, TuneHelpListsOnlyTheOptionsTuneReads) {
  TempDir dir;
  const RunResult tune = RunEstlab("tune --help", dir.path());
  ASSERT_EQ(tune.exit_code, 0) << tune.err;
  for (const char* absent : {"--particles", "--resample", "--ess-threshold", "--full-cov", "| pf"})
    EXPECT_EQ(tune.out.find(absent), std::string::npos) << absent << " in:\n" << tune.out;
  for (const char* present :
       {"kf | ekf | iekf | ukf | ckf | ghkf", "--init-q-diag", "--alpha", "--seed", "Examples:"})
    EXPECT_NE(tune.out.find(present), std::string::npos) << present << " not in:\n" << tune.out;
  // filter keeps them all.
  const RunResult filter = RunEstlab("filter --help", dir.path());
  for (const char* present : {"--particles", "--full-cov", "ghkf | pf", "Examples:"})
    EXPECT_NE(filter.out.find(present), std::string::npos) << present;
}

// The data has R = 0.1. R = 1e-3 makes the innovations 100x larger than S
// predicts (mean NIS ~ 100, far above); R = 10 makes them ~100x smaller (far
// below); R = 0.1 is inside or near the bounds: no line.
TEST(FirstHourCli, FilterSaysWhenTheMeanNisIsFarOutsideItsBounds) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const std::string run = std::string(kFilterArgs) + "--filter ukf --r-diag ";
  const RunResult high = RunEstlab(run + "1e-3", dir.path());
  ASSERT_EQ(high.exit_code, 0) << high.err;
  EXPECT_NE(high.out.find("NIS check       the mean NIS is far above its 95% bounds"),
            std::string::npos)
      << high.out;
  EXPECT_NE(high.out.find("Q or R too small (try 'estlab tune')"), std::string::npos);
  EXPECT_NE(high.out.find("--column"), std::string::npos);
  const RunResult low = RunEstlab(run + "10", dir.path());
  ASSERT_EQ(low.exit_code, 0) << low.err;
  EXPECT_NE(low.out.find("the mean NIS is far below its 95% bounds"), std::string::npos) << low.out;
  EXPECT_NE(low.out.find("Q or R too large"), std::string::npos);
  const RunResult right = RunEstlab(run + "0.1", dir.path());
  ASSERT_EQ(right.exit_code, 0) << right.err;
  EXPECT_EQ(right.out.find("NIS check"), std::string::npos) << right.out;
}

// Issue 14 item 5: Sage-Husa on Q and R with a short memory clips more often
// than there are steps (607 clips in 401 updates here): the text says that it
// counts adapted matrices, two per update.
TEST(FirstHourCli, AdaptationClipsAreCountedPerAdaptedMatrix) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const std::string run =
      "filter --model pendulum --param g=9.8 --measure sin --data d.csv "
      "--integrator euler --x0 theta=0.785398 --p0-diag 0.1,0.1 "
      "--q-diag 1e-6,1e-4 --r-diag 0.1 --adapt sage-husa --forgetting 0.5 ";
  const RunResult qr = RunEstlab(run + "--adapt-what qr", dir.path());
  ASSERT_EQ(qr.exit_code, 0) << qr.err;
  const size_t at = qr.out.find("adaptation      ");
  ASSERT_NE(at, std::string::npos) << qr.out;
  const long clips = std::atol(qr.out.c_str() + at + 16);
  EXPECT_GT(clips, 401) << qr.out;  // more than the updates ...
  EXPECT_LE(clips, 2 * 401);        // ... at most one per matrix per update
  EXPECT_NE(qr.out.find(" clip(s): adapted Q or R matrices with an eigenvalue raised to the "
                        "floor 1e-10 to stay positive definite (one count per adapted matrix; "
                        "2 matrices per update, 401 updates)"),
            std::string::npos)
      << qr.out;
  const RunResult help = RunEstlab("filter --help", dir.path());
  EXPECT_NE(help.out.find("counts the adapted Q and R matrices"), std::string::npos);
}

}  // namespace
}  // namespace estlab::testing
