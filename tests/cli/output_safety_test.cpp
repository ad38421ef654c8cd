// Issue 15, "never lose or corrupt data", at the command level: an output that
// is one of the inputs is refused (exit 2, input unchanged byte for byte), and
// outputs that are not plain files (/dev/null, symlinks, long names) are
// written without replacing what is there.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cli_test_util.h"

namespace estlab::testing {
namespace {

TEST(OutputSafetyCli, OutputThatIsAnInputIsRefused) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  {
    std::ofstream f(dir.File("c.ini"));
    f << "r-diag = 0.1\n";
  }
  std::filesystem::create_symlink("d.csv", dir.File("link.csv"));
  const std::string data = ReadFile(dir.File("d.csv"));
  const std::string config = ReadFile(dir.File("c.ini"));
  struct Case {
    std::string args;
    std::string expect;
  };
  const std::string filter = kPendulumFilter;
  const std::string tune = "tune --model pendulum --measure sin --filter ekf ";
  const std::vector<Case> cases = {
      {filter + "--data d.csv --out d.csv", "--out 'd.csv' is the input file 'd.csv'"},
      {filter + "--data d.csv --out ./d.csv", "--out './d.csv' is the input file 'd.csv'"},
      {filter + "--data d.csv --out link.csv", "'link.csv' is the input file 'd.csv'"},
      {filter + "--data d.csv --config c.ini --out c.ini", "is the input file 'c.ini'"},
      {tune + "--data d.csv --out d.csv", "--out 'd.csv' is the input file 'd.csv'"},
      {tune + "--data x.csv --data d.csv --out ./d.csv", "is the input file 'd.csv'"},
      {tune + "--data x.csv --validate d.csv --out d.csv", "is the input file 'd.csv'"},
      {tune + "--data x.csv --config c.ini --out c.ini", "is the input file 'c.ini'"},
  };
  for (const auto& c : cases) {
    const RunResult r = RunEstlab(c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error: "), std::string::npos) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(ReadFile(dir.File("d.csv")), data) << c.args;
    EXPECT_EQ(ReadFile(dir.File("c.ini")), config) << c.args;
    EXPECT_TRUE(std::filesystem::is_symlink(dir.File("link.csv"))) << c.args;
  }
  EXPECT_EQ(dir.Files(), (std::vector<std::string>{"c.ini", "d.csv", "d.csv.json", "link.csv"}));
}

TEST(OutputSafetyCli, NonRegularOutputsAreWrittenInPlace) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  const std::string filter = std::string(kPendulumFilter) + "--data d.csv ";
  // A device (through a link, so that a regressed build run as root replaces
  // the link and not /dev/null itself): written directly, stays a device.
  std::filesystem::create_symlink("/dev/null", dir.File("null.csv"));
  RunResult r = RunEstlab(filter + "--out null.csv", dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::is_symlink(dir.File("null.csv")));
  ASSERT_TRUE(std::filesystem::is_character_file("/dev/null"));
  // A symlink: its target is replaced, the link stays a link.
  std::filesystem::create_directory(dir.File("real"));
  { std::ofstream(dir.File("real/e.csv")) << "old\n"; }
  std::filesystem::create_symlink("real/e.csv", dir.File("e.csv"));
  r = RunEstlab(filter + "--out e.csv", dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::is_symlink(dir.File("e.csv")));
  EXPECT_EQ(ReadFile(dir.File("real/e.csv")).rfind("t,", 0), 0u);
  EXPECT_EQ(dir.Files(),
            (std::vector<std::string>{"d.csv", "d.csv.json", "e.csv", "null.csv", "real"}));
  // A 250-byte name: the temporary name must stay under the 255-byte limit.
  const std::string long_name = std::string(246, 'x') + ".csv";
  r = RunEstlab(filter + "--out " + long_name, dir.path());
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(dir.Exists(long_name));
  EXPECT_EQ(dir.Files().size(), 6u);  // no temporary file left behind
}

}  // namespace
}  // namespace estlab::testing
