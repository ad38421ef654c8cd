// Issue 15 item 5: non-finite statistics are a divergence, not "status ok".
// A finite but absurd measurement (1e308) used to give nis = inf, loglik =
// -inf and exit 0; an all-missing --validate file printed "nan nan".
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

// 20 rows of z_sin_theta near sin(pi / 4), row `bad` (0-based) set to `value`.
void WriteData(const TempDir& dir, const std::string& name, int bad, const std::string& value) {
  std::ofstream out(dir.File(name));
  out << "t,z_sin_theta\n";
  for (int k = 0; k < 20; ++k)
    out << k * 0.0125 << "," << (k == bad ? value : std::to_string(0.7 + 0.001 * k)) << "\n";
}

TEST(NonFiniteCli, AbsurdMeasurementStopsTheFilterWithStepAndTime) {
  TempDir dir;
  WriteData(dir, "d.csv", 10, "1e308");
  const RunResult r =
      RunEstlab(std::string(kPendulumFilter) + "--filter ekf --data d.csv --out e.csv", dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE((r.out + r.err).find("stopped at step 10 (t = 0.125"), std::string::npos)
      << r.out << r.err;
  EXPECT_NE((r.out + r.err).find("the innovation statistics are not finite"), std::string::npos)
      << r.out << r.err;
  // The rows before it are kept.
  ASSERT_TRUE(dir.Exists("e.csv"));
  const auto lines = SplitLines(ReadFile(dir.File("e.csv")));
  EXPECT_EQ(lines.size(), 11u) << ReadFile(dir.File("e.csv"));  // header + rows 0..9
}

TEST(NonFiniteCli, ValidationRefusesAnAllMissingFileAndShowsADivergence) {
  TempDir dir;
  WriteData(dir, "train.csv", -1, "");
  WriteData(dir, "absurd.csv", 10, "1e308");
  {
    std::ofstream out(dir.File("empty.csv"));
    out << "t,z_sin_theta\n0,nan\n0.0125,\n";
  }
  const std::string tune =
      "tune --model pendulum --param g=9.8 --measure sin --integrator euler --filter ekf "
      "--x0 theta=0.785398 --p0-diag 0.1,0.1 --init-q-white-accel 1 --init-r-diag 0.1 "
      "--data train.csv ";
  const RunResult empty = RunEstlab(tune + "--validate empty.csv", dir.path());
  EXPECT_EQ(empty.exit_code, 2) << empty.out << empty.err;
  EXPECT_NE(empty.err.find("empty.csv: measurement column z_sin_theta has no value"),
            std::string::npos)
      << empty.err;
  const RunResult absurd = RunEstlab(tune + "--validate absurd.csv", dir.path());
  EXPECT_EQ(absurd.exit_code, 0) << absurd.err;
  EXPECT_NE(absurd.out.find("(diverged)"), std::string::npos) << absurd.out;
  EXPECT_EQ(absurd.out.find(" inf "), std::string::npos) << absurd.out;
}

}  // namespace
}  // namespace estlab::testing
