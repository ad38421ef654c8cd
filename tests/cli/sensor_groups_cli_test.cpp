// Sensor groups from the command line (issue 35): a cart-pole whose cart
// position comes at 1 Hz and whose pole encoder at 100 Hz, simulated with
// --sensor-rate, filtered with --measure position,encoder and an R per
// group, with each group's NIS reported; and the bad inputs of sensor
// groups, each `estlab: error:` naming the value, exit 2, nothing written.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

constexpr const char* kSimulate =
    "simulate --model cart-pole --x0 theta=3 --t-end 20 --dt 0.01 --measure position,encoder "
    "--meas-noise-var 1e-4,1e-4 --sensor-rate position=1 --seed 4 --out mr.csv";
constexpr const char* kFilter =
    "filter --model cart-pole --x0 theta=3 --p0-diag 1e-4,1e-4,1e-4,1e-4 --filter ekf "
    "--q-diag 1e-10,1e-10,1e-10,1e-10 --measure position,encoder --r-diag position=1e-4 "
    "--r-diag encoder=1e-4 --data mr.csv --input 0 ";

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

class SensorGroupsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto sim = RunEstlab(kSimulate, dir_.path());
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
  }
  // Runs args, expects exit 2 with `message` in an `estlab: error:` line and
  // no file `out` written.
  void ExpectRefused(const std::string& args, const std::string& message,
                     const std::string& out = "o.csv") {
    const auto r = RunEstlab(args, dir_.path());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos)
        << args << "\nexpected: " << message << "\ngot: " << r.err;
    EXPECT_FALSE(dir_.Exists(out)) << args;
  }
  TempDir dir_;
};

TEST_F(SensorGroupsCli, SlowGroupCellsAreEmptyBetweenItsSamples) {
  const std::vector<std::string> lines = SplitLines(ReadFile(dir_.File("mr.csv")));
  ASSERT_EQ(lines.size(), 2002u);
  EXPECT_EQ(lines[0], "t,x,v,theta,omega,z_x,z_theta");
  int positions = 0;
  for (size_t k = 1; k < lines.size(); ++k) {
    const size_t last = lines[k].rfind(',');
    const size_t before = lines[k].rfind(',', last - 1);
    const bool has_x = last > before + 1;
    EXPECT_EQ(has_x, (k - 1) % 100 == 0) << lines[k];
    EXPECT_GT(lines[k].size(), last + 1) << "z_theta in every row: " << lines[k];
    positions += has_x;
  }
  EXPECT_EQ(positions, 21);
}

TEST_F(SensorGroupsCli, FilterReportsEachGroupsNis) {
  const auto r = RunEstlab(std::string(kFilter) + "--out o.csv --json", dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("\"group_nis\": {\"position\": {\"updates\": 21,"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("\"encoder\": {\"updates\": 2001,"), std::string::npos) << r.out;
  const auto text = RunEstlab(std::string(kFilter) + "--out o2.csv", dir_.path());
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("  position      "), std::string::npos) << text.out;
  EXPECT_NE(text.out.find(", 21 updates)"), std::string::npos) << text.out;
  // The position's innovation is empty where the position is missing: in
  // rows 1..99 after the first, not in rows 0 and 100.
  const std::vector<std::string> lines = SplitLines(ReadFile(dir_.File("o2.csv")));
  ASSERT_GT(lines.size(), 102u);
  auto cell = [&](size_t row, const std::string& column) {
    std::vector<std::string> names, cells;
    std::string part;
    std::stringstream h(lines[0]), c(lines[row]);
    while (std::getline(h, part, ',')) names.push_back(part);
    while (std::getline(c, part, ',')) cells.push_back(part);
    cells.resize(names.size());
    for (size_t j = 0; j < names.size(); ++j)
      if (names[j] == column) return cells[j];
    ADD_FAILURE() << "no column " << column << " in " << lines[0];
    return std::string();
  };
  EXPECT_NE(cell(1, "nu_x"), "");
  EXPECT_EQ(cell(2, "nu_x"), "");
  EXPECT_NE(cell(2, "nu_theta"), "");
  EXPECT_NE(cell(101, "nu_x"), "");
}

TEST_F(SensorGroupsCli, BadGroupInputIsRefusedNamingIt) {
  const std::string base =
      "filter --model cart-pole --x0 theta=3 --filter ekf --q-diag 1e-10,1e-10,1e-10,1e-10 "
      "--data mr.csv --input 0 --out o.csv ";
  ExpectRefused(base + "--measure position,position --r-diag 1e-4,1e-4",
                "sensor group 'position' is named twice in 'position,position'");
  ExpectRefused(base + "--measure position,gyro --r-diag 1e-4,1e-4",
                "unknown sensor group 'gyro' in 'position,gyro' for model 'cart-pole'");
  ExpectRefused(base + "--measure position,encoder --r-diag gyro=1e-4 --r-diag position=1",
                "--r-diag: unknown sensor group 'gyro' (groups of x-theta: position, encoder)");
  ExpectRefused(base + "--measure position,encoder --r-diag encoder=1e-4 --r encoder=1",
                "--r: sensor group 'encoder' is given twice");
  ExpectRefused(base + "--measure position,encoder --r-diag encoder=1e-4",
                "no R for sensor group 'position'");
  // A group's column missing from the data.
  std::string cut;
  for (const std::string& line : SplitLines(ReadFile(dir_.File("mr.csv"))))
    cut += line.substr(0, line.rfind(',', line.rfind(',') - 1)) + "," +
           line.substr(line.rfind(',') + 1) + "\n";
  WriteText(dir_.File("cut.csv"), cut);
  ExpectRefused(
      "filter --model cart-pole --x0 theta=3 --filter ekf --q-diag 1e-10,1e-10,1e-10,1e-10 "
      "--measure position,encoder --r-diag 1e-4,1e-4 --data cut.csv --input 0 --out o.csv",
      "no measurement column 'z_x' for output 'x' of measurement 'x-theta'");
  // A row earlier than the one before it.
  std::vector<std::string> lines = SplitLines(ReadFile(dir_.File("mr.csv")));
  std::swap(lines[5], lines[6]);
  std::string swapped;
  for (const std::string& line : lines) swapped += line + "\n";
  WriteText(dir_.File("swapped.csv"), swapped);
  ExpectRefused(
      "filter --model cart-pole --x0 theta=3 --filter ekf --q-diag 1e-10,1e-10,1e-10,1e-10 "
      "--measure position,encoder --r-diag 1e-4,1e-4 --data swapped.csv --input 0 --out o.csv",
      "swapped.csv:7: column 1 ('t'): time goes backwards");
  // Rates: a group named twice, one that is not a whole number of rows.
  ExpectRefused(
      "simulate --model cart-pole --t-end 1 --dt 0.01 --measure x-theta --sensor-rate position=1 "
      "--sensor-every position=5 --out s.csv",
      "--sensor-every: sensor group 'position' is given twice", "s.csv");
  ExpectRefused(
      "simulate --model cart-pole --t-end 1 --dt 0.01 --measure x-theta --sensor-rate position=3 "
      "--out s.csv",
      "--sensor-rate: position at 3 Hz is 33.3", "s.csv");
  // The tuner's R per group: every group once.
  ExpectRefused(
      "tune --model cart-pole --x0 theta=3 --filter ekf --init-q-diag 1e-10,1e-10,1e-10,1e-10 "
      "--q-param fixed --measure position,encoder --init-r-diag 1e-4,1e-4 --r-param "
      "position=scalar --data mr.csv --input 0 --out t.ini",
      "--r-param: no kind for sensor group 'encoder'", "t.ini");
  ExpectRefused(
      "tune --model cart-pole --x0 theta=3 --filter ekf --init-q-diag 1e-10,1e-10,1e-10,1e-10 "
      "--q-param fixed --measure position,encoder --init-r-diag 1e-4,1e-4 --r-param "
      "position=scalar,position=full --data mr.csv --input 0 --out t.ini",
      "--r-param: sensor group 'position' is given twice", "t.ini");
}

// A row per sensor: no row has both the position and the angle, so a full
// R's covariance of the two is not in the likelihood; the tuner says so
// before the fit (and not for the multi-rate file, whose rows at t = 0, 1, ...
// have both).
TEST_F(SensorGroupsCli, TunerNotesAFullRCovarianceNoRowObserves) {
  std::string split;
  const std::vector<std::string> lines = SplitLines(ReadFile(dir_.File("mr.csv")));
  split += lines[0] + "\n";
  for (size_t k = 1; k < lines.size(); ++k) {
    const size_t last = lines[k].rfind(',');
    const size_t before = lines[k].rfind(',', last - 1);
    const std::string head = lines[k].substr(0, before);      // t and the states
    split += head + ",," + lines[k].substr(last + 1) + "\n";  // the angle alone
    if (last > before + 1)  // and the position alone, at the same time
      split += head + "," + lines[k].substr(before + 1, last - before - 1) + ",\n";
  }
  WriteText(dir_.File("split.csv"), split);
  const std::string tune =
      "tune --model cart-pole --x0 theta=3 --p0-diag 1e-4,1e-4,1e-4,1e-4 --filter ekf "
      "--init-q-diag 1e-10,1e-10,1e-10,1e-10 --q-param fixed --measure x-theta "
      "--init-r '1e-4,0;0,1e-4' --r-param full --input 0 --max-iterations 1 --data ";
  const auto r = RunEstlab(tune + "split.csv", dir_.path());
  EXPECT_NE(r.err.find("estlab: note: no row observes both outputs of R(x,theta)"),
            std::string::npos)
      << r.err;
  const auto both = RunEstlab(tune + "mr.csv", dir_.path());
  EXPECT_EQ(both.err.find("no row observes"), std::string::npos) << both.err;
}

}  // namespace
}  // namespace estlab::testing
