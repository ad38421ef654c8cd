// End-to-end tests of `estlab simulate` (and the top-level help/version/list
// entry points): bad input exits 2 with "estlab: error: " naming the bad value
// and writes nothing; a CVODES failure exits 1 and keeps the rows computed so
// far in <stem>.partial.csv; seeds make runs reproducible; the CSV header and
// the JSON sidecar carry what a study needs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "src/sim/input_signal.h"
#include "tests/cli/cli_test_util.h"

namespace estlab {
namespace {

using testing::ReadFile;
using testing::RunEstlab;
using testing::SplitLines;
using testing::TempDir;

struct BadInputCase {
  const char* label;
  std::string args;      // full argument list after "estlab"
  std::string mentions;  // text the error message must contain (the bad value)
};

const std::string kDp = "simulate --model double-pendulum --t-end 0.1 --out out.csv ";

std::vector<BadInputCase> BadInputCases() {
  return {
      {"unknown model", "simulate --model nosuch-model --out out.csv", "nosuch-model"},
      {"unknown parameter", kDp + "--param gravity=9.8", "gravity"},
      {"unknown state", kDp + "--x0 phi=0.1", "phi"},
      {"unknown integrator", kDp + "--integrator rk5", "rk5"},
      {"unknown input hold", kDp + "--input-hold cubic",
       "--input-hold: unknown input hold 'cubic'"},
      {"too many meas-noise-var", kDp + "--measure angles --meas-noise-var 0.1,0.2,0.3",
       "--meas-noise-var"},
      {"too few meas-noise-var", kDp + "--measure angles --meas-noise-var 0.1", "got 1"},
      {"too few process-noise-var", kDp + "--process-noise-var 1e-6,1e-6", "--process-noise-var"},
      {"too many process-noise-var", kDp + "--process-noise-var 1,2,3,4,5", "got 5"},
      {"dt zero", kDp + "--dt 0", "--dt"},
      {"dt negative", kDp + "--dt -0.01", "-0.01"},
      {"t-end negative", "simulate --model double-pendulum --out out.csv --t-end -1", "-1"},
      {"x0 nan", kDp + "--x0 theta1=nan", "nan"},
      {"x0 inf", kDp + "--x0 theta2=inf", "inf"},
      {"param nan", kDp + "--param g=nan", "nan"},
      {"param inf", kDp + "--param L1=inf", "inf"},
      {"dt nan", kDp + "--dt nan", "nan"},
      {"dt inf", kDp + "--dt inf", "inf"},
      {"negative meas variance", kDp + "--measure angles --meas-noise-var 0.1,-0.5", "-0.5"},
      {"negative process variance", kDp + "--process-noise-var 0,0,-0.25,0", "-0.25"},
      {"input signal on a model without input",
       "simulate --model pendulum --input 'steps(0, 1:2)' --out out.csv", "has no input"},
      {"input signal missing key",
       "simulate --model cart-pole --input 'prbs(period=2)' --out out.csv", "'amplitude='"},
      {"input signal with --data",
       "simulate --model cart-pole --input 'steps(0, 1:2)' --data nosuch.csv --out out.csv",
       "--input does not apply"},
      {"unwritable output",
       "simulate --model double-pendulum --t-end 0.1 --out /nonexistent/dir/x.csv",
       "/nonexistent/dir/x.csv"},
  };
}

TEST(SimulateCli, BadInputExits2NamesTheValueAndWritesNothing) {
  for (const BadInputCase& c : BadInputCases()) {
    SCOPED_TRACE(std::string(c.label) + ": estlab " + c.args);
    TempDir dir;
    const auto r = RunEstlab(c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("estlab: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos)
        << "stderr does not mention '" << c.mentions << "': " << r.err;
    // No out.csv, no sidecar, no out.csv.tmp.<pid>: nothing at all.
    EXPECT_TRUE(dir.Files().empty()) << "left behind: " << dir.Files().front();
  }
}

TEST(SimulateCli, CvodesTooMuchWorkOnVanDerPolKeepsPartialRows) {
  TempDir dir;
  const auto r = RunEstlab(
      "simulate --model van-der-pol --x0 x=2 --t-end 10 --dt 1 --max-steps 1 --out vdp.csv",
      dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(r.err.rfind("estlab: error: ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find("CV_TOO_MUCH_WORK"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("vdp.partial.csv"), std::string::npos) << r.err;
  EXPECT_FALSE(dir.Exists("vdp.csv"));
  EXPECT_FALSE(dir.Exists("vdp.csv.json"));
  ASSERT_TRUE(dir.Exists("vdp.partial.csv"));
  for (const auto& f : dir.Files()) EXPECT_EQ(f.find(".tmp."), std::string::npos) << f;
  const auto lines = SplitLines(ReadFile(dir.File("vdp.partial.csv")));
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "t,x,y");
  EXPECT_EQ(lines[1], "0,2,0");
}

TEST(SimulateCli, CvodesFailureOnDoublePendulumKeepsRowsSoFar) {
  TempDir dir;
  const auto r = RunEstlab(
      "simulate --model double-pendulum --x0 theta1=1.5707963267948966,theta2=1.5707963267948966"
      " --t-end 1 --dt 0.01 --rtol 1e-10 --max-steps 5 --out run.csv",
      dir.path());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("CV_TOO_MUCH_WORK"), std::string::npos) << r.err;
  EXPECT_FALSE(dir.Exists("run.csv"));
  ASSERT_TRUE(dir.Exists("run.partial.csv"));
  for (const auto& f : dir.Files()) EXPECT_EQ(f.find(".tmp."), std::string::npos) << f;
  const auto lines = SplitLines(ReadFile(dir.File("run.partial.csv")));
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "t,theta1,omega1,theta2,omega2");
  EXPECT_EQ(lines[1].rfind("0,1.5707963267948966,0,1.5707963267948966,0", 0), 0u) << lines[1];
  // Fewer rows than a full run (101 data rows).
  EXPECT_LT(lines.size(), 102u);
}

const std::string kNoisy =
    "simulate --model double-pendulum --x0 theta1=0.785398,theta2=0.523599 --t-end 1 --dt 0.01"
    " --measure angles --meas-noise-var 0.0025,0.0016"
    " --process-noise-var 1e-8,1e-6,1e-8,1e-6";

TEST(SimulateCli, SameSeedGivesIdenticalFilesDifferentSeedDiffers) {
  TempDir dir;
  ASSERT_EQ(RunEstlab(kNoisy + " --seed 7 --out a.csv", dir.path()).exit_code, 0);
  ASSERT_EQ(RunEstlab(kNoisy + " --seed 7 --out b.csv", dir.path()).exit_code, 0);
  ASSERT_EQ(RunEstlab(kNoisy + " --seed 8 --out c.csv", dir.path()).exit_code, 0);
  const std::string a = ReadFile(dir.File("a.csv"));
  const std::string b = ReadFile(dir.File("b.csv"));
  const std::string c = ReadFile(dir.File("c.csv"));
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // Same header and the same t = 0 state; only the noise differs.
  const auto la = SplitLines(a), lc = SplitLines(c);
  ASSERT_EQ(la.size(), 102u);
  ASSERT_EQ(lc.size(), 102u);
  EXPECT_EQ(la[0], lc[0]);
  auto states = [](const std::string& row) {  // t and the four states
    size_t pos = 0;
    for (int i = 0; i < 5; ++i) pos = row.find(',', pos) + 1;
    return row.substr(0, pos);
  };
  EXPECT_EQ(states(la[1]), "0,0.78539800000000004,0,0.52359900000000004,0,");  // %.17g
  EXPECT_EQ(states(la[1]), states(lc[1]));
  EXPECT_NE(la[1], lc[1]);
}

// Parses the JSON array of numbers following "key": in `json`.
std::vector<double> JsonNumberArray(const std::string& json, const std::string& key) {
  std::vector<double> values;
  const auto k = json.find("\"" + key + "\": [");
  if (k == std::string::npos) return values;
  const char* p = json.c_str() + json.find('[', k) + 1;
  while (*p != ']' && *p != '\0') {
    char* end = nullptr;
    values.push_back(std::strtod(p, &end));
    if (end == p) break;
    p = end;
    while (*p == ',' || *p == ' ') ++p;
  }
  return values;
}

TEST(SimulateCli, HeaderAndSidecar) {
  TempDir dir;
  const auto r = RunEstlab(kNoisy + " --seed 12345 --out traj.csv", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = SplitLines(ReadFile(dir.File("traj.csv")));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "t,theta1,omega1,theta2,omega2,z_theta1,z_theta2");
  EXPECT_EQ(lines.back().substr(0, 2), "1,");
  ASSERT_TRUE(dir.Exists("traj.csv.json"));
  const std::string json = ReadFile(dir.File("traj.csv.json"));
  EXPECT_NE(json.find("\"seed\": 12345"), std::string::npos) << json;
  EXPECT_NE(json.find("\"model\": \"double-pendulum\""), std::string::npos) << json;
  const auto meas = JsonNumberArray(json, "meas_noise_var");
  ASSERT_EQ(meas.size(), 2u) << json;
  EXPECT_DOUBLE_EQ(meas[0], 0.0025);
  EXPECT_DOUBLE_EQ(meas[1], 0.0016);
  const auto proc = JsonNumberArray(json, "process_noise_var");
  ASSERT_EQ(proc.size(), 4u) << json;
  EXPECT_DOUBLE_EQ(proc[0], 1e-8);
  EXPECT_DOUBLE_EQ(proc[1], 1e-6);
  EXPECT_DOUBLE_EQ(proc[2], 1e-8);
  EXPECT_DOUBLE_EQ(proc[3], 1e-6);
  for (const auto& f : dir.Files()) EXPECT_EQ(f.find(".tmp."), std::string::npos) << f;
}

// --input with a signal: the force column after the states holds the
// signal at each row's time (the definition, src/sim/input_signal.h), and the
// sidecar names it.
TEST(SimulateCli, InputSignalIsWrittenAsTheInputColumn) {
  TempDir dir;
  const std::string signal = "prbs(amplitude=2, period=0.2, order=7, seed=5)";
  const auto r = RunEstlab("simulate --model cart-pole --input '" + signal +
                               "' --t-end 2 --dt 0.02 --integrator rk4 --out cart.csv",
                           dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<std::string> lines = SplitLines(ReadFile(dir.File("cart.csv")));
  ASSERT_EQ(lines.size(), 102u);  // header + t = 0, 0.02, ..., 2
  EXPECT_EQ(lines[0], "t,x,v,theta,omega,u");
  const InputSignal expected = ParseInputSignal(signal, "input");
  double moved = 0.0;
  for (size_t i = 1; i < lines.size(); ++i) {
    const double t = std::stod(lines[i]);
    const double u = std::stod(lines[i].substr(lines[i].rfind(',') + 1));
    EXPECT_EQ(u, expected.At(t)) << lines[i];
    moved = std::max(moved, std::abs(std::stod(lines[i].substr(lines[i].find(',') + 1))));
  }
  EXPECT_GT(moved, 1e-3);  // the force moved the cart
  const std::string sidecar = ReadFile(dir.File("cart.csv.json"));
  EXPECT_NE(sidecar.find("\"input\": \"" + signal + ", sampled at the output times"),
            std::string::npos)
      << sidecar;
  EXPECT_NE(sidecar.find("\"dt\": 0.02"), std::string::npos) << sidecar;
}

// The same PRBS force held (zoh) and drawn as lines (linear): the sidecar
// says which, and the states differ.
TEST(SimulateCli, InputHoldIsRecordedAndChangesTheTrajectory) {
  TempDir dir;
  const std::string base =
      "simulate --model cart-pole --input 'prbs(amplitude=2, period=0.2, order=7, seed=5)' "
      "--t-end 2 --dt 0.02 --integrator rk4 ";
  ASSERT_EQ(RunEstlab(base + "--out zoh.csv", dir.path()).exit_code, 0);
  const auto r = RunEstlab(base + "--input-hold linear --out linear.csv", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(ReadFile(dir.File("zoh.csv.json")).find("\"input_hold\": \"zoh\""), std::string::npos);
  EXPECT_NE(ReadFile(dir.File("linear.csv.json")).find("\"input_hold\": \"linear\""),
            std::string::npos);
  const std::vector<std::string> a = SplitLines(ReadFile(dir.File("zoh.csv")));
  const std::vector<std::string> b = SplitLines(ReadFile(dir.File("linear.csv")));
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a[1], b[1]);  // x0
  EXPECT_NE(a.back(), b.back());
}

TEST(SimulateCli, HelpVersionAndListExitZero) {
  TempDir dir;
  const auto help = RunEstlab("--help", dir.path());
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_NE(help.out.find("simulate"), std::string::npos);

  const auto sim_help = RunEstlab("simulate --help", dir.path());
  EXPECT_EQ(sim_help.exit_code, 0) << sim_help.err;
  EXPECT_NE(sim_help.out.find("--meas-noise-var"), std::string::npos);

  const auto version = RunEstlab("--version", dir.path());
  EXPECT_EQ(version.exit_code, 0) << version.err;
  EXPECT_EQ(version.out.rfind("estlab ", 0), 0u) << version.out;

  const auto list = RunEstlab("list --json", dir.path());
  EXPECT_EQ(list.exit_code, 0) << list.err;
  ASSERT_FALSE(list.out.empty());
  EXPECT_EQ(list.out.front(), '{');
  for (const char* model : {"pendulum", "double-pendulum", "cart-pole", "dipc", "van-der-pol"})
    EXPECT_NE(list.out.find("\"name\": \"" + std::string(model) + "\""), std::string::npos)
        << model;
  EXPECT_TRUE(dir.Files().empty());
}

}  // namespace
}  // namespace estlab
