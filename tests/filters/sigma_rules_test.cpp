// Point rules alone: exactness degrees against closed-form Gaussian moments,
// and the Gauss-Hermite nodes and weights.
#include "src/filters/sigma_rules.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <vector>

#include "src/core/types.h"

namespace estlab {
namespace {

// E[xi^a] for xi ~ N(0, 1): (a - 1)!! for even a, 0 for odd a.
double StdNormalMoment(int a) {
  if (a % 2 == 1) return 0.0;
  double m = 1.0;
  for (int k = a - 1; k > 1; k -= 2) m *= k;
  return m;
}

// sum_i w_i prod_j xi_ij^{a_j} over the unit points.
double RuleMoment(const UnitSigmaPoints& u, const std::vector<int>& powers) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < u.points.cols(); ++i) {
    double term = u.mean_weights(i);
    for (size_t j = 0; j < powers.size(); ++j) term *= std::pow(u.points(j, i), powers[j]);
    sum += term;
  }
  return sum;
}

// Largest error over all monomials of total degree <= max_degree in n
// dimensions (E[prod xi_j^a_j] = prod_j E[xi^a_j] for N(0, I)).
double MaxMonomialError(const UnitSigmaPoints& u, int n, int max_degree) {
  double worst = 0.0;
  std::vector<int> powers(n, 0);
  // Enumerate all exponent vectors with entries in [0, max_degree].
  const int base = max_degree + 1;
  long total = 1;
  for (int j = 0; j < n; ++j) total *= base;
  for (long code = 0; code < total; ++code) {
    long rest = code;
    int degree = 0;
    double exact = 1.0;
    for (int j = 0; j < n; ++j) {
      powers[j] = int(rest % base);
      rest /= base;
      degree += powers[j];
      exact *= StdNormalMoment(powers[j]);
    }
    if (degree > max_degree) continue;
    worst = std::max(worst, std::abs(RuleMoment(u, powers) - exact) / std::max(1.0, exact));
  }
  return worst;
}

SigmaPointOptions Rule(SigmaRule rule, double alpha = 1.0, double kappa = 0.0, int order = 3) {
  SigmaPointOptions o;
  o.rule = rule;
  o.alpha = alpha;
  o.kappa = kappa;
  o.gh_order = order;
  return o;
}

TEST(SigmaRulesTest, UnscentedTransformOfAQuadraticHasTheExactMean) {
  // y = x^T A x + b^T x, x ~ N(m, P):  E[y] = tr(A P) + m^T A m + b^T m.
  const Eigen::Vector3d m(0.5, -1.2, 2.0);
  Eigen::Matrix3d P;
  P << 2.0, 0.3, -0.4, 0.3, 1.0, 0.2, -0.4, 0.2, 0.5;
  Eigen::Matrix3d A;
  A << 1.0, 0.5, -2.0, 0.1, 3.0, 0.7, 0.0, -1.0, 0.4;
  const Eigen::Vector3d b(1.0, -2.0, 0.5);
  const double exact = (A * P).trace() + m.dot(A * m) + b.dot(m);
  const Eigen::Matrix3d L = P.llt().matrixL();
  for (double alpha : {1e-3, 0.5, 1.0, 2.0}) {
    for (double kappa : {0.0, 1.0, -1.0}) {  // -1 = 3 - n - 1, still n + kappa > 0
      const UnitSigmaPoints u = MakeUnitSigmaPoints(3, Rule(SigmaRule::kUnscented, alpha, kappa));
      ASSERT_EQ(u.points.cols(), 7);
      EXPECT_NEAR(u.mean_weights.sum(), 1.0, 1e-9);
      double mean = 0.0;
      for (int i = 0; i < 7; ++i) {
        const Eigen::Vector3d x = m + L * u.points.col(i);
        mean += u.mean_weights(i) * (x.dot(A * x) + b.dot(x));
      }
      // Weights of size 1/alpha^2 cancel: relative rounding ~ eps / alpha^2.
      const double tol = alpha < 0.01 ? 1e-8 : 1e-12;
      EXPECT_NEAR(mean, exact, tol * std::abs(exact)) << "alpha " << alpha << " kappa " << kappa;
      // The covariance of x itself is exact too: sum Wc (X - m)(X - m)^T = P.
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 7; ++i) {
        const Eigen::Vector3d d = L * u.points.col(i);
        cov += u.cov_weights(i) * d * d.transpose();
      }
      EXPECT_LT((cov - P).cwiseAbs().maxCoeff(), 1e-12 + (alpha < 0.01 ? 1e-9 : 0.0));
    }
  }
  // A quartic is not exact (the test can fail): E[x1^4] = 3 P11^2 for m = 0.
  const UnitSigmaPoints u = MakeUnitSigmaPoints(3, Rule(SigmaRule::kUnscented, 0.5));
  double quartic = 0.0;
  for (int i = 0; i < 7; ++i) quartic += u.mean_weights(i) * std::pow((L * u.points.col(i))(0), 4);
  EXPECT_GT(std::abs(quartic - 3 * P(0, 0) * P(0, 0)), 1.0);
}

TEST(SigmaRulesTest, CubatureIsExactToDegreeThree) {
  for (int n : {2, 3, 5}) {
    const UnitSigmaPoints u = MakeUnitSigmaPoints(n, Rule(SigmaRule::kCubature));
    ASSERT_EQ(u.points.cols(), 2 * n);
    EXPECT_LT(MaxMonomialError(u, n, 3), 1e-13) << "n " << n;
    // Degree 4 fails: E[xi_1^2 xi_2^2] = 1, the rule gives 0.
    std::vector<int> powers(n, 0);
    powers[0] = powers[1] = 2;
    EXPECT_NEAR(RuleMoment(u, powers), 0.0, 1e-15);
  }
}

TEST(SigmaRulesTest, GaussHermiteOfOrderPIsExactToDegree2PMinus1) {
  for (int p : {3, 5}) {
    const int n = 2;
    const UnitSigmaPoints u = MakeUnitSigmaPoints(n, Rule(SigmaRule::kGaussHermite, 1, 0, p));
    ASSERT_EQ(u.points.cols(), p * p);
    const double err = MaxMonomialError(u, n, 2 * p - 1);
    std::printf("[ measured ] gauss-hermite p=%d: max error over degree <= %d: %.1e\n", p,
                2 * p - 1, err);
    EXPECT_LT(err, 1e-13) << "order " << p;
    // Degree 2p fails: E[xi^6] = 15, GH3 gives 9.
    if (p == 3) {
      EXPECT_NEAR(RuleMoment(u, {6, 0}), 9.0, 1e-12);
    }
  }
}

TEST(SigmaRulesTest, GaussHermiteOrderThreeMatchesCorrelatedGaussianMoments) {
  // x = m + L xi ~ N(m, P), closed forms (Isserlis):
  //   E[x1^2 x2] = m1^2 m2 + P11 m2 + 2 P12 m1
  //   E[(x1-m1)^2 (x2-m2)^2] = P11 P22 + 2 P12^2,  E[(x1-m1)^3 (x2-m2)] = 3 P11 P12
  //   E[(x1-m1)^4] = 3 P11^2,  degree 5 central moments vanish.
  const Eigen::Vector2d m(0.7, -0.4);
  Eigen::Matrix2d P;
  P << 1.5, 0.6, 0.6, 0.8;
  const Eigen::Matrix2d L = P.llt().matrixL();
  const UnitSigmaPoints u = MakeUnitSigmaPoints(2, Rule(SigmaRule::kGaussHermite, 1, 0, 3));
  double e_x1x1x2 = 0, e22 = 0, e31 = 0, e40 = 0, e32 = 0;
  for (Eigen::Index i = 0; i < u.points.cols(); ++i) {
    const Eigen::Vector2d d = L * u.points.col(i);
    const Eigen::Vector2d x = m + d;
    const double w = u.mean_weights(i);
    e_x1x1x2 += w * x(0) * x(0) * x(1);
    e22 += w * d(0) * d(0) * d(1) * d(1);
    e31 += w * d(0) * d(0) * d(0) * d(1);
    e40 += w * std::pow(d(0), 4);
    e32 += w * std::pow(d(0), 3) * d(1) * d(1);
  }
  EXPECT_NEAR(e_x1x1x2, m(0) * m(0) * m(1) + P(0, 0) * m(1) + 2 * P(0, 1) * m(0), 1e-13);
  EXPECT_NEAR(e22, P(0, 0) * P(1, 1) + 2 * P(0, 1) * P(0, 1), 1e-13);
  EXPECT_NEAR(e31, 3 * P(0, 0) * P(0, 1), 1e-13);
  EXPECT_NEAR(e40, 3 * P(0, 0) * P(0, 0), 1e-13);
  EXPECT_NEAR(e32, 0.0, 1e-13);
}

TEST(SigmaRulesTest, GaussHermiteNodesAndWeights) {
  Eigen::VectorXd x, w;
  GaussHermite1D(3, &x, &w);  // {-sqrt 3, 0, sqrt 3}, {1/6, 2/3, 1/6}
  EXPECT_NEAR(x(0), -std::sqrt(3.0), 1e-14);
  EXPECT_EQ(x(1), 0.0);
  EXPECT_NEAR(x(2), std::sqrt(3.0), 1e-14);
  EXPECT_NEAR(w(0), 1.0 / 6, 1e-14);
  EXPECT_NEAR(w(1), 2.0 / 3, 1e-14);
  EXPECT_NEAR(w(2), 1.0 / 6, 1e-14);
  GaussHermite1D(2, &x, &w);  // {-1, 1}, {1/2, 1/2}
  EXPECT_NEAR(x(0), -1.0, 1e-14);
  EXPECT_NEAR(w(1), 0.5, 1e-14);
  GaussHermite1D(4, &x, &w);  // nodes +-sqrt(3 -+ sqrt 6)
  EXPECT_NEAR(x(3), std::sqrt(3 + std::sqrt(6.0)), 1e-13);
  EXPECT_NEAR(x(2), std::sqrt(3 - std::sqrt(6.0)), 1e-13);
  EXPECT_NEAR(w(3), 1.0 / (4 * (3 + std::sqrt(6.0))), 1e-13);
  GaussHermite1D(1, &x, &w);
  EXPECT_EQ(x(0), 0.0);
  EXPECT_EQ(w(0), 1.0);
}

TEST(SigmaRulesTest, PointCountsAndInvalidOptions) {
  EXPECT_EQ(NumSigmaPoints(6, Rule(SigmaRule::kGaussHermite, 1, 0, 3)), 729);
  EXPECT_EQ(MakeUnitSigmaPoints(6, Rule(SigmaRule::kGaussHermite, 1, 0, 3)).points.cols(), 729);
  EXPECT_EQ(NumSigmaPoints(4, Rule(SigmaRule::kUnscented)), 9);
  EXPECT_EQ(NumSigmaPoints(4, Rule(SigmaRule::kCubature)), 8);
  EXPECT_THROW(MakeUnitSigmaPoints(6, Rule(SigmaRule::kGaussHermite, 1, 0, 20)), InputError);
  EXPECT_THROW(MakeUnitSigmaPoints(2, Rule(SigmaRule::kUnscented, 1, -2.0)), InputError);
  EXPECT_THROW(MakeUnitSigmaPoints(0, Rule(SigmaRule::kCubature)), InputError);
  std::string error;
  SigmaPointOptions o;
  o.jitter = -1;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("jitter"), std::string::npos);
  o = SigmaPointOptions{};
  o.gh_order = 0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_EQ(ParseSigmaRule("ckf"), SigmaRule::kCubature);
  EXPECT_EQ(ParseSigmaRule("gauss-hermite"), SigmaRule::kGaussHermite);
  EXPECT_THROW(ParseSigmaRule("sphere"), InputError);
  EXPECT_STREQ(SigmaRuleName(SigmaRule::kUnscented), "unscented");
}

}  // namespace
}  // namespace estlab
