// Issue 40 item 1: with truth cells missing, each state's RMSE and MAE are
// over the rows where its truth is finite (recomputed here from the errors
// the run writes), the counts are printed and in --json ("truth_rows"), and
// a state with no finite truth has no RMSE (null), not 0. Before, the sums
// over the finite rows were divided by every row: 0.058197 instead of
// 0.082406 in the issue, and all-NaN truth printed an RMSE of 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

// d.csv with the theta truth cell emptied where keep(row) is false.
void WriteWithTheta(const TempDir& dir, const std::string& name, bool (*keep)(size_t)) {
  const auto lines = SplitLines(ReadFile(dir.File("d.csv")));
  std::ostringstream out;
  out << lines[0] << "\n";  // t,theta,omega,z_sin_theta
  for (size_t k = 1; k < lines.size(); ++k) {
    const size_t a = lines[k].find(','), b = lines[k].find(',', a + 1);
    out << (keep(k) ? lines[k] : lines[k].substr(0, a + 1) + lines[k].substr(b)) << "\n";
  }
  std::ofstream(dir.File(name)) << out.str();
}

// The number after `"KEY": {"theta": ` (the last one: a smoother's own).
double ThetaOf(const std::string& json, const std::string& key) {
  const std::string text = "\"" + key + "\": {\"theta\": ";
  const size_t at = json.rfind(text);
  if (at == std::string::npos) return -1.0;
  const std::string rest = json.substr(at + text.size());
  return rest.rfind("null", 0) == 0 ? std::nan("") : std::stod(rest);
}

// RMSE of the finite theta_err cells of `csv` and their count.
double RmseOfWrittenErrors(const std::string& csv, long* count) {
  const auto lines = SplitLines(csv);
  std::vector<std::string> head;
  std::stringstream h(lines[0]);
  for (std::string c; std::getline(h, c, ',');) head.push_back(c);
  const size_t col = size_t(std::find(head.begin(), head.end(), "theta_err") - head.begin());
  double sum = 0.0;
  *count = 0;
  for (size_t k = 1; k < lines.size(); ++k) {
    std::stringstream cells(lines[k]);
    std::string cell;
    for (size_t j = 0; j <= col; ++j) std::getline(cells, cell, ',');
    if (cell.empty()) continue;
    const double e = std::stod(cell);
    sum += e * e;
    ++*count;
  }
  return std::sqrt(sum / double(*count));
}

TEST(TruthRowsCli, RmseIsOverTheRowsWithFiniteTruthAndSaysHowMany) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  WriteWithTheta(dir, "half.csv", [](size_t k) { return k % 2 == 0; });
  const std::string smooth =
      "smooth" + std::string(kPendulumFilter).substr(std::string("filter").size());
  for (const std::string& command : {std::string(kPendulumFilter), smooth}) {
    const std::string run = command + "--data half.csv --truth theta,omega --out e.csv";
    const RunResult j = RunEstlab(run + " --json", dir.path());
    ASSERT_EQ(j.exit_code, 0) << j.err;
    long rows = 0;
    const double expected = RmseOfWrittenErrors(ReadFile(dir.File("e.csv")), &rows);
    EXPECT_EQ(rows, 200);
    EXPECT_NEAR(ThetaOf(j.out, "rmse"), expected, 1e-9 * expected) << j.out;
    EXPECT_EQ(ThetaOf(j.out, "truth_rows"), 200.0) << j.out;
    EXPECT_NE(j.out.find("\"truth_rows\": {\"theta\": 200, \"omega\": 401}"), std::string::npos)
        << j.out;
    const RunResult text = RunEstlab(run, dir.path());
    EXPECT_NE(
        text.out.find("(over the rows with finite truth: theta 200 of 401, omega 401 of 401)"),
        std::string::npos)
        << text.out;
  }
  // No finite theta truth at all: no RMSE (null), not 0.
  WriteWithTheta(dir, "none.csv", [](size_t) { return false; });
  const RunResult none = RunEstlab(
      std::string(kPendulumFilter) + "--data none.csv --truth theta,omega --json", dir.path());
  ASSERT_EQ(none.exit_code, 0) << none.err;
  EXPECT_NE(none.out.find("\"rmse\": {\"theta\": null, \"omega\": "), std::string::npos)
      << none.out;
  EXPECT_NE(none.out.find("\"truth_rows\": {\"theta\": 0, \"omega\": 401}"), std::string::npos)
      << none.out;
}

}  // namespace
}  // namespace estlab::testing
