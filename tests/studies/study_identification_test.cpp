// Noise identification in studies (studies/run/study_identification.h,
// tune-per-run, tune-estimator, init-scale, tune-tolerance): each run's Q/R
// equal what `estlab tune` finds on that run's data, the errors against the
// truth are the hand-computed ones, identification.csv's scores follow from
// runs.csv, results do not depend on --jobs, and bad keys are refused.
#include "studies/run/study_identification.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>

#include "../cli/cli_test_util.h"
#include "error_text.h"
#include "studies/config/study_config.h"
#include "studies/results/study_results.h"
#include "study_test_util.h"

namespace estlab::testing {
namespace {

TEST(StudyIdentification, RelativeFrobeniusErrorByHand) {
  // ||[1.1 0.2; 0.2 1.9] - [1 0; 0 2]||_F = sqrt(0.01 + 0.04 + 0.04 + 0.01) = sqrt(0.1),
  // ||[1 0; 0 2]||_F = sqrt(5).
  EXPECT_NEAR(RelativeFrobeniusError({1.1, 0.2, 0.2, 1.9}, {1, 0, 0, 2}), std::sqrt(0.1 / 5.0),
              1e-15);
  EXPECT_NEAR(RelativeFrobeniusError({0.09}, {0.1}), 0.1, 1e-15);
  EXPECT_EQ(RelativeFrobeniusError({3.0}, {3.0}), 0.0);
  EXPECT_TRUE(std::isnan(RelativeFrobeniusError({}, {})));
  EXPECT_TRUE(std::isnan(RelativeFrobeniusError({1.0}, {1.0, 0.0})));
  EXPECT_TRUE(std::isnan(RelativeFrobeniusError({1.0}, {0.0})));
  const std::vector<double> ratios = DiagonalRatios({2, 5, 5, 3}, {4, 1, 1, 0});
  ASSERT_EQ(ratios.size(), 2u);
  EXPECT_EQ(ratios[0], 0.5);
  EXPECT_TRUE(std::isnan(ratios[1]));  // a zero true variance
}

// Pendulum, white-acceleration truth qc = 0.5 and R = 0.01, EKF: the oracle,
// ML and EM identified per run, and ML from 0.01 x the truth.
std::string IdentificationStudy(int runs) {
  return "[study]\nname = ident\nseed = 11\nruns = " + std::to_string(runs) +
         "\nkeep-runs = 1\n\n"
         "[scenario.pend]\nmodel = pendulum\nparams = g=9.8\nx0 = theta=0.7853981633974483\n"
         "dt = 0.05\nsteps = 80\ntruth-integrator = rk4\nprocess-noise = white-accel 0.5\n"
         "measurement = sin\nmeas-noise-var = 0.01\nprior-p0-diag = 0.05,0.05\n\n"
         "[filter.ekf]\nkind = ekf\nintegrator = rk4\n\n"
         "[noise.oracle]\nq = oracle\nr = oracle\n\n"
         "[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = true\n\n"
         "[noise.em]\nq = tuned\nr = tuned\ntune-estimator = em\ntune-tolerance = 1e-7\n"
         "tune-per-run = true\n\n"
         "[noise.ml-x0_01]\nq = tuned\nr = tuned\ninit-scale = 0.01\ntune-per-run = true\n";
}

// "key = value" of a tuned.ini.
double IniValue(const std::string& ini, const std::string& key) {
  std::istringstream in(ini);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key + " = ", 0) == 0) return std::stod(line.substr(key.size() + 3));
  ADD_FAILURE() << "no " << key << " in\n" << ini;
  return NAN;
}

// A CSV file of the study (read by the study code's own reader, quotes and
// all) as rows of column -> value.
std::vector<std::map<std::string, std::string>> Table(const std::string& path) {
  const CsvText csv = ReadCsvText(path);
  std::vector<std::map<std::string, std::string>> rows;
  for (const auto& r : csv.rows) {
    std::map<std::string, std::string> row;
    for (size_t j = 0; j < csv.columns.size() && j < r.size(); ++j) row[csv.columns[j]] = r[j];
    rows.push_back(row);
  }
  return rows;
}

class StudyIdentificationCli : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  }
  TempDir dir_;
};

TEST_F(StudyIdentificationCli, EachRunIdentifiesWhatEstlabTuneFindsOnItsData) {
  WriteText(dir_.File("s.ini"), IdentificationStudy(3));
  const auto r = RunEstlab("study s.ini --out out --jobs 2 --quiet", dir_.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto runs = Table(dir_.File("out/runs.csv"));
  ASSERT_EQ(runs.size(), 12u);  // 3 runs x 4 noise settings

  // Run 1's data as kept in its time series: `estlab tune` on it from the
  // oracle (t0 = 0 as in the study) gives the per-run Q/R.
  const std::string base =
      "tune --model pendulum --param g=9.8 --measure sin --filter ekf --integrator rk4 "
      "--x0 theta=0.7853981633974483 --p0-diag 0.05,0.05 --t0 0 --q-param white-accel "
      "--init-r-diag 0.01 ";
  struct Case {
    std::string noise, options;
  };
  for (const Case& c : {Case{"ml", "--init-q-white-accel 0.5"},
                        Case{"em", "--init-q-white-accel 0.5 --estimator em --tolerance 1e-7"}}) {
    const auto t = RunEstlab(base + c.options + " --data out/timeseries/pend/run1_ekf_" + c.noise +
                                 ".csv --out " + c.noise + ".ini",
                             dir_.path());
    ASSERT_EQ(t.exit_code, 0) << t.err;
    const std::string ini = ReadFile(dir_.File(c.noise + ".ini"));
    const double qc = IniValue(ini, "q-white-accel"), rv = IniValue(ini, "r-diag");
    const std::map<std::string, std::string>* row = nullptr;
    for (const auto& x : runs)
      if (x.at("noise") == c.noise && x.at("run") == "1") row = &x;
    ASSERT_NE(row, nullptr);
    EXPECT_EQ(row->at("status"), "ok");
    // White acceleration: Q^ - Q = (qc^ - qc) Q_wa, so the error is |qc^/qc - 1|.
    EXPECT_NEAR(std::stod(row->at("id_q_err")), std::abs(qc / 0.5 - 1.0), 1e-6) << c.noise;
    EXPECT_NEAR(std::stod(row->at("id_r_err")), std::abs(rv / 0.01 - 1.0), 1e-6) << c.noise;
    // Per element: white acceleration scales both variances by qc^ / qc.
    EXPECT_NEAR(std::stod(row->at("id_q_theta")), qc / 0.5, 1e-6) << c.noise;
    EXPECT_NEAR(std::stod(row->at("id_q_omega")), qc / 0.5, 1e-6) << c.noise;
    EXPECT_NEAR(std::stod(row->at("id_r_sin_theta")), rv / 0.01, 1e-6) << c.noise;
    EXPECT_EQ(row->at("id_at_bound"), "0");
    EXPECT_GT(std::stoi(row->at("id_iterations")), 0);
  }
  // The oracle has no identification; every tuned run has one.
  for (const auto& x : runs) {
    EXPECT_EQ(x.at("id_q_err").empty(), x.at("noise") == "oracle") << x.at("noise");
    EXPECT_EQ(x.at("id_r_err").empty(), x.at("noise") == "oracle") << x.at("noise");
  }
  const auto timing = Table(dir_.File("out/timing.csv"));
  for (const auto& x : timing)
    EXPECT_EQ(x.at("identify_wall_s").empty(), x.at("noise") == "oracle") << x.at("noise");
}

TEST_F(StudyIdentificationCli, ScoresFollowFromRunsCsvAndJobsChangeNothing) {
  WriteText(dir_.File("s.ini"), IdentificationStudy(4));
  const auto r1 = RunEstlab("study s.ini --out j1 --jobs 1 --quiet", dir_.path());
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  const auto r2 = RunEstlab("study s.ini --out j2 --jobs 2 --quiet", dir_.path());
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  for (const char* f : {"runs.csv", "summary.csv", "steps.csv"})
    EXPECT_EQ(ReadFile(dir_.File(std::string("j1/") + f)),
              ReadFile(dir_.File(std::string("j2/") + f)))
        << f;

  // score = mean over theta, omega of mean RMSE / the oracle's mean RMSE.
  std::map<std::string, std::map<std::string, double>> sum;  // noise -> state -> sum
  std::map<std::string, int> n;
  for (const auto& x : Table(dir_.File("j1/runs.csv"))) {
    ASSERT_EQ(x.at("status"), "ok");
    sum[x.at("noise")]["theta"] += std::stod(x.at("rmse_theta"));
    sum[x.at("noise")]["omega"] += std::stod(x.at("rmse_omega"));
    ++n[x.at("noise")];
  }
  const auto id = Table(dir_.File("j1/identification.csv"));
  ASSERT_EQ(id.size(), 4u);
  for (const auto& x : id) {
    const std::string& noise = x.at("noise");
    const double score = 0.5 *
                         (sum[noise]["theta"] / sum["oracle"]["theta"] +
                          sum[noise]["omega"] / sum["oracle"]["omega"]) *
                         (double(n["oracle"]) / double(n[noise]));
    EXPECT_NEAR(std::stod(x.at("score")), score, 1e-12) << noise;
    EXPECT_EQ(x.at("kind"), "ekf");
    EXPECT_EQ(x.at("per_run"), noise == "oracle" ? "0" : "1");
  }
  const std::string report = ReadFile(dir_.File("j1/report.md"));
  for (const char* s : {"## Noise identification", "### Ranking over the scenarios",
                        "### Results against common wisdom", "### Robustness",
                        "### `pend`, ekf (ekf; reference `ekf/oracle`)", "| `ml-x0_01` |",
                        "| setting | filter | Q theta | Q omega | R sin_theta |"})
    EXPECT_NE(report.find(s), std::string::npos) << s;
  // The hand-vs-auto section is about settings tuned once, not these.
  EXPECT_EQ(report.find("## Hand-tuned vs auto-tuned"), std::string::npos);

  const auto f = RunEstlab("figures j1 --no-render", dir_.path());
  ASSERT_EQ(f.exit_code, 0) << f.err;
  for (const char* fig : {"pend_score_cost", "pend_id_error"}) {
    EXPECT_TRUE(dir_.Exists(std::string("j1/figures/") + fig + ".gp")) << fig;
    EXPECT_TRUE(dir_.Exists(std::string("j1/figures/") + fig + ".dat")) << fig;
  }
}

TEST(StudyIdentificationConfig, BadKeysNameTheirLine) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  auto error = [](const std::string& text) {
    return ErrorText([&] { ParseStudyConfig(text, "s.ini"); });
  };
  const std::string good = IdentificationStudy(2);
  ASSERT_EQ(error(good), "");
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"tune-estimator = em", "tune-estimator = kalman",
       "[noise.em] tune-estimator: expected ml, em or als, got 'kalman'"},
      {"init-scale = 0.01", "init-scale = 0", "init-scale must be a finite number > 0, got '0'"},
      {"init-scale = 0.01", "init-scale = -1", "init-scale must be a finite number > 0"},
      {"[noise.oracle]\nq = oracle\nr = oracle\n",
       "[noise.oracle]\nq = oracle\nr = oracle\ninit-scale = 2\n",
       "[noise.oracle] init-scale: scales the oracle start"},
      {"tune-estimator = em\ntune-tolerance = 1e-7", "tune-tolerance = 1e-7",
       "[noise.em] tune-tolerance: applies to the em estimator only (the estimator is ml)"},
      {"[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = true",
       "[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = maybe",
       "[noise.ml] tune-per-run: expected true or false, got 'maybe'"},
      {"[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = true",
       "[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = true\ntune-datasets = 3",
       "[noise.ml] tune-datasets: with tune-per-run each run fits on its own measurements"},
      {"[noise.ml-x0_01]\nq = tuned\nr = tuned\ninit-scale = 0.01",
       "[noise.ml-x0_01]\nq = tuned\nr = tuned\ninit-r-diag = 0.02\ninit-scale = 0.01",
       "[noise.ml-x0_01] init-scale: scales the oracle start: every tuned side must start from"},
      {"[noise.oracle]\nq = oracle\nr = oracle\n",
       "[noise.oracle]\nq = oracle\nr = oracle\ntune-per-run = true\n",
       "[noise.oracle] tune-per-run: applies only with q = tuned or r = tuned"},
  };
  for (const Case& c : cases) {
    const std::string message = error(Replace(good, c.from, c.to));
    EXPECT_NE(message.find(c.expect), std::string::npos)
        << "got: " << message << "\nexpected: " << c.expect;
    EXPECT_EQ(message.rfind("s.ini:", 0), 0u) << message;
  }
}

// Every tuner key of `estlab tune` is a tune-<key> of a [noise.*] section
// (one table, src/options/tuner_settings.cpp): the ml estimator's solver and
// multi-start reach the combination's TunerOptions, EM's keys its own.
TEST(StudyIdentificationConfig, TuneKeysReachTheTunerOptions) {
  const std::string text = Replace(
      Replace(IdentificationStudy(2), "[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = true",
              "[noise.ml]\nq = tuned\nr = tuned\ntune-per-run = true\ntune-solver = "
              "least-squares\ntune-starts = 3\ntune-start-spread = 1.5"),
      "tune-tolerance = 1e-7", "tune-tolerance = 1e-7\ntune-max-iterations = 77");
  const StudyConfig config = ParseStudyConfig(text, "s.ini");
  int seen = 0;
  for (const Combo& c : config.scenarios.at(0).combos) {
    const std::string& noise = config.noises.at(c.noise).name;
    if (noise == "ml") {
      EXPECT_EQ(c.tuner.estimator, Estimator::kMl);
      EXPECT_EQ(c.tuner.solver, MlSolver::kLeastSquares);
      EXPECT_EQ(c.tuner.starts, 3);
      EXPECT_EQ(c.tuner.start_spread, 1.5);
      ++seen;
    } else if (noise == "em") {
      EXPECT_EQ(c.tuner.estimator, Estimator::kEm);
      EXPECT_EQ(c.tuner.em_tolerance, 1e-7);
      EXPECT_EQ(c.tuner.max_iterations, 77);
      ++seen;
    } else if (noise == "ml-x0_01") {
      EXPECT_EQ(c.tuner.solver, MlSolver::kLbfgs);
      EXPECT_EQ(c.tuner.max_iterations, 200);
      ++seen;
    }
  }
  EXPECT_EQ(seen, 3);
  const std::string err = ErrorText([&] {
    ParseStudyConfig(Replace(text, "tune-starts = 3", "tune-starts = 3\ntune-lags = 4"), "s.ini");
  });
  EXPECT_NE(err.find("tune-lags: applies to the als estimator only (the estimator is ml)"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.rfind("s.ini:", 0), 0u) << err;
}

}  // namespace
}  // namespace estlab::testing
