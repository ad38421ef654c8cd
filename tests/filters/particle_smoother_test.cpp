// The particle smoother (src/filters/particle_smoother.h): its backward
// weights against the formula evaluated by hand on small clouds, and the
// smoothed moments of 100 backward-simulated trajectories on a bootstrap
// filter with 10^4 particles against the RTS smoother, which is exact on a
// linear-Gaussian model (rts_smoother_test.cpp checks it against a batch
// Gaussian conditioning).
#include "src/filters/particle_smoother.h"

#include <gtest/gtest.h>
#include <Eigen/LU>

#include <cmath>
#include <cstdio>

#include "linear_fixture.h"
#include "src/filters/ekf.h"
#include "src/filters/particle.h"
#include "src/filters/rts_smoother.h"

namespace estlab {
namespace {

using testing::DampedOscillator;

TEST(ParticleSmoother, BackwardWeightsEqualTheFormulaByHand) {
  // 1-D: v_i ~ w_i exp(-(x' - m_i)^2 / (2 q)), q = 0.25, x' = 1.2:
  //   m = (0, 1, 3), w = (0.2, 0.5, 0.3)
  //   exponents (1.2^2, 0.2^2, 1.8^2) / 0.5 = (2.88, 0.08, 6.48)
  ParticleCloud means(1, 3);
  means << 0.0, 1.0, 3.0;
  std::vector<double> v;
  ASSERT_TRUE(BackwardWeights(means, {0.2, 0.5, 0.3}, Eigen::MatrixXd::Constant(1, 1, 0.5),
                              Eigen::VectorXd::Constant(1, 1.2), &v));
  const double a = 0.2 * std::exp(-2.88), b = 0.5 * std::exp(-0.08), c = 0.3 * std::exp(-6.48);
  EXPECT_NEAR(v[0], a / (a + b + c), 1e-15);
  EXPECT_NEAR(v[1], b / (a + b + c), 1e-15);
  EXPECT_NEAR(v[2], c / (a + b + c), 1e-15);
  // 2-D, correlated Q: the exponent is d^T Q^-1 d / 2 with the inverse taken
  // directly (the smoother uses a triangular solve with chol(Q)).
  Eigen::Matrix2d Q;
  Q << 0.5, 0.2, 0.2, 0.3;
  ParticleCloud m2(2, 2);
  m2 << 0.0, 1.0, 0.0, -0.5;
  const Eigen::Vector2d x(0.4, 0.1);
  ASSERT_TRUE(BackwardWeights(m2, {0.6, 0.4}, Eigen::MatrixXd(Q.llt().matrixL()), x, &v));
  const Eigen::Vector2d d0 = x - m2.col(0), d1 = x - m2.col(1);
  const double v0 = 0.6 * std::exp(-0.5 * d0.dot(Q.inverse() * d0));
  const double v1 = 0.4 * std::exp(-0.5 * d1.dot(Q.inverse() * d1));
  EXPECT_NEAR(v[0], v0 / (v0 + v1), 1e-14);
  EXPECT_NEAR(v[1], v1 / (v0 + v1), 1e-14);
  // Zero weights stay zero; far from every mean the weights are computed in
  // logs, so the nearest mean takes all (no 0 / 0); no positive weight is
  // refused.
  ASSERT_TRUE(BackwardWeights(means, {0.0, 1.0, 0.0}, Eigen::MatrixXd::Constant(1, 1, 0.5),
                              Eigen::VectorXd::Constant(1, 1.2), &v));
  EXPECT_EQ(v[0], 0.0);
  EXPECT_EQ(v[1], 1.0);
  ASSERT_TRUE(BackwardWeights(means, {0.2, 0.5, 0.3}, Eigen::MatrixXd::Constant(1, 1, 1e-3),
                              Eigen::VectorXd::Constant(1, 100.0), &v));
  EXPECT_EQ(v[2], 1.0);
  EXPECT_FALSE(BackwardWeights(means, {0.0, 0.0, 0.0}, Eigen::MatrixXd::Constant(1, 1, 0.5),
                               Eigen::VectorXd::Constant(1, 1.2), &v));
}

TEST(ParticleSmoother, SampleIndexInvertsTheCumulativeSum) {
  const std::vector<double> p = {0.2, 0.5, 0.3};
  EXPECT_EQ(SampleIndex(p, 0.0), 0u);
  EXPECT_EQ(SampleIndex(p, 0.19), 0u);
  EXPECT_EQ(SampleIndex(p, 0.2), 1u);
  EXPECT_EQ(SampleIndex(p, 0.69), 1u);
  EXPECT_EQ(SampleIndex(p, 0.71), 2u);
  EXPECT_EQ(SampleIndex({0.5, 0.5, 0.0}, 1.0), 1u);  // rounding: never a zero-weight index
}

TEST(ParticleSmoother, AgreesWithTheRtsSmootherOnALinearGaussianModel) {
  using Model = DampedOscillator;
  using Meas = DampedOscillator::Mixed;
  constexpr int N = 2;
  const Model::Params params;
  const double dt = 0.1;
  const Mat<N, N> F = Mat<N, N>::Identity() + dt * Model::A(params);  // Euler
  const auto d = testing::MakeLinearData<N, Meas::kDim>(F, dt * Model::B(), Meas::H(), 40, 21);
  auto transition = testing::EulerTransition<Model>(params);

  // Reference: ERTS on the same Euler transition (exact for this linear model).
  Ekf<Model, Meas> ekf(transition.get(), params, EkfOptions{});
  RtsSmoother<N> rts;
  ParticleFilter<Model, Meas> pf(transition.get(), params,
                                 ParticleOptions{.num_particles = 10000, .seed = 5});
  ParticleSmoother<N> ps;
  ekf.Initialize(d.x0, d.P0);
  pf.Initialize(d.x0, d.P0);
  Eigen::Matrix<double, N, Eigen::Dynamic> means(N, 10000);
  std::string why;
  for (int k = 0; k < d.steps; ++k) {
    if (k > 0) {
      ekf.SetInput(d.u[k - 1]);
      pf.SetInput(d.u[k - 1]);
      transition->StepCloud(pf.particles(), d.t(k - 1), d.t(k), &means);
      ASSERT_TRUE(ps.AddPredicted(means, d.Q, &why)) << why;
      ASSERT_EQ(ekf.Predict(d.t(k - 1), d.t(k), d.Q), FilterStatus::kOk);
      ASSERT_EQ(pf.Predict(d.t(k - 1), d.t(k), d.Q), FilterStatus::kOk);
      Mat<N, N> C = Mat<N, N>::Zero();
      ASSERT_TRUE(ekf.PredictCrossCov(&C));
      rts.AddPredicted(ekf.mean(), ekf.cov(), C);
    }
    if (d.has_z[k]) {
      ASSERT_EQ(ekf.Update(d.z[k], d.R).status, FilterStatus::kOk);
      ASSERT_EQ(pf.Update(d.z[k], d.R).status, FilterStatus::kOk);
    }
    rts.AddFiltered(ekf.mean(), ekf.cov());
    ps.AddFiltered(pf.particles(), pf.weights());
  }
  ASSERT_TRUE(rts.Smooth(&why)) << why;
  constexpr int kTrajectories = 100;
  ASSERT_TRUE(ps.Smooth(kTrajectories, 77, &why)) << why;

  // z = (mean_ps - mean_rts) / sqrt(var_rts / M): the Monte Carlo standard
  // error of a mean of M independent draws from the smoothing distribution.
  int outside = 0, count = 0;
  double sum_z2 = 0.0, worst_z = 0.0, worst_var_ratio = 0.0;
  for (int k = 0; k < d.steps; ++k) {
    for (int i = 0; i < N; ++i) {
      const double se = std::sqrt(rts.cov(k)(i, i) / kTrajectories);
      const double z = (ps.mean(k)(i) - rts.mean(k)(i)) / se;
      outside += std::abs(z) > 3.0;
      sum_z2 += z * z;
      ++count;
      worst_z = std::max(worst_z, std::abs(z));
      worst_var_ratio =
          std::max(worst_var_ratio, std::abs(std::log(ps.var(k)(i) / rts.cov(k)(i, i))));
    }
  }
  std::printf(
      "  FFBSi (10^4 particles, %d trajectories) vs RTS over %d means: %d beyond 3 SE, "
      "RMS z %.2f, largest |z| %.2f, largest |log variance ratio| %.2f\n",
      kTrajectories, count, outside, std::sqrt(sum_z2 / count), worst_z, worst_var_ratio);
  EXPECT_LE(outside, count / 20);             // ~0.3 % expected; a wrong smoother is far off
  EXPECT_LT(std::sqrt(sum_z2 / count), 1.5);  // 1 for independent trajectories
  // Sample variances of 100 draws: relative sd sqrt(2/99) = 0.14; 0.6 is > 4 sd.
  EXPECT_LT(worst_var_ratio, 0.6);
}

}  // namespace
}  // namespace estlab
