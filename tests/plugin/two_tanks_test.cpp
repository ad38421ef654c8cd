// The two-tank example (examples/two_tanks/): its README walkthrough as
// written, output error and prediction error with the initial state
// estimated on 50 simulated data sets each (coverage of the truth by 2
// standard errors, the squared error or NLL at the estimate at most that at
// the truth), three experiments with their own initial states
// (--x0-per-file, both methods), and a relative --model-cache on a first
// compile. Label "plugin": the model file compiles (about a minute).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli/cli_test_util.h"
#include "plugin/plugin_test_util.h"

namespace estlab::testing {
namespace {

namespace fs = std::filesystem;

const std::string kDir = std::string(ESTLAB_SOURCE_DIR) + "/examples/two_tanks";
const std::string kModel = kDir + "/two_tanks.model";

void WriteFile(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

RunResult Est(const std::string& args, const std::string& cwd) { return EstCached(args, cwd); }

const char* kTrue[] = {"k", "a1", "a2"};
const double kTrueValue[] = {0.004, 0.03, 0.025};

// --plot's free-simulation figure: its four files, every error column equal
// to z - y, and the RMSE of the errors equal to the validation's whole-file
// RMSE (recomputed here from the numbers the figure draws).
void ExpectFreeSimulationFigure(const TempDir& dir, double whole_rmse) {
  for (const char* ext : {".png", ".svg", ".gp", ".dat"})
    EXPECT_TRUE(dir.Exists(std::string("plots/free-simulation") + ext)) << ext;
  const std::vector<std::string> lines =
      SplitLines(ReadFile(dir.File("plots/free-simulation.dat")));
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "# t z_h2 sim_h2 err_h2");
  double sum = 0.0;
  size_t rows = 0;
  for (size_t i = 1; i < lines.size(); ++i) {
    double t, z, y, e;
    ASSERT_EQ(std::sscanf(lines[i].c_str(), "%lf %lf %lf %lf", &t, &z, &y, &e), 4) << lines[i];
    EXPECT_NEAR(e, z - y, 1e-15) << lines[i];
    sum += e * e, ++rows;
  }
  EXPECT_EQ(rows, 500u);
  EXPECT_NEAR(std::sqrt(sum / double(rows)), whole_rmse, 1e-9 * whole_rmse);
}

TEST(TwoTanks, ReadmeWalkthroughFitsAndValidatesNearTheNoiseFreeFloor) {
  const std::vector<std::string> commands =
      MarkdownCommands("examples/two_tanks/README.md", "## Walkthrough");
  ASSERT_EQ(commands.size(), 6u);
  TempDir dir;
  for (size_t i = 0; i < commands.size(); ++i) {
    const bool tune = commands[i].rfind("tune ", 0) == 0;
    const RunResult r = Est(commands[i] + (tune ? " --json" : ""), dir.path());
    ASSERT_EQ(r.exit_code, 0) << commands[i] << "\n" << r.err << r.out;
    if (!tune) continue;
    EXPECT_NE(r.out.find("\"status\": \"converged\""), std::string::npos) << r.out;
    for (int j = 0; j < 3; ++j) {
      const double v = JsonNumber(r.out, "tuned", kTrue[j]);
      const double se = JsonNumber(r.out, "std_errors", kTrue[j]);
      EXPECT_LT(std::abs(v - kTrueValue[j]), 3 * se) << kTrue[j] << " " << v << " +- " << se;
      std::printf("  %s = %.6g +- %.2g (true %g)\n", kTrue[j], v, se, kTrueValue[j]);
    }
    const double h1 = JsonNumber(r.out, "x0", "h1"), h2 = JsonNumber(r.out, "x0", "h2");
    EXPECT_NEAR(h1, 0.07, 3 * JsonNumber(r.out, "x0_std_errors", "h1"));
    EXPECT_NEAR(h2, 0.10, 3 * JsonNumber(r.out, "x0_std_errors", "h2"));
    // The validation: the tuned model's whole-file free simulation against
    // the true model's (the noise-free floor of these data).
    const size_t validation = r.out.find("\"validation\"");
    ASSERT_NE(validation, std::string::npos);
    const std::string v = r.out.substr(validation);
    const double tuned = JsonNumber(v.substr(v.find("\"tuned\"")), "whole_rmse", "h2");
    const double floor = JsonNumber(v.substr(v.find("\"oracle\"")), "whole_rmse", "h2");
    EXPECT_LE(tuned, 1.2 * floor) << tuned << " vs floor " << floor;
    EXPECT_GT(floor, 0.0);
    std::printf("  validation free-simulation RMSE %.4g m, noise-free floor %.4g m (x%.3f)\n",
                tuned, floor, tuned / floor);
    ExpectFreeSimulationFigure(dir, tuned);
  }
  const std::string fitted = ReadFile(dir.path() + "/fitted_valid.csv");
  EXPECT_EQ(fitted.rfind("t,h1,h2,u,z_h2\n", 0), 0u) << fitted.substr(0, 80);
  // Step 4's tuned.ini: the estimated x0 as a line the filter's --config reads.
  const std::string ini = ReadFile(dir.path() + "/tuned_pem.ini");
  EXPECT_NE(ini.find("\nx0 = h1="), std::string::npos) << ini;
  EXPECT_NE(ini.find("\nparam = k="), std::string::npos) << ini;
  // And the process model its Q is per step of, the input's hold included.
  EXPECT_NE(ini.find("\nintegrator = "), std::string::npos) << ini;
  EXPECT_NE(ini.find("\ninput-hold = zoh\n"), std::string::npos) << ini;
  EXPECT_TRUE(dir.Exists("filtered_valid.csv"));
}

// Simulates one record of `input` from x0 with `seed` into `out`.
void Simulate(const std::string& cwd, const std::string& input, const std::string& x0, int seed,
              const std::string& out) {
  const RunResult r =
      Est("simulate --model " + kModel + " --data " + kDir + "/" + input + " --x0 " + x0 +
              " --integrator rk4 --substeps 4 --process-noise-var 1e-9,1e-9 "
              "--measure level --meas-noise-var 1e-6 --seed " +
              std::to_string(seed) + " --out " + out,
          cwd);
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

std::string Fit(const std::string& data, const std::string& start, const std::string& extra) {
  return "tune --model " + kModel + " " + data +
         " --measure level --estimator output-error --estimate-param k,a1,a2 " + start +
         " --estimate-x0 h1,h2 --integrator rk4 --substeps 4 --init-q-diag 1e-9,1e-9 "
         "--init-r-diag 1e-6 --json " +
         extra;
}

// Prediction error with x0: the innovation likelihood (tune's default
// filter, the UKF) with the simulation's true Q and R (fixed), the pump gain,
// both orifices and the prior mean x0 estimated; P0 tiny, since the records
// start exactly at x0.
std::string PemFit(const std::string& data, const std::string& start, const std::string& extra) {
  return "tune --model " + kModel + " " + data + " --measure level --estimate-param k,a1,a2 " +
         start +
         " --estimate-x0 h1,h2 --integrator rk4 --substeps 4 --init-q-diag 1e-9,1e-9 "
         "--q-param fixed --init-r-diag 1e-6 --r-param fixed --p0-diag 1e-10,1e-10 "
         "--json " +
         extra;
}

// 50 data sets simulated from the truth, each fitted from a wrong guess by
// `fit` (Fit or PemFit): k, a1, a2 and both initial levels within 2 SE of
// the truth in at least 45, and the objective at the estimate (JSON key
// `end`) never above that at the truth (key `start` of a fit started there).
void ExpectCoverageInFiftySets(std::string (*fit)(const std::string&, const std::string&,
                                                  const std::string&),
                               const char* end, const char* start, const char* label) {
  TempDir dir;
  int covered[5] = {0, 0, 0, 0, 0}, not_worse = 0, sets = 0;
  const char* x0_names[] = {"h1", "h2"};
  const double x0_true[] = {0.07, 0.10};
  for (int seed = 1; seed <= 50; ++seed) {
    Simulate(dir.path(), "pump_train.csv", "h1=0.07,h2=0.10", seed, "d.csv");
    const RunResult r = Est(
        fit("--data d.csv", "--param k=0.003,a1=0.02,a2=0.02 --x0 h1=0.1,h2=0.1", ""), dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    const RunResult at_truth =
        Est(fit("--data d.csv", "--param k=0.004,a1=0.03,a2=0.025 --x0 h1=0.07,h2=0.10",
                "--max-iterations 1"),
            dir.path());
    const double value = JsonNumber(r.out, "", end), truth = JsonNumber(at_truth.out, "", start);
    ASSERT_TRUE(std::isfinite(value) && std::isfinite(truth)) << at_truth.out;
    not_worse += value <= truth + 1e-9 * std::abs(truth);
    for (int j = 0; j < 3; ++j) {
      const double v = JsonNumber(r.out, "tuned", kTrue[j]);
      covered[j] += std::abs(v - kTrueValue[j]) <= 2 * JsonNumber(r.out, "std_errors", kTrue[j]);
    }
    for (int j = 0; j < 2; ++j) {
      const double v = JsonNumber(r.out, "x0", x0_names[j]);
      covered[3 + j] +=
          std::abs(v - x0_true[j]) <= 2 * JsonNumber(r.out, "x0_std_errors", x0_names[j]);
    }
    ++sets;
  }
  const char* names[] = {"k", "a1", "a2", "h1(0)", "h2(0)"};
  for (int j = 0; j < 5; ++j) {
    std::printf("  %s: %s within 2 SE in %d of %d data sets\n", label, names[j], covered[j], sets);
    EXPECT_GE(covered[j], 45) << label << " " << names[j];
  }
  std::printf("  %s: %s at the estimate <= at the truth in %d of %d\n", label, end, not_worse,
              sets);
  EXPECT_EQ(not_worse, sets) << label;
}

TEST(TwoTanks, OutputErrorWithX0CoversTheTruthInFiftyDataSets) {
  ExpectCoverageInFiftySets(&Fit, "cost", "cost_initial", "output error");
}

TEST(TwoTanks, PredictionErrorWithX0CoversTheTruthInFiftyDataSets) {
  // Levenberg-Marquardt (--solver least-squares): from this guess the
  // projected L-BFGS stops at a saddle on some data sets, which it reports
  // as not-a-minimum (exit 1), not as converged.
  auto lm = [](const std::string& data, const std::string& start, const std::string& extra) {
    return PemFit(data, start, "--solver least-squares " + extra);
  };
  ExpectCoverageInFiftySets(+lm, "nll_tuned", "nll_initial", "prediction error");
}

// Three experiments from other initial levels (one 80 mm below the common
// guess), each its own x0, by both methods. Prediction error uses Ceres'
// Levenberg-Marquardt here: from that guess the projected L-BFGS walks into
// a level clipped at 0 (sqrt(max(h, 0))), where the filter fails within a
// finite-difference step, and reports it as unverified (exit 1).
TEST(TwoTanks, ThreeExperimentsRecoverTheirOwnInitialStates) {
  TempDir dir;
  const double x0[3][2] = {{0.07, 0.10}, {0.02, 0.03}, {0.15, 0.05}};
  int covered[2] = {0, 0}, total[2] = {0, 0};  // output error, prediction error
  for (int rep = 0; rep < 10; ++rep) {
    std::string data;
    for (int f = 0; f < 3; ++f) {
      const std::string name = "e" + std::to_string(f) + ".csv";
      Simulate(dir.path(), f == 1 ? "pump_valid.csv" : "pump_train.csv",
               "h1=" + std::to_string(x0[f][0]) + ",h2=" + std::to_string(x0[f][1]),
               100 * rep + f + 1, name);
      data += " --data " + name;
    }
    const std::string start = "--param k=0.003,a1=0.02,a2=0.02 --x0 h1=0.1,h2=0.1";
    for (int method = 0; method < 2; ++method) {
      const RunResult fit = Est(method ? PemFit(data, start, "--x0-per-file --solver least-squares")
                                       : Fit(data, start, "--x0-per-file"),
                                dir.path());
      ASSERT_EQ(fit.exit_code, 0) << fit.err << fit.out;
      size_t at = fit.out.find("\"x0_per_file\"");
      ASSERT_NE(at, std::string::npos) << fit.out;
      for (int f = 0; f < 3; ++f) {
        at = fit.out.find("\"data\": ", at + 1);
        const std::string item = fit.out.substr(at);
        for (int j = 0; j < 2; ++j) {
          const char* s = j ? "h2" : "h1";
          const double v = JsonNumber(item, "x0", s), se = JsonNumber(item, "std_errors", s);
          covered[method] += std::abs(v - x0[f][j]) <= 2 * se;
          ++total[method];
        }
      }
    }
  }
  const char* method_name[] = {"output error", "prediction error"};
  for (int method = 0; method < 2; ++method) {
    std::printf("  %s: per-file x0 within 2 SE: %d of %d\n", method_name[method], covered[method],
                total[method]);
    EXPECT_GE(covered[method], int(std::ceil(0.9 * total[method]))) << method_name[method];
  }
}

TEST(TwoTanks, BadInputNamesTheValueAndWritesNothing) {
  TempDir dir;
  WriteFile(dir.path() + "/no_u.csv", "t,volts\n0,1\n2,1\n");
  WriteFile(dir.path() + "/nan_u.csv", "t,u\n0,1\n2,nan\n");
  WriteFile(dir.path() + "/inf_u.csv", "t,u\n0,1\n2,inf\n");
  WriteFile(dir.path() + "/back.csv", "t,u\n0,1\n2,1\n1,1\n");
  const std::string sim = "simulate --model " + kModel + " --measure level --out o.csv --data ";
  const std::string tune = "tune --model " + kModel +
                           " --data d.csv --measure level --init-q-diag 1e-9,1e-9 "
                           "--init-r-diag 1e-6 --out tuned.ini ";
  struct Case {
    std::string args, mentions;
  } cases[] = {
      {sim + "no_u.csv", "no_u.csv: no input column 'u'"},
      {sim + "nan_u.csv", "nan_u.csv:3: column 2 ('u'): missing input"},
      {sim + "inf_u.csv", "inf_u.csv:3: column 2 ('u'): 'inf' is not a finite number"},
      {sim + "back.csv", "back.csv:4: column 1 ('t'): time goes backwards"},
      {sim + "d.csv --integrator semi-implicit-euler",
       "advances only the states in a (position, rate) pair; model 'two-tanks' has h1, h2 in none"},
      {tune + "--estimator output-error --estimate-x0 h3", "--estimate-x0: 'h3' is not a state"},
      {tune + "--estimator output-error --estimate-x0 h1 --x0-per-file",
       "--x0-per-file needs two --data files"},
      {tune + "--estimator als --estimate-x0 h1",
       "--estimate-x0 applies to the ml, em and output-error estimators, not als"},
      {tune + "--estimate-x0 h3", "--estimate-x0: 'h3' is not a state"},
      {tune + "--estimate-x0 h1 --x0-per-file", "--x0-per-file needs two --data files"},
  };
  Simulate(dir.path(), "pump_train.csv", "h1=0.07,h2=0.10", 1, "d.csv");
  for (const Case& c : cases) {
    const RunResult r = Est(c.args, dir.path());
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(dir.path() + "/o.csv"));
    EXPECT_FALSE(fs::exists(dir.path() + "/tuned.ini"));
  }
}

TEST(TwoTanks, RelativeModelCacheWorksOnAFirstCompile) {
  TempDir dir;
  const RunResult r = RunEstlab("--model-cache relative-cache simulate --model " + kModel +
                                    " --data " + kDir + "/pump_train.csv --x0 h1=0.07 --out s.csv",
                                dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::is_directory(dir.path() + "/relative-cache"));
  EXPECT_EQ(ReadFile(dir.path() + "/s.csv").rfind("t,h1,h2,u\n", 0), 0u);
}

}  // namespace
}  // namespace estlab::testing
