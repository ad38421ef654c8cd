// Studies on recorded data (`data =` scenarios): the config keys and their
// errors, the metrics that need no truth against hand values, and the
// recorded-data study subset of tests/studies/data/recorded_single.ini end to
// end (the built-in pendulum on a real single-pendulum piece).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../cli/cli_test_util.h"
#include "src/core/types.h"
#include "studies/config/study_config.h"
#include "studies/report/study_metrics.h"
#include "studies/results/study_results.h"
#include "study_test_util.h"

namespace estlab::testing {
namespace {

const std::string kConfig =
    std::string(ESTLAB_SOURCE_DIR) + "/tests/studies/data/recorded_single.ini";

std::string ConfigText() { return ReadFile(kConfig); }

// The error of parsing `text` as if it were the subset config (same folder,
// so its relative data paths resolve), or "" when it parses.
std::string ParseError(const std::string& text) {
  try {
    ParseStudyConfig(text, kConfig);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// "recorded_single.ini:N: " for the line of the config text that starts with `key =`.
std::string At(const std::string& text, const std::string& key) {
  const auto lines = SplitLines(text);
  for (size_t i = 0; i < lines.size(); ++i)
    if (lines[i].rfind(key + " =", 0) == 0) return kConfig + ":" + std::to_string(i + 1) + ": ";
  ADD_FAILURE() << "no line '" << key << " ='";
  return "";
}

class RecordedStudy : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  }
};

// Issue 40 item 4: a file listed twice (two runs of one recording: a
// zero-width interval), a recording with no finite measurement (an "ok"
// run with log-likelihood 0) and a tuning file that is also evaluated are
// refused at the config, naming the key and the file.
TEST_F(RecordedStudy, DuplicateEmptyAndInSampleFilesAreRefused) {
  const std::string text = ConfigText();
  const std::string v1 = "../../../examples/data/multiarm/single/validate_1.csv";
  const std::string twice =
      Replace(text, v1, v1 + ", ../../../examples/data/multiarm/single/validate_*.csv");
  EXPECT_NE(ParseError(twice).find("[scenario.single] data: '"), std::string::npos)
      << ParseError(twice);
  EXPECT_NE(ParseError(twice).find("validate_1.csv' is listed twice"), std::string::npos)
      << ParseError(twice);
  const std::string in_sample = Replace(text, "train_4.csv", "validate_1.csv");
  EXPECT_NE(ParseError(in_sample).find("[scenario.single] tune-data: '"), std::string::npos)
      << ParseError(in_sample);
  EXPECT_NE(ParseError(in_sample).find("validate_1.csv' is also in data"), std::string::npos)
      << ParseError(in_sample);
  TempDir dir;
  std::ofstream(dir.File("empty.csv")) << "t,theta,omega\n0,,1\n0.001,,1\n";
  const std::string empty =
      Replace(text, "../../../examples/data/multiarm/single/validate_1.csv", dir.File("empty.csv"));
  EXPECT_NE(ParseError(empty).find("empty.csv' has no finite measurement"), std::string::npos)
      << ParseError(empty);
}

// Issue 40 item 4: a noise tuning that fails (tune-data shorter than the
// burn-in) is recorded in tuned.csv and the study exits 1 saying so, also
// when the complete folder is run again; before, it exited 0.
TEST_F(RecordedStudy, AFailedTuningMakesTheStudyExitOne) {
  TempDir dir;
  const std::string data = std::string(ESTLAB_SOURCE_DIR) + "/examples/data/multiarm/single/";
  const auto train = SplitLines(ReadFile(data + "train_4.csv"));
  std::ofstream(dir.File("short.csv")) << train[0] << "\n" << train[1] << "\n" << train[2] << "\n";
  std::string text = Replace(ConfigText(), "../../../examples/data/multiarm/single/validate_1.csv",
                             data + "validate_1.csv");
  text = Replace(text, "../../../examples/data/multiarm/single/train_4.csv", dir.File("short.csv"));
  std::ofstream(dir.File("s.ini")) << text;
  for (int pass = 0; pass < 2; ++pass) {
    const auto r = RunEstlab("study s.ini --out out --quiet", dir.path());
    EXPECT_EQ(r.exit_code, 1) << pass << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: 2 noise tuning(s) failed (out/tuned.csv says why"),
              std::string::npos)
        << r.err;
  }
  const std::string tuned = ReadFile(dir.File("out/tuned.csv"));
  EXPECT_NE(tuned.find("single,ekf,tuned,failed,"), std::string::npos) << tuned;
  EXPECT_NE(tuned.find("not more than the burn-in of 20"), std::string::npos) << tuned;
}

// Issue 40 item 18: a data glob that reaches a study's results folder
// (`data = dd/*/*.csv` with --out dd/res) leaves its files out; before, the
// second run read dd/res/runs.csv as data and failed.
TEST_F(RecordedStudy, DataGlobsLeaveResultsFoldersOut) {
  TempDir dir;
  const std::string data = std::string(ESTLAB_SOURCE_DIR) + "/examples/data/multiarm/single/";
  std::filesystem::create_directories(dir.File("dd/a"));
  std::filesystem::create_directories(dir.File("dd/res/timeseries/single"));
  std::filesystem::copy_file(data + "validate_1.csv", dir.File("dd/a/x.csv"));
  std::ofstream(dir.File("dd/res/study.state")) << "status = complete\n";
  std::ofstream(dir.File("dd/res/runs.csv")) << "scenario,run\nsingle,0\n";
  std::ofstream(dir.File("dd/res/timeseries/single/run_0.csv")) << "t,x\n0,1\n";
  const std::string text =
      Replace(ConfigText(), "../../../examples/data/multiarm/single/validate_1.csv",
              dir.File("dd/*/*.csv"));
  const StudyConfig c = ParseStudyConfig(text, kConfig);
  ASSERT_EQ(c.scenarios[0].data_runs.size(), 1u);
  EXPECT_EQ(c.scenarios[0].data_runs[0].path, dir.File("dd/a/x.csv"));
  const std::string only = Replace(text, "dd/*/*.csv", "dd/res/*.csv");
  EXPECT_NE(ParseError(only).find("matches only files of a study's results folder"),
            std::string::npos)
      << ParseError(only);
}

TEST_F(RecordedStudy, DataFilesAreTheRuns) {
  const std::string text = Replace(ConfigText(), "validate_1.csv", "validate_*.csv");
  const StudyConfig c = ParseStudyConfig(text, kConfig);
  ASSERT_EQ(c.scenarios.size(), 1u);
  const ScenarioConfig& s = c.scenarios[0];
  EXPECT_TRUE(s.recorded);
  EXPECT_FALSE(s.has_truth);          // truth = none by default: omega is derived, not truth
  ASSERT_EQ(ScenarioRuns(s, 10), 2);  // one run per file, sorted
  EXPECT_EQ(std::filesystem::path(s.data_runs[0].path).filename(), "validate_1.csv");
  EXPECT_EQ(std::filesystem::path(s.data_runs[1].path).filename(), "validate_2.csv");
  EXPECT_FALSE(s.data_runs[0].has_truth);
  ASSERT_EQ(s.data_runs[0].t.size(), 9167u);
  // The column map: validate_1's first row has theta = 3.56835753 from upright.
  EXPECT_DOUBLE_EQ(s.data_runs[0].z[0], 3.56835753 - 3.141592653589793);
  EXPECT_EQ(s.tune_runs.size(), 1u);
  EXPECT_EQ(c.output_columns, std::vector<std::string>{"theta"});
  // The prior holds at the first recorded row; tuning fits on tune-data.
  EXPECT_FALSE(s.combos[0].spec.has_t0);
  EXPECT_TRUE(s.combos[1].tune);
  EXPECT_EQ(s.combos[1].tune_datasets, 1);
  // truth = columns: the state-named columns are read as the truth.
  const StudyConfig t = ParseStudyConfig(
      Replace(ConfigText(), "measurement = angle\n", "measurement = angle\ntruth = columns\n"),
      kConfig);
  EXPECT_TRUE(t.scenarios[0].has_truth);
  EXPECT_TRUE(t.scenarios[0].data_runs[0].has_truth);
}

TEST_F(RecordedStudy, ConfigErrorsNameTheKey) {
  const std::string text = ConfigText();
  const std::string glob = Replace(text, "validate_1.csv", "nothing_*.csv");
  EXPECT_EQ(ParseError(glob).rfind(At(glob, "data") + "[scenario.single] data: no file matches '" +
                                       "../../../examples/data/multiarm/single/nothing_*.csv'",
                                   0),
            0u)
      << ParseError(glob);
  const std::string oracle = Replace(text, "q-white-accel = 1\nr-diag", "q = oracle\nr-diag");
  EXPECT_EQ(ParseError(oracle), At(oracle, "q") +
                                    "[noise.hand] q: no oracle on recorded data: [scenario.single] "
                                    "has no known noise (use a hand Q/R or 'q = tuned')");
  const std::string dt =
      Replace(text, "measurement = angle\n", "measurement = angle\ndt = 0.001\n");
  EXPECT_EQ(ParseError(dt), At(dt, "dt") +
                                "[scenario.single] dt: not allowed with data (recorded runs are "
                                "not simulated)");
  const std::string x0 =
      Replace(text, "measurement = angle\n", "measurement = angle\nx0 = theta=1\n");
  EXPECT_NE(ParseError(x0).find("[scenario.single] x0: not allowed with data"), std::string::npos);
  const std::string no_tune = Replace(text, "tune-data = ", "# tune-data = ");
  EXPECT_NE(ParseError(no_tune).find("[noise.tuned] q: [scenario.single] has no tune-data files"),
            std::string::npos)
      << ParseError(no_tune);
  const std::string no_init = Replace(text, "init-q-white-accel = 1\n", "");
  EXPECT_NE(ParseError(no_init).find("[noise.tuned] q: 'tuned' on recorded data needs a start"),
            std::string::npos)
      << ParseError(no_init);
  const std::string column = Replace(text, "theta-pi", "theta-");
  EXPECT_EQ(ParseError(column), At(column, "column") +
                                    "[scenario.single] column: expected ours=[a*]theirs[+-b], got "
                                    "'z_theta=theta-'");
  const std::string missing = Replace(text, "z_theta=theta-pi", "z_theta=angle");
  EXPECT_NE(ParseError(missing).find("[scenario.single] data: "), std::string::npos);
  EXPECT_NE(ParseError(missing).find("no measurement column 'angle'"), std::string::npos);
  const std::string truth =
      Replace(text, "measurement = angle\n", "measurement = angle\ntruth = yes\n");
  EXPECT_NE(ParseError(truth).find("truth: expected none or columns, got 'yes'"),
            std::string::npos);
  const std::string burn = Replace(text, "burn-in = 20", "burn-in = 9167");
  EXPECT_EQ(ParseError(burn), At(burn, "burn-in") +
                                  "[scenario.single] burn-in: must be less than the rows of every "
                                  "data file (the shortest has 9167)");
  // Recorded-data keys without data.
  EXPECT_NE(ParseError(Replace(TinyStudy(2), "measurement = sin\n",
                               "measurement = sin\ncolumn = z_sin_theta=s\n"))
                .find("[scenario.pend] column: applies only with data = FILES"),
            std::string::npos);
}

// pred_rmse from the filter's innovations, NLL per step from its per-row
// log-likelihood, by hand; `skip` leaves out the first rows.
TEST(NoTruthMetrics, FromTheInnovationsByHand) {
  FilterRunOutput out;
  out.columns = {"t", "theta_est", "nu_theta", "nis", "loglik"};
  out.rows = {{0.0, 0.1, 3.0, 0.5, -2.0}, {0.1, 0.1, NAN, NAN, NAN}, {0.2, 0.1, -4.0, 1.5, -3.0}};
  const NoTruthMetrics m = ComputeNoTruthMetrics(out, {"theta", "omega"});
  EXPECT_EQ(m.updates, 2);
  EXPECT_DOUBLE_EQ(m.nll_per_step, 2.5);  // (2 + 3) / 2
  EXPECT_DOUBLE_EQ(m.mean_nis, 1.0);      // (0.5 + 1.5) / 2
  ASSERT_EQ(m.pred_rmse.size(), 2u);
  EXPECT_DOUBLE_EQ(m.pred_rmse[0], std::sqrt(12.5));  // sqrt((9 + 16) / 2): the update rows only
  EXPECT_TRUE(std::isnan(m.pred_rmse[1]));            // no such output
  // 2 updates of a 2-output NIS: 2 mean ~ chi2(4), quantiles 0.484419 and 11.143287.
  EXPECT_NEAR(m.nis_bounds95[0], 0.484419 / 2, 1e-6);
  EXPECT_NEAR(m.nis_bounds95[1], 11.143287 / 2, 1e-6);
  const NoTruthMetrics late = ComputeNoTruthMetrics(out, {"theta"}, 1);
  EXPECT_EQ(late.updates, 1);
  EXPECT_DOUBLE_EQ(late.nll_per_step, 3.0);
  EXPECT_DOUBLE_EQ(late.pred_rmse[0], 4.0);
}

// The filter's first innovation on recorded data is z_0 - theta_prior (no
// prediction before the first row): one row gives pred_rmse = |0.3 - 0.4|.
TEST_F(RecordedStudy, FirstInnovationIsAgainstThePrior) {
  const StudyConfig c = LoadStudyConfig(kConfig);
  const ScenarioConfig& s = c.scenarios[0];
  FilterData one;
  one.path = "one row";
  one.t = {36.668};
  one.lines = {2};
  one.m = 1;
  one.z = {0.3};
  const FilterRunOutput out = s.model->run_filter(s.combos[0].spec, one);
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  EXPECT_NEAR(ComputeNoTruthMetrics(out, {"theta"}).pred_rmse[0], 0.1, 1e-15);
}

// The subset study end to end: the report says what was available without
// truth and that there is no oracle; the metrics are finite; NIS bounds present.
TEST_F(RecordedStudy, SubsetStudyReportsMetricsWithoutTruth) {
  TempDir dir;
  const auto r = RunEstlab("study " + kConfig + " --out out --jobs 2 --quiet", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string report = ReadFile(dir.File("out/report.md"));
  EXPECT_NE(report.find("## Recorded data: metrics without truth"), std::string::npos);
  EXPECT_NE(report.find("**No truth**"), std::string::npos) << report;
  EXPECT_NE(report.find("RMSE, MAE and NEES are **not available**"), std::string::npos);
  EXPECT_NE(report.find("**No oracle**"), std::string::npos);
  EXPECT_NE(report.find("The first 20 rows of each run"), std::string::npos);
  EXPECT_NE(report.find("Metrics available without truth: the innovation log-likelihood"),
            std::string::npos);
  EXPECT_NE(report.find("| ekf | `hand` | `tuned` | "), std::string::npos) << report;
  const StudyConfig c = LoadStudyConfig(kConfig);
  const RowFile runs = ReadRowFile(dir.File("out/runs.csv"), RunsColumns(c));
  ASSERT_EQ(runs.rows.size(), 4u);  // 1 file x 2 filters x 2 noise settings
  const auto cols = RunsColumns(c);
  auto col = [&](const std::string& name) {
    return size_t(std::find(cols.begin(), cols.end(), name) - cols.begin());
  };
  for (const auto& row : runs.rows) {
    EXPECT_EQ(row[col("status")], "ok") << row[col("message")];
    EXPECT_EQ(row[col("rmse_theta")], "");  // no truth, no error
    EXPECT_EQ(row[col("mean_nees")], "");
    const double nll = std::stod(row[col("nll_per_step")]);
    const double lo = std::stod(row[col("nis_lo95")]), hi = std::stod(row[col("nis_hi95")]);
    const double pred = std::stod(row[col("pred_rmse_theta")]);
    EXPECT_TRUE(std::isfinite(nll));
    EXPECT_TRUE(std::isfinite(std::stod(row[col("mean_nis")])));
    EXPECT_EQ(row[col("steps")], "9167");
    // 9167 rows - 20 burn-in = 9147 updates of a 1-output NIS: 1 -+ 1.96 sqrt(2 / 9147).
    EXPECT_NEAR(lo, 1 - 1.96 * std::sqrt(2.0 / 9147), 1e-3);
    EXPECT_NEAR(hi, 1 + 1.96 * std::sqrt(2.0 / 9147), 1e-3);
    // One-step-ahead error at 1 kHz: well below a degree, above zero.
    EXPECT_TRUE(pred > 0 && pred < 0.01) << pred;
  }
  // Figures without truth: prediction RMSE and NLL, no RMSE figures.
  const auto f = RunEstlab("figures out --no-render", dir.path());
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_TRUE(dir.Exists("out/figures/single_pred_rmse_means.gp"));
  EXPECT_TRUE(dir.Exists("out/figures/single_nll_means.gp"));
  EXPECT_TRUE(dir.Exists("out/figures/single_nees_nis.gp"));
  EXPECT_FALSE(dir.Exists("out/figures/single_rmse_means.gp"));
  EXPECT_FALSE(dir.Exists("out/figures/single_rmse_time.gp"));
}

}  // namespace
}  // namespace estlab::testing

namespace estlab::testing {
namespace {

// A noise section may fit model parameters with Q and R (`params = tuned
// L,b`): tuned.csv lists them, the filters run with them, bad keys name
// their line.
TEST_F(RecordedStudy, NoiseSectionFitsModelParametersWithQAndR) {
  const std::string fit =
      "\n[noise.fit]\nq = tuned\ninit-q-white-accel = 1\nr = tuned\ninit-r-diag = 1e-6\n"
      "tune-burn-in = 20\nparams = tuned L,b\nparam-bounds = b=0:1\nfilters = ekf\n";
  TempDir dir;
  {
    std::ofstream out(dir.File("fit.ini"));
    std::string text = ConfigText();  // its data paths made absolute
    for (size_t at; (at = text.find("../../../examples")) != std::string::npos;)
      text.replace(at, 17, std::string(ESTLAB_SOURCE_DIR) + "/examples");
    out << text << fit;
  }
  const auto r = RunEstlab("study fit.ini --out out --jobs 2 --quiet", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string tuned = ReadFile(dir.File("out/tuned.csv"));
  const size_t at = tuned.find("single,ekf,fit,converged");
  ASSERT_NE(at, std::string::npos) << tuned;
  const std::string row = tuned.substr(at, tuned.find('\n', at) - at);
  const size_t l = row.find("L=");
  ASSERT_NE(l, std::string::npos) << row;
  EXPECT_NEAR(std::stod(row.substr(l + 2)), 0.1532, 0.002) << row;  // g / L = 64 1/s^2
  EXPECT_NE(row.find(";b="), std::string::npos) << row;
  EXPECT_NE(ReadFile(dir.File("out/report.md")).find("model parameters tuned L,b"),
            std::string::npos);

  const std::string text = ConfigText() + fit;
  const std::string no_tuned = Replace(text, "params = tuned L,b", "params = L,b");
  const auto lines = SplitLines(no_tuned);
  const size_t line = size_t(std::find(lines.begin(), lines.end(), "params = L,b") - lines.begin());
  EXPECT_EQ(ParseError(no_tuned), kConfig + ":" + std::to_string(line + 1) +
                                      ": [noise.fit] params: expected 'tuned NAME[,NAME...]', got "
                                      "'L,b'");
  const std::string bad_name = Replace(text, "params = tuned L,b", "params = tuned len,b");
  EXPECT_NE(ParseError(bad_name).find(
                "[noise.fit] params: model 'pendulum' has no parameter 'len' (it has g, L, b)"),
            std::string::npos)
      << ParseError(bad_name);
  const std::string stray = Replace(text, "params = tuned L,b\n", "");
  EXPECT_NE(ParseError(stray).find("param-bounds: applies only with params = tuned"),
            std::string::npos)
      << ParseError(stray);
}

}  // namespace
}  // namespace estlab::testing
