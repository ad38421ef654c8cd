// Issue 15, "never lose or corrupt data", at the command level: an output that
// is one of the inputs is refused (exit 2, input unchanged byte for byte), and
// outputs that are not plain files (/dev/null, symlinks, long names) are
// written without replacing what is there.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
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
  const std::string sidecar = ReadFile(dir.File("d.csv.json"));
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
      // Issue 40 item 5: a sidecar read with its data file is an input too,
      // and simulate's own sidecar (OUT.json) is one of its outputs.
      {filter + "--data d.csv --out d.csv.json", "is the input file 'd.csv.json'"},
      {tune + "--data x.csv --validate d.csv --out d.csv.json", "is the input file 'd.csv.json'"},
      {"simulate --model pendulum --config d.csv.json --out d.csv",
       "--out (its sidecar) 'd.csv.json' is the input file 'd.csv.json'"},
  };
  for (const auto& c : cases) {
    const RunResult r = RunEstlab(c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error: "), std::string::npos) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(ReadFile(dir.File("d.csv")), data) << c.args;
    EXPECT_EQ(ReadFile(dir.File("c.ini")), config) << c.args;
    EXPECT_EQ(ReadFile(dir.File("d.csv.json")), sidecar) << c.args;
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

namespace estlab::testing {
namespace {

// Item 9: simulate writes t.csv and its sidecar t.csv.json; when the sidecar
// cannot be written (a full disk: /dev/full through a link) neither appears,
// not a CSV without its record of how it was made.
TEST(OutputSafetyCli, SimulateWritesTheCsvAndItsSidecarOrNeither) {
  TempDir dir;
  std::filesystem::create_symlink("/dev/full", dir.File("t.csv.json"));
  const RunResult r = RunEstlab(
      "simulate --model pendulum --x0 theta=0.5 --t-end 1 --dt 0.01 --out t.csv", dir.path());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.err.find("estlab: error: error while writing 't.csv.json'"), std::string::npos)
      << r.err;
  EXPECT_FALSE(dir.Exists("t.csv"));
  EXPECT_EQ(dir.Files(), (std::vector<std::string>{"t.csv.json"}));  // the link, still a link
  EXPECT_TRUE(std::filesystem::is_symlink(dir.File("t.csv.json")));
}

}  // namespace
}  // namespace estlab::testing

namespace estlab::testing {
namespace {

// Item 24, one rule for exit codes: an output that cannot be made (a results
// folder under a regular file; a read-only folder is the same error, but
// root, who runs CI, may write anywhere) exits 2 like bad input, with
// "estlab: error:", for every command that writes.
TEST(OutputSafetyCli, UnwritableOutputsExitTwo) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  { std::ofstream(dir.File("file")) << "x\n"; }
  const std::string study =
      "[study]\nseed = 1\nruns = 1\n\n[scenario.p]\nmodel = pendulum\nx0 = theta=0.5\n"
      "dt = 0.1\nsteps = 10\nmeasurement = angle\nmeas-noise-var = 0.01\n"
      "prior-p0-diag = 0.05,0.05\n\n[filter.ekf]\nkind = ekf\n\n"
      "[noise.oracle]\nq = oracle\nr = oracle\n";
  { std::ofstream(dir.File("s.ini")) << study; }
  for (const std::string& args : {std::string("study s.ini --quiet --out file/r"),
                                  std::string(kPendulumFilter) + "--data d.csv --out file/e.csv",
                                  std::string(kPendulumFilter) + "--data d.csv --plot file/plots",
                                  std::string("simulate --model pendulum --out file/t.csv")}) {
    const RunResult r = RunEstlab(args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out << r.err;
    EXPECT_EQ(r.err.rfind("estlab: error: ", 0), 0u) << args << ": " << r.err;
  }
}

}  // namespace
}  // namespace estlab::testing

namespace estlab::testing {
namespace {

// Item 10: SIGTERM during a long run removes its temporary output, and a
// temporary file of a process that is gone (a SIGKILL) is removed by the
// next estlab writing in that folder; one of a live process is left alone.
TEST(OutputSafetyCli, SignalsAndDeadProcessesLeaveNoTemporaryFiles) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kPendulumSimulate, dir.path()).exit_code, 0);
  // A particle filter of a million particles: seconds of work, its output
  // opened (as a temporary file) before it starts.
  const std::string cmd = "cd '" + dir.path() + "' && ('" + std::string(ESTLAB_BINARY) + "' " +
                          kPendulumFilter +
                          "--data d.csv --filter pf --particles 1000000 --out big.csv "
                          ">/dev/null 2>&1 & pid=$!; sleep 1; kill -TERM $pid; wait $pid; "
                          "echo $? > status) 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(ReadFile(dir.File("status")), "143\n");  // 128 + SIGTERM: the default action
  for (const auto& f : dir.Files()) EXPECT_EQ(f.find(".estlab-"), std::string::npos) << f;
  EXPECT_FALSE(dir.Exists("big.csv"));

  // Stale: pid 2^22 + 1 is above the largest pid Linux can give (2^22);
  // our own test process is alive.
  const std::string dead = ".estlab-4194305-0.tmp";
  const std::string live = ".estlab-" + std::to_string(::getpid()) + "-0.tmp";
  { std::ofstream(dir.File(dead)) << "partial"; }
  { std::ofstream(dir.File(live)) << "partial"; }
  ASSERT_EQ(
      RunEstlab(std::string(kPendulumFilter) + "--data d.csv --out e.csv", dir.path()).exit_code,
      0);
  EXPECT_FALSE(dir.Exists(dead));
  EXPECT_TRUE(dir.Exists(live));
}

}  // namespace
}  // namespace estlab::testing
