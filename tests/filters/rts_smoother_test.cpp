// The RTS smoother (src/filters/rts_smoother.h) behind every Gaussian filter,
// against an independent closed form: on a linear-Gaussian model the smoothed
// means, covariances and lag-one covariances are the moments of the stacked
// states X = [x_0; ...; x_K] conditioned on all measurements, computed here
// by one batch Gaussian conditioning (no recursion):
//   m_0 = x0, m_k = F m_{k-1} + G u_{k-1},
//   Cov(x_k, x_k) = F Cov(x_{k-1}, x_{k-1}) F^T + Q,  Cov(x_j, x_k) = F^{j-k} Cov(x_k, x_k),
//   Z = H X + V,  E[X | Z] = m + S_XZ S_ZZ^-1 (z - H m),  Cov = S_XX - S_XZ S_ZZ^-1 S_ZX.
// The KF (exact discretisation: F = e^{A dt}), the EKF and the unscented,
// cubature and Gauss-Hermite filters (Euler transition: F = I + dt A) with
// zero jitter must all reproduce it, with every 7th measurement missing.
#include "src/filters/rts_smoother.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

#include "linear_fixture.h"
#include "models/pendulum.h"
#include "src/core/random.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/sigma_point.h"

namespace estlab {
namespace {

using testing::CoupledOscillators;
using testing::DampedOscillator;
using testing::LinearData;
using testing::MakeLinearData;

// The smoothed moments of the batch conditioning.
template <int N>
struct Batch {
  std::vector<Vec<double, N>> mean;
  std::vector<Mat<N, N>> cov, lag_one;  // lag_one[k] = Cov(x_k, x_{k+1} | Z)
};

template <int N, int M>
Batch<N> BatchSmoother(const Mat<N, N>& F, const Vec<double, N>& G, const Mat<M, N>& H,
                       const LinearData<N, M>& d) {
  const int K = d.steps;
  Eigen::VectorXd m(N * K);
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(N * K, N * K);
  m.segment<N>(0) = d.x0;
  S.block<N, N>(0, 0) = d.P0;
  for (int k = 1; k < K; ++k) {
    m.segment<N>(N * k) = F * m.segment<N>(N * (k - 1)) + G * d.u[k - 1];
    // Cov(x_k, x_j) = F Cov(x_{k-1}, x_j) for j < k; + Q on the diagonal.
    for (int j = 0; j < k; ++j) {
      S.block<N, N>(N * k, N * j) = F * S.block<N, N>(N * (k - 1), N * j);
      S.block<N, N>(N * j, N * k) = S.block<N, N>(N * k, N * j).transpose();
    }
    S.block<N, N>(N * k, N * k) = F * S.block<N, N>(N * (k - 1), N * (k - 1)) * F.transpose() + d.Q;
  }
  std::vector<int> rows;
  for (int k = 0; k < K; ++k)
    if (d.has_z[k]) rows.push_back(k);
  const int nz = int(rows.size()) * M;
  Eigen::MatrixXd Hb = Eigen::MatrixXd::Zero(nz, N * K), Rb = Eigen::MatrixXd::Zero(nz, nz);
  Eigen::VectorXd z(nz);
  for (size_t i = 0; i < rows.size(); ++i) {
    Hb.block<M, N>(M * i, N * rows[i]) = H;
    Rb.block<M, M>(M * i, M * i) = d.R;
    z.segment<M>(M * i) = d.z[rows[i]];
  }
  const Eigen::MatrixXd Sxz = S * Hb.transpose();
  const Eigen::MatrixXd Szz = Hb * S * Hb.transpose() + Rb;
  const Eigen::MatrixXd gain = Szz.ldlt().solve(Sxz.transpose()).transpose();
  const Eigen::VectorXd mean = m + gain * (z - Hb * m);
  const Eigen::MatrixXd cov = S - gain * Sxz.transpose();
  Batch<N> out;
  for (int k = 0; k < K; ++k) {
    out.mean.push_back(mean.segment<N>(N * k));
    out.cov.push_back(cov.block<N, N>(N * k, N * k));
    if (k + 1 < K) out.lag_one.push_back(cov.block<N, N>(N * k, N * (k + 1)));
  }
  return out;
}

// Runs the filter forward, recording into an RtsSmoother, and smooths.
template <class Model, class Meas, int N = Model::kStateDim, int M = Meas::kDim>
RtsSmoother<N> SmoothWith(Filter<Model, Meas>& filter, const LinearData<N, M>& d) {
  RtsSmoother<N> rts;
  filter.Initialize(d.x0, d.P0);
  for (int k = 0; k < d.steps; ++k) {
    if (k > 0) {
      filter.SetInput(d.u[k - 1]);
      EXPECT_EQ(filter.Predict(d.t(k - 1), d.t(k), d.Q), FilterStatus::kOk);
      Mat<N, N> C = Mat<N, N>::Zero();
      EXPECT_TRUE(filter.PredictCrossCov(&C));
      rts.AddPredicted(filter.mean(), filter.cov(), C);
    }
    if (d.has_z[k]) {
      EXPECT_EQ(filter.Update(d.z[k], d.R).status, FilterStatus::kOk);
    }
    rts.AddFiltered(filter.mean(), filter.cov());
  }
  std::string why;
  EXPECT_TRUE(rts.Smooth(&why, LagOne::kCompute)) << why;
  return rts;
}

// Largest scaled difference of means, covariances and lag-one covariances.
template <int N>
double Deviation(const RtsSmoother<N>& rts, const Batch<N>& ref) {
  double worst = 0.0;
  for (size_t k = 0; k < ref.mean.size(); ++k) {
    worst = std::max(worst, testing::ScaledDiff(rts.mean(k), ref.mean[k]));
    worst = std::max(worst, testing::ScaledDiff(rts.cov(k), ref.cov[k]));
    if (k + 1 < ref.mean.size())
      worst = std::max(worst, testing::ScaledDiff(rts.lag_one_cov(k), ref.lag_one[k]));
  }
  return worst;
}

template <class Model, class Meas>
void CheckEveryGaussianFilter(uint64_t seed) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const typename Model::Params params;
  const double dt = 0.1;
  const Mat<N, N> A = Model::A(params);
  // Euler: F = I + dt A, G = dt B.
  const Mat<N, N> F_euler = Mat<N, N>::Identity() + dt * A;
  const Vec<double, N> G_euler = dt * Model::B();
  const LinearData<N, M> d = MakeLinearData<N, M>(F_euler, G_euler, Meas::H(), 60, seed);
  const Batch<N> euler = BatchSmoother<N, M>(F_euler, G_euler, Meas::H(), d);
  // Exact: [F G; 0 1] = exp([A B; 0 0] dt).
  Mat<N + 1, N + 1> aug = Mat<N + 1, N + 1>::Zero();
  aug.template topLeftCorner<N, N>() = A * dt;
  aug.template topRightCorner<N, 1>() = Model::B() * dt;
  const Mat<N + 1, N + 1> e = aug.exp();
  const Batch<N> exact = BatchSmoother<N, M>(e.template topLeftCorner<N, N>(),
                                             e.template topRightCorner<N, 1>(), Meas::H(), d);

  auto transition = testing::EulerTransition<Model>(params);
  std::vector<std::pair<std::string, double>> results;
  {
    LinearizedKf<Model, Meas> kf(params, KfOptions{});
    results.push_back({"kf-rts", Deviation(SmoothWith(kf, d), exact)});
  }
  {
    Ekf<Model, Meas> ekf(transition.get(), params, EkfOptions{});
    results.push_back({"erts", Deviation(SmoothWith(ekf, d), euler)});
  }
  const std::pair<const char*, SigmaPointOptions> rules[] = {
      {"urts", {.rule = SigmaRule::kUnscented, .alpha = 0.5, .jitter = 0.0}},
      {"ckf-rts", {.rule = SigmaRule::kCubature, .jitter = 0.0}},
      {"ghkf-rts", {.rule = SigmaRule::kGaussHermite, .gh_order = 5, .jitter = 0.0}}};
  for (const auto& [label, options] : rules) {
    SigmaPointFilter<Model, Meas> f(transition.get(), params, options);
    results.push_back({label, Deviation(SmoothWith(f, d), euler)});
  }
  for (const auto& [label, dev] : results) {
    std::printf("  %s n=%d: largest scaled difference from the batch smoother %.2e\n",
                label.c_str(), N, dev);
    EXPECT_LT(dev, label == "kf-rts" ? 1e-12 : 1e-10) << label;
  }
}

TEST(RtsSmoother, EveryGaussianFilterEqualsTheBatchSmootherOnALinearModel) {
  CheckEveryGaussianFilter<DampedOscillator, DampedOscillator::Mixed>(11);
  CheckEveryGaussianFilter<CoupledOscillators, CoupledOscillators::Relative>(12);
}

TEST(RtsSmoother, RefusesAnInconsistentRecordingAndASingularPrediction) {
  RtsSmoother<2> rts;
  std::string why;
  EXPECT_FALSE(rts.Smooth(&why));
  rts.AddFiltered(Vec<double, 2>::Zero(), Mat<2, 2>::Identity());
  rts.AddFiltered(Vec<double, 2>::Zero(), Mat<2, 2>::Identity());
  EXPECT_FALSE(rts.Smooth(&why));
  EXPECT_NE(why.find("step 1 has no prediction from step 0"), std::string::npos) << why;
  // A prediction whose update never came is dropped before smoothing.
  rts.Clear();
  rts.AddFiltered(Vec<double, 2>::Zero(), Mat<2, 2>::Identity());
  rts.AddPredicted(Vec<double, 2>::Zero(), Mat<2, 2>::Identity(), Mat<2, 2>::Zero());
  EXPECT_FALSE(rts.Smooth(&why));
  EXPECT_NE(why.find("the last prediction has no filtered belief"), std::string::npos) << why;
  rts.DropUnfinishedStep();
  EXPECT_EQ(rts.filtered_steps(), 1u);
  EXPECT_TRUE(rts.Smooth(&why)) << why;
  rts.Clear();
  rts.AddFiltered(Vec<double, 2>::Zero(), Mat<2, 2>::Identity());
  rts.AddPredicted(Vec<double, 2>::Zero(), Mat<2, 2>::Zero(), Mat<2, 2>::Zero());
  rts.AddFiltered(Vec<double, 2>::Zero(), Mat<2, 2>::Identity());
  EXPECT_FALSE(rts.Smooth(&why));
  EXPECT_NE(why.find("step 1 is not positive definite"), std::string::npos) << why;
  // A single step smooths to itself.
  rts.Clear();
  rts.AddFiltered(Vec<double, 2>(1.0, 2.0), Mat<2, 2>::Identity());
  ASSERT_TRUE(rts.Smooth(&why));
  EXPECT_EQ(rts.mean(0)(0), 1.0);
  EXPECT_EQ(rts.mean(0)(1), 2.0);
}

// The pendulum benchmark of Saerkkae & Svensson (Bayesian Filtering and
// Smoothing, 2nd ed., 2023, the pendulum example of chs. 7-14): the Euler
// model x1' = x1 + x2 dt, x2' = x2 - g sin(x1) dt + q, g = 9.81, dt = 0.01,
// Q = qc [[dt^3/3, dt^2/2], [dt^2/2, dt]] with qc = 0.01, y = sin(x1) + r,
// R = 0.1, 500 steps; the truth starts at x = (1.5, 0) as in the book's code
// and the smoothers at the prior m0 = 0, P0 = I. The data are drawn
// here, by that recursion written out, for 20 seeds; the mean angle RMSE of
// each smoother is reported beside the book's single-realisation figures
// (ERTS 0.057, URTS 0.037, CRTS 0.041, GHRTS 0.037) and must lie within a
// factor 1.5 of them, and below its own forward filter's.
TEST(RtsSmoother, SaerkkaeSvenssonPendulumBenchmark) {
  using P = models::Pendulum;
  const P::Params params;  // g = 9.81, L = 1, b = 0
  constexpr double dt = 0.01, qc = 0.01, r = 0.1;
  constexpr int kSteps = 500, kSeeds = 20;
  Mat<2, 2> Q;
  Q << qc * dt * dt * dt / 3, qc * dt * dt / 2, qc * dt * dt / 2, qc * dt;
  const Mat<2, 2> LQ = Q.llt().matrixL();
  const Mat<1, 1> R = Mat<1, 1>::Constant(r);
  auto transition = testing::EulerTransition<P>(params);
  struct Case {
    const char* label;
    double book;
    std::function<std::unique_ptr<Filter<P, P::Sin>>()> make;
  };
  const std::vector<Case> cases = {
      {"erts", 0.057,
       [&] { return std::make_unique<Ekf<P, P::Sin>>(transition.get(), params, EkfOptions{}); }},
      {"urts", 0.037,
       [&] {
         return std::make_unique<SigmaPointFilter<P, P::Sin>>(
             transition.get(), params, SigmaPointOptions{.rule = SigmaRule::kUnscented});
       }},
      {"ckf-rts", 0.041,
       [&] {
         return std::make_unique<SigmaPointFilter<P, P::Sin>>(
             transition.get(), params, SigmaPointOptions{.rule = SigmaRule::kCubature});
       }},
      {"ghkf-rts", 0.037,
       [&] {
         return std::make_unique<SigmaPointFilter<P, P::Sin>>(
             transition.get(), params,
             SigmaPointOptions{.rule = SigmaRule::kGaussHermite, .gh_order = 3});
       }},
  };
  std::vector<double> smooth_rmse(cases.size(), 0.0), filter_rmse(cases.size(), 0.0);
  for (int seed = 0; seed < kSeeds; ++seed) {
    Rng rng(DeriveSeed({2023, uint64_t(seed)}));
    std::vector<Vec<double, 2>> x(kSteps);
    std::vector<double> y(kSteps);
    Vec<double, 2> s(1.5, 0.0);
    for (int k = 0; k < kSteps; ++k) {
      if (k > 0) {
        s = Vec<double, 2>(s(0) + s(1) * dt, s(1) - params.g * std::sin(s(0)) * dt) +
            LQ * Vec<double, 2>(rng.Normal(), rng.Normal());
      }
      x[k] = s;
      y[k] = std::sin(s(0)) + std::sqrt(r) * rng.Normal();
    }
    for (size_t c = 0; c < cases.size(); ++c) {
      auto filter = cases[c].make();
      RtsSmoother<2> rts;
      filter->Initialize(Vec<double, 2>::Zero(), Mat<2, 2>::Identity());
      double sq_filter = 0.0;
      for (int k = 0; k < kSteps; ++k) {
        if (k > 0) {
          ASSERT_EQ(filter->Predict((k - 1) * dt, k * dt, Q), FilterStatus::kOk);
          Mat<2, 2> C = Mat<2, 2>::Zero();
          ASSERT_TRUE(filter->PredictCrossCov(&C));
          rts.AddPredicted(filter->mean(), filter->cov(), C);
        }
        ASSERT_EQ(filter->Update(Vec<double, 1>(y[k]), R).status, FilterStatus::kOk);
        rts.AddFiltered(filter->mean(), filter->cov());
        sq_filter += std::pow(filter->mean()(0) - x[k](0), 2);
      }
      std::string why;
      ASSERT_TRUE(rts.Smooth(&why)) << why;
      double sq = 0.0;
      for (int k = 0; k < kSteps; ++k) sq += std::pow(rts.mean(k)(0) - x[k](0), 2);
      smooth_rmse[c] += std::sqrt(sq / kSteps) / kSeeds;
      filter_rmse[c] += std::sqrt(sq_filter / kSteps) / kSeeds;
    }
  }
  for (size_t c = 0; c < cases.size(); ++c) {
    std::printf("  %-9s angle RMSE %.4f (book %.3f), its filter %.4f, mean of %d data sets\n",
                cases[c].label, smooth_rmse[c], cases[c].book, filter_rmse[c], kSeeds);
    EXPECT_LT(smooth_rmse[c], 1.5 * cases[c].book) << cases[c].label;
    EXPECT_GT(smooth_rmse[c], cases[c].book / 1.5) << cases[c].label;
    EXPECT_LT(smooth_rmse[c], filter_rmse[c]) << cases[c].label;
  }
}

}  // namespace
}  // namespace estlab
