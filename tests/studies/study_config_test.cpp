// Study configuration parsing and checking (studies/config/study_config.h), and the
// statistics of studies/report/study_finalize.h.
#include "studies/config/study_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "error_text.h"
#include "src/core/types.h"
#include "studies/report/study_finalize.h"
#include "study_test_util.h"

namespace estlab {
namespace {

using testing::FiltersAvailable;
using testing::Replace;
using testing::TinyStudy;

// The error message of parsing `text`, or "" when it parses.
std::string ParseError(const std::string& text) {
  return testing::ErrorText([&] { ParseStudyConfig(text, "s.ini"); });
}

TEST(StudyConfig, ParsesTheTinyStudy) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const StudyConfig c = ParseStudyConfig(TinyStudy(4), "s.ini");
  EXPECT_EQ(c.study.name, "tiny");
  EXPECT_EQ(c.study.seed, 7u);
  EXPECT_EQ(c.study.runs, 4);
  ASSERT_EQ(c.scenarios.size(), 1u);
  const ScenarioConfig& s = c.scenarios[0];
  EXPECT_EQ(s.name, "pend");
  EXPECT_EQ(s.steps, 25);
  EXPECT_DOUBLE_EQ(s.truth.t_end, 1.25);
  EXPECT_TRUE(s.sample_x0);
  ASSERT_EQ(s.combos.size(), 6u);  // 3 filters x 2 noise settings, filter-major
  EXPECT_EQ(c.filters[s.combos[1].filter].name, "ekf");
  EXPECT_EQ(c.noises[s.combos[1].noise].name, "hand");
  // Oracle: the truth's white-acceleration Q and diagonal R.
  const FilterSpec& oracle = s.combos[0].spec;
  EXPECT_TRUE(oracle.q_white_accel);
  EXPECT_DOUBLE_EQ(oracle.qc, 0.5);
  EXPECT_EQ(oracle.r, std::vector<double>{0.01});
  // Hand-tuned values as given; the prior holds at t = 0, before the first measurement.
  const FilterSpec& hand = s.combos[1].spec;
  EXPECT_FALSE(hand.q_white_accel);
  EXPECT_EQ(hand.q, (std::vector<double>{1e-3, 0, 0, 1e-2}));
  EXPECT_EQ(hand.r, std::vector<double>{0.02});
  EXPECT_TRUE(hand.has_t0);
  EXPECT_EQ(hand.p0, (std::vector<double>{0.05, 0, 0, 0.05}));
  EXPECT_DOUBLE_EQ(hand.x0[0], 0.7853981633974483);
  EXPECT_EQ(c.filters[2].kind, "pf");
  EXPECT_EQ(std::get<ParticleOptions>(s.combos[4].spec.filter).num_particles, 100);
  EXPECT_EQ(c.claims.size(), 1u);
  EXPECT_EQ(c.references.size(), 1u);
}

TEST(StudyConfig, ReadsBomAndCrLineEndsAndRefusesDirectories) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const std::string dir = ::testing::TempDir();
  for (const std::string& eol : {std::string("\r"), std::string("\r\n")}) {
    const std::string path = dir + "/estlab_eol_study.ini";
    {
      std::ofstream f(path, std::ios::binary);
      f << "\xEF\xBB\xBF";
      for (const char c : TinyStudy(4)) f << (c == '\n' ? eol : std::string(1, c));
    }
    const StudyConfig c = LoadStudyConfig(path);
    std::remove(path.c_str());
    EXPECT_EQ(c.study.name, "tiny");
    EXPECT_EQ(c.study.runs, 4);
    EXPECT_EQ(c.text, TinyStudy(4));
  }
  try {
    LoadStudyConfig(dir);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "study config '" + dir + "' is a directory");
  }
}

TEST(StudyConfig, AlternativesExpandToNamedScenarios) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  std::string text = Replace(TinyStudy(3), "x0 = theta=0.7853981633974483",
                             "x0 = pi4: theta=0.785 | pi2: theta=1.571");
  text = Replace(text, "meas-noise-var = 0.01", "meas-noise-var = 0.01 | 1e-4");
  const StudyConfig c = ParseStudyConfig(text, "s.ini");
  ASSERT_EQ(c.scenarios.size(), 4u);
  EXPECT_EQ(c.scenarios[0].name, "pend.pi4.0.01");
  EXPECT_EQ(c.scenarios[1].name, "pend.pi4.1e-4");
  EXPECT_EQ(c.scenarios[2].name, "pend.pi2.0.01");
  EXPECT_DOUBLE_EQ(c.scenarios[3].truth.x0[0], 1.571);
  EXPECT_EQ(c.scenarios[3].truth.meas_noise_var, std::vector<double>{1e-4});
  // The prior defaults to the truth's start of the same alternative.
  EXPECT_DOUBLE_EQ(c.scenarios[3].prior_x0[0], 1.571);
  EXPECT_EQ(c.scenarios[1].combos[0].spec.r, std::vector<double>{1e-4});
}

TEST(StudyConfig, ErrorsNameFileLineAndKey) {
  const std::string good = TinyStudy(2);
  // Lines of the tiny study: 8 model, 13 steps, 21 kind = ekf, 27 alpha, 32 particles.
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"alpha = 0.5", "alpah = 0.5", "s.ini:27: unknown key 'alpah' in [filter.ukf]"},
      {"model = pendulum", "model = pendulumm",
       "s.ini:8: [scenario.pend] model: unknown model 'pendulumm'"},
      {"kind = ekf", "kind = ekff", "s.ini:21: [filter.ekf] kind: unknown filter 'ekff'"},
      {"steps = 25", "steps = 2x5", "s.ini:13: [scenario.pend] steps: '2x5' is not a number"},
      {"runs = 2", "runs = 0", "s.ini:4: [study] runs: must be >= 1"},
      {"[noise.hand]", "[nosie.hand]", "s.ini:39: unknown section [nosie.hand]"},
      {"q-diag = 1e-3,1e-2", "q-diag = 1e-3", "s.ini:40: [noise.hand] q-diag: expected 2 values"},
      {"q-diag = 1e-3,1e-2", "q-diag = tuned",
       "s.ini:40: [noise.hand] q-diag: 'tuned' goes in key q"},
      {"measurement = sin", "measurement = cos",
       "s.ini:16: [scenario.pend] measurement: unknown measurement 'cos'"},
      {"seed = 7", "seed = 7\nseed = 8", "s.ini:4: key 'seed' given twice in [study]"},
      // Issue 15 item 4: counts beyond 32 bits used to wrap (4294967297 ran 1).
      {"runs = 2", "runs = 4294967297",
       "s.ini:4: [study] runs: must be in [1, 100000000], got 4294967297"},
      {"runs = 2", "runs = 3000000000",
       "s.ini:4: [study] runs: must be in [1, 100000000], got 3000000000"},
      {"steps = 25", "steps = 4294967696",
       "s.ini:13: [scenario.pend] steps: must be in [1, 100000000], got 4294967696"},
      // Issue 40 item 4: a run too large to hold is refused before any runs
      // (it used to end as a bad_alloc truth_failed run of a complete study).
      {"steps = 25", "steps = 100000000",
       "s.ini:13: [scenario.pend] steps: 100000000 steps of a 2-state model would hold about "
       "23.8419 GiB per run (at most 4): fewer steps, or a larger dt"},
      // ... and so is a particle smoother whose clouds would not fit.
      {"kind = pf\nintegrator = rk4\nparticles = 100",
       "kind = pf-bs\nintegrator = rk4\nparticles = 10000000",
       "s.ini:32: [filter.pf] particles: 10000000 particles over 25 rows: the particle "
       "smoother's clouds would take 9.31323 GiB per run (at most 4 for [scenario.pend]): fewer "
       "particles or steps"},
      {"keep-runs = 0,2", "keep-runs = 0,4294967296",
       "s.ini:5: [study] keep-runs: must be in [0, 99999999], got 4294967296"},
      {"particles = 100", "particles = 1000000000",
       "s.ini:32: [filter.pf] particles: must be in [1, 10000000], got 1000000000"},
  };
  for (const Case& c : cases) {
    const std::string message = ParseError(Replace(good, c.from, c.to));
    EXPECT_EQ(message.rfind(c.expect, 0), 0u) << "got: " << message << "\nexpected: " << c.expect;
  }
  if (FiltersAvailable()) {
    EXPECT_EQ(ParseError(Replace(good, "alpha = 0.5", "alpha = abc"))
                  .rfind("s.ini:27: [filter.ukf] alpha: 'abc' is not a number", 0),
              0u)
        << ParseError(Replace(good, "alpha = 0.5", "alpha = abc"));
    // The filter's own check of its options, reported at the key's line.
    EXPECT_EQ(ParseError(Replace(good, "alpha = 0.5", "alpha = -1"))
                  .rfind("s.ini:27: [filter.ukf] alpha: must be > 0 and finite, got -1", 0),
              0u)
        << ParseError(Replace(good, "alpha = 0.5", "alpha = -1"));
    EXPECT_EQ(ParseError(Replace(good, "particles = 100", "particles = 0"))
                  .rfind("s.ini:32: [filter.pf] particles: must be >= 1", 0),
              0u)
        << ParseError(Replace(good, "particles = 100", "particles = 0"));
  }
}

TEST(StudyConfig, OracleRNeedsMeasurementNoise) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const std::string message =
      ParseError(Replace(TinyStudy(2), "meas-noise-var = 0.01", "meas-noise-var = 0"));
  EXPECT_NE(message.find("s.ini:37: [noise.oracle] r: the oracle R of [scenario.pend] is singular"),
            std::string::npos)
      << message;
}

TEST(StudyConfig, TunedNoiseSettings) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const StudyConfig c = ParseStudyConfig(TinyStudy(3, 25, 100, /*tuned=*/true), "s.ini");
  const ScenarioConfig& s = c.scenarios[0];
  // 3 filters x 2 settings + EKF and UKF with the tuned setting (not the PF).
  ASSERT_EQ(s.combos.size(), 8u);
  const Combo& ekf_tuned = s.combos[2];
  EXPECT_EQ(c.noises[ekf_tuned.noise].name, "tuned");
  EXPECT_TRUE(ekf_tuned.tune);
  EXPECT_EQ(ekf_tuned.tune_datasets, 2);
  EXPECT_EQ(ekf_tuned.tuner.q_param, NoiseParam::kWhiteAccel);  // the start's shape
  EXPECT_EQ(ekf_tuned.tuner.r_param, NoiseParam::kDiag);
  EXPECT_TRUE(ekf_tuned.spec.q_white_accel);
  EXPECT_DOUBLE_EQ(ekf_tuned.spec.qc, 0.1);  // the start
  EXPECT_EQ(ekf_tuned.spec.r, std::vector<double>{0.1});
  EXPECT_FALSE(s.combos[0].tune);
  // Errors: a start without `tuned`, and the tuner on a particle filter.
  std::string text = TinyStudy(3, 25, 100, true);
  EXPECT_EQ(ParseError(Replace(text, "r = tuned\ninit-r-diag", "r = oracle\ninit-r-diag"))
                .rfind("s.ini:47: [noise.tuned] init-r-diag: an initial guess needs r = tuned", 0),
            0u)
      << ParseError(Replace(text, "r = tuned\ninit-r-diag", "r = oracle\ninit-r-diag"));
  EXPECT_NE(ParseError(Replace(text, "filters = ekf,ukf", "filters = ekf,pf"))
                .find("s.ini:29: [filter.pf] with [scenario.pend] and [noise.tuned]"),
            std::string::npos)
      << ParseError(Replace(text, "filters = ekf,ukf", "filters = ekf,pf"));
}

// Issue 35: a noise section gives R per sensor group on one line,
// `r-diag = GROUP=values, GROUP=values` (the command line's --r-diag once per
// group); a group's block may hold several values, `r` takes a matrix per
// group, and the start of a tuned R reads the same. Errors name the line.
TEST(StudyConfig, NoiseSectionsGiveRPerSensorGroup) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  const std::string head =
      "[study]\nname = g\nseed = 1\nruns = 2\n\n"
      "[scenario.cart]\nmodel = cart-pole\nx0 = theta=3\ndt = 0.01\nsteps = 50\n"
      "process-noise = diag 1e-8,1e-6,1e-8,1e-6\nmeasurement = position,encoder\n"
      "meas-noise-var = 1e-4,1e-4\nsensor-rate = position=1\n"
      "prior-p0-diag = 1e-4,1e-4,1e-4,1e-4\n\n[filter.ekf]\nkind = ekf\n\n";
  const std::string diag =
      head + "[noise.hand]\nq = oracle\nr-diag = position=2e-4, encoder=3e-4\n";
  const StudyConfig c = ParseStudyConfig(diag, "s.ini");
  ASSERT_EQ(c.scenarios[0].combos.size(), 1u);
  EXPECT_EQ(c.scenarios[0].combos[0].spec.r, (std::vector<double>{2e-4, 0.0, 0.0, 3e-4}));
  const StudyConfig m = ParseStudyConfig(
      head + "[noise.hand]\nq = oracle\nr = encoder=3e-4, position=2e-4\n", "s.ini");
  EXPECT_EQ(m.scenarios[0].combos[0].spec.r, (std::vector<double>{2e-4, 0.0, 0.0, 3e-4}));
  const StudyConfig t = ParseStudyConfig(
      head +
          "[noise.tuned]\nq = oracle\nr = tuned\ninit-r-diag = position=5e-4, encoder=6e-4\n"
          "r-param = position=scalar,encoder=scalar\n",
      "s.ini");
  EXPECT_TRUE(t.scenarios[0].combos[0].tune);
  EXPECT_EQ(t.scenarios[0].combos[0].spec.r, (std::vector<double>{5e-4, 0.0, 0.0, 6e-4}));
  for (const auto& [bad, expected] : std::vector<std::pair<std::string, std::string>>{
           {"position=2e-4, gps=3e-4", "unknown sensor group 'gps'"},
           {"position=2e-4, position=3e-4", "sensor group 'position' is given twice"},
           {"position=2e-4", "no R for sensor group 'encoder'"},
           {"2e-4, encoder=3e-4", "not both"},
           {"position=2e-4,1, encoder=3e-4", "one per output of group 'position'"}}) {
    const std::string error = ParseError(Replace(diag, "position=2e-4, encoder=3e-4", bad));
    EXPECT_EQ(error.rfind("s.ini:22: [noise.hand] r-diag: ", 0), 0u) << bad << ": " << error;
    EXPECT_NE(error.find(expected), std::string::npos) << bad << ": " << error;
  }
}

// The truth's white-acceleration covariance pairs states (0,1), (2,3), ...;
// the filters use each model's own (position, rate) pairs. They must agree.
TEST(StudyConfig, WhiteAccelPairsMatchEveryModel) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  for (const ModelEntry* model : AllModels()) {
    const int n = int(model->states.size());
    const MeasurementDesc& meas = model->measurements[0];
    FilterSpec spec;
    spec.params = model->ResolveParams({});
    spec.measurement = meas.name;
    spec.filter = EkfOptions{};
    spec.transition.integrator = Integrator::kRk4;
    spec.x0.assign(n, 0.1);
    spec.p0.assign(n * n, 0.0);
    for (int i = 0; i < n; ++i) spec.p0[i * n + i] = 1.0;
    spec.q_white_accel = true;
    spec.qc = 2.0;
    const int m = int(meas.outputs.size());
    spec.r.assign(m * m, 0.0);
    for (int j = 0; j < m; ++j) spec.r[j * m + j] = 1.0;
    FilterData data;
    data.t = {0.0, 0.2};
    data.lines = {1, 2};
    data.m = m;
    data.z.assign(2 * m, 0.1);
    const FilterRunOutput out = model->run_filter(spec, data);
    ASSERT_EQ(out.summary.final_q.size(), size_t(n * n)) << model->name;
    const std::vector<double> ours = WhiteAccelCovariance(*model, 2.0, 0.2);
    for (int k = 0; k < n * n; ++k)
      EXPECT_NEAR(out.summary.final_q[k], ours[k], 1e-15) << model->name << " entry " << k;
  }
}

TEST(StudyStats, MatchHandComputedValues) {
  // 1..5: mean 3, sample variance 2.5, percentiles by linear interpolation.
  const MetricStats s = ComputeStats({5, 1, 4, 2, 3, std::nan("")});
  EXPECT_EQ(s.n, 5);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.var, 2.5);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(2.5));
  EXPECT_DOUBLE_EQ(s.ci95_lo, 3.0 - 1.96 * std::sqrt(2.5) / std::sqrt(5.0));
  EXPECT_DOUBLE_EQ(s.median, 3.0);
  EXPECT_DOUBLE_EQ(s.p2_5, 1.0 + 0.025 * 4 * 1.0);  // h = 0.1 between 1 and 2
  EXPECT_DOUBLE_EQ(s.p97_5, 4.9);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 5.0);
  const MetricStats empty = ComputeStats({});
  EXPECT_EQ(empty.n, 0);
  EXPECT_TRUE(std::isnan(empty.mean));
}

}  // namespace
}  // namespace estlab
