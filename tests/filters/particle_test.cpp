// Particle filter: agreement with the Kalman filter on linear-Gaussian data
// within Monte Carlo error, unbiased resampling schemes, determinism for a
// seed, failures as statuses.
#include "src/filters/particle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "linear_fixture.h"
#include "models/pendulum.h"

namespace estlab::testing {
namespace {

using Osc = DampedOscillator;

// One PF run beside the KF: per step (after each update) the PF mean,
// variances and ESS, and the KF mean and variances; total log-likelihoods.
struct PfTrace {
  std::vector<Vec<double, 2>> pf_mean, pf_var, kf_mean, kf_var;
  std::vector<double> ess;
  double loglik_pf = 0.0, loglik_kf = 0.0;
};

PfTrace RunPfBesideKf(const LinearData<2, 1>& data, int particles, uint64_t seed) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  HandKf<2, 1> kf = EulerReference<Osc, Osc::Position>(params, data.dt);
  ParticleOptions options;
  options.num_particles = particles;
  options.seed = seed;
  ParticleFilter<Osc, Osc::Position> pf(transition.get(), params, options);
  pf.Initialize(data.x0, data.P0);
  kf.x = data.x0;
  kf.P = data.P0;
  PfTrace t;
  for (int k = 0; k < data.steps; ++k) {
    if (k > 0) {
      pf.SetInput(data.u[k - 1]);
      EXPECT_EQ(pf.Predict(data.t(k - 1), data.t(k), data.Q), FilterStatus::kOk);
      kf.Predict(data.Q, data.u[k - 1]);
    }
    const StepResult<1> r = pf.Update(data.z[k], data.R);
    EXPECT_EQ(r.status, FilterStatus::kOk) << r.message;
    const auto o = kf.Update(data.z[k], data.R);
    t.loglik_pf += r.log_likelihood;
    t.loglik_kf += o.log_likelihood;
    t.pf_mean.push_back(pf.mean());
    t.pf_var.push_back(pf.cov().diagonal());
    t.kf_mean.push_back(kf.x);
    t.kf_var.push_back(kf.P.diagonal());
    t.ess.push_back(pf.effective_sample_size());
  }
  return t;
}

// Monte Carlo criterion (R = 8 independent runs of 10^4 particles, fixed
// seeds, 200 steps of linear-Gaussian data, position measured).
//
// 1. Importance-sampling standard error, observed component. After an update
//    the PF mean is a self-normalised importance-sampling estimate of the KF
//    mean with standard error ~ sqrt(P_jj / ESS) (Kong 1992). For the
//    measured position this holds (measured: z-scores with rms ~1.1), so
//    >= 95% of the steps of each run must be within 3 such standard errors.
//    For the unmeasured velocity it does NOT: velocity is inferred from the
//    particles' history, which resampling has thinned, so the PF error is 2-3
//    times sqrt(P/ESS) (measured rms z ~2-3 for 10^4 and 4*10^4 particles
//    alike, i.e. not a bias). It is therefore checked by 2.
// 2. Empirical standard error, both components: over the R runs, the mean m^
//    and standard deviation s of the PF mean; t = (m^ - m_kf) / (s / sqrt R)
//    is Student-t with R - 1 = 7 degrees of freedom for an unbiased PF
//    (P(|t| > 3.5) = 1%); >= 95% of the steps must have |t| <= 3.5.
// 3. Log-likelihood: the total over 200 steps (about -18.7 here) has a
//    Monte Carlo spread of ~0.2 per run, i.e. 1% of it, so 1% is asserted for
//    the average over the R runs (spread ~0.07), together with |t| <= 3.5
//    built from the spread of the runs; each single run within 5%.
// 4. Posterior variances: the R-run average within 5% of the KF's.
TEST(ParticleFilterTest, AgreesWithKalmanFilterOnLinearGaussianData) {
  const Osc::Params params;
  const HandKf<2, 1> kf = EulerReference<Osc, Osc::Position>(params, 0.1);
  const LinearData<2, 1> data = MakeLinearData<2, 1>(kf.F, kf.G, kf.H, 200, 71, /*gap=*/0);
  constexpr int kRuns = 8;
  std::vector<PfTrace> runs;
  for (int r = 0; r < kRuns; ++r) runs.push_back(RunPfBesideKf(data, 10000, 2024 + r));
  const int steps = data.steps;

  // 1. Observed component within 3 sqrt(P / ESS).
  for (int r = 0; r < kRuns; ++r) {
    int within = 0;
    for (int k = 0; k < steps; ++k) {
      const PfTrace& t = runs[r];
      const double se = std::sqrt(t.kf_var[k](0) / t.ess[k]);
      if (std::abs(t.pf_mean[k](0) - t.kf_mean[k](0)) <= 3 * se) ++within;
    }
    if (r == 0)
      std::printf("[ measured ] pf run 0: position within 3 sqrt(P/ESS) at %d/%d steps\n", within,
                  steps);
    EXPECT_GE(within, 0.95 * steps) << "run " << r;
  }
  // 2. Both components: replicate t-statistics.
  int within_t[2] = {0, 0};
  double worst_var_err = 0.0;
  for (int k = 0; k < steps; ++k) {
    for (int j = 0; j < 2; ++j) {
      double sum = 0, sum_sq = 0, var_sum = 0;
      for (const PfTrace& t : runs) {
        sum += t.pf_mean[k](j);
        sum_sq += t.pf_mean[k](j) * t.pf_mean[k](j);
        var_sum += t.pf_var[k](j);
      }
      const double mean = sum / kRuns;
      const double sd = std::sqrt(std::max(0.0, (sum_sq - kRuns * mean * mean) / (kRuns - 1)));
      const double t_stat = (mean - runs[0].kf_mean[k](j)) / (sd / std::sqrt(double(kRuns)));
      if (std::abs(t_stat) <= 3.5) ++within_t[j];
      worst_var_err = std::max(worst_var_err, std::abs(var_sum / kRuns / runs[0].kf_var[k](j) - 1));
    }
  }
  // 3. Log-likelihoods.
  double ll_sum = 0, ll_sum_sq = 0;
  for (const PfTrace& t : runs) {
    ll_sum += t.loglik_pf;
    ll_sum_sq += t.loglik_pf * t.loglik_pf;
    EXPECT_NEAR(t.loglik_pf, t.loglik_kf, 0.05 * std::abs(t.loglik_kf));
  }
  const double ll_mean = ll_sum / kRuns;
  const double ll_sd =
      std::sqrt(std::max(0.0, (ll_sum_sq - kRuns * ll_mean * ll_mean) / (kRuns - 1)));
  const double ll_kf = runs[0].loglik_kf;
  std::printf(
      "[ measured ] pf (8 x 1e4 particles): |t| <= 3.5 at %d/%d (x) and %d/%d (v) steps; "
      "loglik mean %.4f sd %.4f vs kf %.4f (%.2f%%, t = %.2f); "
      "max |mean var_pf / var_kf - 1| = %.3f\n",
      within_t[0], steps, within_t[1], steps, ll_mean, ll_sd, ll_kf,
      100 * std::abs(ll_mean / ll_kf - 1), (ll_mean - ll_kf) / (ll_sd / std::sqrt(double(kRuns))),
      worst_var_err);
  EXPECT_GE(within_t[0], 0.95 * steps);
  EXPECT_GE(within_t[1], 0.95 * steps);
  EXPECT_NEAR(ll_mean, ll_kf, 0.01 * std::abs(ll_kf));
  EXPECT_LE(std::abs(ll_mean - ll_kf), 3.5 * ll_sd / std::sqrt(double(kRuns)));
  // 4. Variances.
  EXPECT_LT(worst_var_err, 0.05);
}

TEST(ParticleFilterTest, SameSeedSameResultsDifferentSeedDifferentResults) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  HandKf<2, 1> kf = EulerReference<Osc, Osc::Position>(params, 0.1);
  const LinearData<2, 1> data = MakeLinearData<2, 1>(kf.F, kf.G, kf.H, 30, 72, 0);
  auto run = [&](uint64_t seed, ResampleScheme scheme) {
    ParticleOptions options;
    options.num_particles = 200;
    options.seed = seed;
    options.resample = scheme;
    ParticleFilter<Osc, Osc::Position> pf(transition.get(), params, options);
    pf.Initialize(data.x0, data.P0);
    double loglik = 0.0;
    for (int k = 0; k < data.steps; ++k) {
      if (k > 0) pf.Predict(data.t(k - 1), data.t(k), data.Q);
      loglik += pf.Update(data.z[k], data.R).log_likelihood;
    }
    return std::make_pair(loglik, Vec<double, 2>(pf.mean()));
  };
  for (ResampleScheme s : {ResampleScheme::kMultinomial, ResampleScheme::kSystematic,
                           ResampleScheme::kStratified, ResampleScheme::kResidual}) {
    const auto a = run(5, s), b = run(5, s), c = run(6, s);
    EXPECT_EQ(a.first, b.first);
    EXPECT_TRUE((a.second == b.second));
    EXPECT_NE(a.first, c.first);
  }
}

// Fixed weights with zeros, tiny and large ones, N = 40 particles.
std::vector<double> TestWeights() {
  std::vector<double> w(40);
  for (int i = 0; i < 40; ++i) w[i] = 0.5 + std::sin(1.7 * i) + (i == 7 ? 6.0 : 0.0);
  for (double& v : w) v = std::max(v, 0.0);
  w[3] = 0.0;
  w[11] = 1e-6;
  const double sum = std::accumulate(w.begin(), w.end(), 0.0);
  for (double& v : w) v /= sum;
  return w;
}

TEST(ResampleTest, EverySchemeKeepsTheExpectedNumberOfCopies) {
  const std::vector<double> w = TestWeights();
  const int n = int(w.size());
  const int trials = 20000;
  std::vector<int> indices;
  bool stratified_left_floor_ceil = false;
  for (ResampleScheme scheme : {ResampleScheme::kMultinomial, ResampleScheme::kSystematic,
                                ResampleScheme::kStratified, ResampleScheme::kResidual}) {
    const char* name = ResampleSchemeName(scheme);
    Rng rng(99);
    std::vector<double> sum(n, 0.0), sum_sq(n, 0.0);
    for (int t = 0; t < trials; ++t) {
      Resample(w, scheme, rng, &indices);
      ASSERT_EQ(int(indices.size()), n);
      ASSERT_TRUE(std::is_sorted(indices.begin(), indices.end())) << name;
      std::vector<int> copies(n, 0);
      for (int i : indices) {
        ASSERT_GE(i, 0);
        ASSERT_LT(i, n);
        ++copies[i];
      }
      for (int i = 0; i < n; ++i) {
        const double nw = n * w[i];
        const int lo = int(std::floor(nw)), hi = int(std::ceil(nw));
        if (scheme == ResampleScheme::kSystematic) {
          ASSERT_TRUE(copies[i] == lo || copies[i] == hi) << name << " particle " << i;
        } else if (scheme == ResampleScheme::kResidual) {
          ASSERT_GE(copies[i], lo) << name << " particle " << i;
        } else if (scheme == ResampleScheme::kStratified) {
          // One draw per stratum of width 1/N: a particle whose CDF interval
          // cuts two strata can get one copy more or less than floor/ceil.
          ASSERT_LT(std::abs(copies[i] - nw), 2.0) << name << " particle " << i;
          if (copies[i] < lo || copies[i] > hi) stratified_left_floor_ceil = true;
        }
        if (w[i] == 0.0) {
          ASSERT_EQ(copies[i], 0) << name;
        }
        sum[i] += copies[i];
        sum_sq[i] += double(copies[i]) * copies[i];
      }
    }
    // E[copies_i] = N w_i: the sample mean within 4 standard errors. The
    // standard error uses the sample variance, but at least f (1 - f) with
    // f = frac(N w_i), the smallest variance any unbiased integer count can
    // have (so a particle with N w_i = 1e-6 that was never drawn in 20000
    // trials is judged against sqrt(1e-6 / 20000), not against 0).
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
      const double mean = sum[i] / trials;
      const double f = n * w[i] - std::floor(n * w[i]);
      const double var = std::max(sum_sq[i] / trials - mean * mean, f * (1 - f));
      const double se = std::sqrt(var / trials);
      EXPECT_LE(std::abs(mean - n * w[i]), 4 * se + 1e-9)
          << name << " particle " << i << " mean " << mean << " expected " << n * w[i];
      if (se > 0) worst = std::max(worst, std::abs(mean - n * w[i]) / se);
    }
    std::printf("[ measured ] resample %-11s worst |mean copies - N w| = %.2f se\n", name, worst);
  }
  // Documents why floor/ceil is not asserted for stratified resampling.
  EXPECT_TRUE(stratified_left_floor_ceil);
}

TEST(ResampleTest, ParseAndNames) {
  EXPECT_EQ(ParseResampleScheme("multinomial"), ResampleScheme::kMultinomial);
  EXPECT_EQ(ParseResampleScheme("systematic"), ResampleScheme::kSystematic);
  EXPECT_EQ(ParseResampleScheme("stratified"), ResampleScheme::kStratified);
  EXPECT_EQ(ParseResampleScheme("residual"), ResampleScheme::kResidual);
  EXPECT_THROW(ParseResampleScheme("Systematic "), InputError);
  EXPECT_STREQ(ResampleSchemeName(ResampleScheme::kResidual), "residual");
  Eigen::VectorXd v(3);
  v << -1000.0, -1000.0 + std::log(3.0), -std::numeric_limits<double>::infinity();
  EXPECT_NEAR(LogSumExp(v), -1000.0 + std::log(4.0), 1e-12);
}

TEST(ParticleFilterTest, ResamplesWhenTheEffectiveSampleSizeDrops) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  ParticleOptions options;
  options.num_particles = 500;
  options.ess_threshold = 0.5;
  ParticleFilter<Osc, Osc::Position> pf(transition.get(), params, options);
  pf.Initialize(Vec<double, 2>(0, 0), Mat<2, 2>::Identity());
  // A precise measurement far in the tail: ESS collapses, the filter resamples.
  StepResult<1> r = pf.Update(Vec<double, 1>(1.5), Mat<1, 1>::Constant(1e-3));
  ASSERT_EQ(r.status, FilterStatus::kOk);
  EXPECT_LT(pf.effective_sample_size(), 0.5 * 500);
  EXPECT_TRUE(pf.resampled());
  for (double w : pf.weights()) EXPECT_EQ(w, 1.0 / 500);
  // A vague measurement keeps the ESS high: no resampling.
  r = pf.Update(Vec<double, 1>(pf.mean()(0)), Mat<1, 1>::Constant(1e3));
  EXPECT_GT(pf.effective_sample_size(), 0.99 * 500);
  EXPECT_FALSE(pf.resampled());
  // innovation_cov = weighted variance of h(x_i) + R.
  EXPECT_GT(r.innovation_cov(0, 0), 1e3);
}

TEST(ParticleFilterTest, CircularMeanOfAngleStates) {
  using P = models::Pendulum;
  const P::Params params;
  auto transition = EulerTransition<P>(params);
  ParticleOptions options;
  options.num_particles = 4000;
  ParticleFilter<P, P::Angle> pf(transition.get(), params, options);
  // Particles around theta = pi (never wrapped): their plain weighted mean
  // stays near pi, and a measurement wrapped to -pi + 0.01 gives a wrapped
  // innovation of 0.01.
  pf.Initialize(Vec<double, 2>(M_PI, 0.0), 0.01 * Mat<2, 2>::Identity());
  EXPECT_NEAR(pf.mean()(0), M_PI, 0.01);
  EXPECT_NEAR(pf.cov()(0, 0), 0.01, 0.002);
  const StepResult<1> r = pf.Update(Vec<double, 1>(-M_PI + 0.01), Mat<1, 1>::Constant(0.01));
  ASSERT_EQ(r.status, FilterStatus::kOk);
  EXPECT_NEAR(r.innovation(0), 0.01, 0.01);
  EXPECT_NEAR(pf.mean()(0), M_PI + 0.005, 0.01);
}

TEST(ParticleFilterTest, ZeroProcessNoiseAndSingularPriorAreAllowed) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  ParticleOptions options;
  options.num_particles = 50;
  ParticleFilter<Osc, Osc::Position> pf(transition.get(), params, options);
  Mat<2, 2> P0;
  P0 << 1, 1, 1, 1;  // rank 1
  pf.Initialize(Vec<double, 2>(1, 0), P0);
  ASSERT_EQ(pf.Predict(0.0, 0.1, Mat<2, 2>::Zero()), FilterStatus::kOk);
  // All particles moved by the same linear map, no noise: they stay on a line.
  const auto& X = pf.particles();
  const Mat<2, 2> F = Mat<2, 2>::Identity() + 0.1 * Osc::A(params);
  for (Eigen::Index i = 0; i < X.cols(); ++i) {
    const Vec<double, 2> back = F.partialPivLu().solve(Vec<double, 2>(X.col(i)));
    EXPECT_NEAR(back(0) - back(1), 1.0, 1e-12);
  }
}

TEST(ParticleFilterTest, FailuresAreStatuses) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  ParticleOptions options;
  options.num_particles = 100;
  {
    ParticleFilter<Osc, Osc::Position> pf(transition.get(), params, options);
    pf.Initialize(Vec<double, 2>(1, 0), (Mat<2, 2>() << 1, 0, 0, -1).finished());
    EXPECT_EQ(pf.Predict(0.0, 0.1, Mat<2, 2>::Identity()), FilterStatus::kFactorizationFailed);
    EXPECT_NE(pf.last_error().find("P0"), std::string::npos) << pf.last_error();
  }
  {
    ParticleFilter<Osc, Osc::Position> pf(transition.get(), params, options);
    pf.Initialize(Vec<double, 2>(1, 0), Mat<2, 2>::Identity());
    const StepResult<1> r = pf.Update(Vec<double, 1>(1.0), -Mat<1, 1>::Identity());
    EXPECT_EQ(r.status, FilterStatus::kFactorizationFailed);
    EXPECT_NE(r.message.find("R"), std::string::npos);
    EXPECT_EQ(pf.Predict(0.0, 0.1, -Mat<2, 2>::Identity()), FilterStatus::kFactorizationFailed);
    EXPECT_NE(pf.last_error().find("Q"), std::string::npos);
    // A measurement no particle can explain: every likelihood underflows.
    const StepResult<1> far = pf.Update(Vec<double, 1>(1e200), Mat<1, 1>::Constant(1e-6));
    EXPECT_EQ(far.status, FilterStatus::kNonFinite);
  }
  {
    ThrowingTransition<Osc> throwing(params);
    ParticleFilter<Osc, Osc::Position> pf(&throwing, params, options);
    pf.Initialize(Vec<double, 2>(1, 0), Mat<2, 2>::Identity());
    EXPECT_EQ(pf.Predict(0.0, 0.1, Mat<2, 2>::Identity()), FilterStatus::kTransitionFailed);
  }
  options.num_particles = 0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_THROW((ParticleFilter<Osc, Osc::Position>(transition.get(), params, options)), InputError);
  options.num_particles = 10;
  options.ess_threshold = 1.5;
  EXPECT_FALSE(options.IsValid(&error));
}

}  // namespace
}  // namespace estlab::testing
