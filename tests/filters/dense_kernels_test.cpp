// The dense kernels compiled once in the library (symmetric_eigen.h,
// matrix_exponential.h): bit for bit what Eigen's fixed-size solver and
// exp give when instantiated in place (the test instantiates them itself,
// as the filters did before), and, beyond the fixed sizes, the defining
// identities A V = V diag(values) and exp(A) exp(-A) = I. The innovation
// covariance's written-out Cholesky (filter_util.h) against Eigen's LLT.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "src/filters/filter_util.h"
#include "src/filters/matrix_exponential.h"
#include "src/filters/symmetric_eigen.h"

namespace estlab {
namespace {

template <int N>
bool SameBits(const Mat<N, N>& a, const Mat<N, N>& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * N * N) == 0;
}

// Symmetric matrices of every kind the filters meet: positive definite,
// indefinite (an adaptive R that needs its floor), rank-deficient (a
// white-acceleration Q), and nearly diagonal.
template <int N>
Mat<N, N> Symmetric(std::mt19937* rng, int kind) {
  std::normal_distribution<double> normal;
  Mat<N, N> B;
  for (int i = 0; i < N * N; ++i) B.data()[i] = normal(*rng);
  Mat<N, N> A = B * B.transpose();
  if (kind == 1) A(0, 0) -= 3.0;
  if (kind == 2) A = B.col(0) * B.col(0).transpose();
  if (kind == 3) A = Mat<N, N>::Identity() + 1e-9 * (B + B.transpose());
  return A;
}

template <int N>
void CheckEigenBits(std::mt19937* rng) {
  for (int trial = 0; trial < 200; ++trial) {
    const Mat<N, N> A = Symmetric<N>(rng, trial % 4);
    const Eigen::SelfAdjointEigenSolver<Mat<N, N>> in_place(A);
    Vec<double, N> values;
    Mat<N, N> vectors;
    ASSERT_TRUE(SymmetricEigen<N>(A, &values, &vectors));
    ASSERT_EQ(std::memcmp(values.data(), in_place.eigenvalues().data(), sizeof(double) * N), 0)
        << "N = " << N << ", trial " << trial;
    const Mat<N, N> expected = in_place.eigenvectors();
    ASSERT_TRUE(SameBits<N>(vectors, expected)) << "N = " << N << ", trial " << trial;
  }
}

template <int N>
void CheckExpBits(std::mt19937* rng) {
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 100; ++trial) {
    Mat<N, N> A;
    const double scale = trial % 2 ? 0.05 : 3.0;  // one Pade branch, then scaling and squaring
    for (int i = 0; i < N * N; ++i) A.data()[i] = scale * normal(*rng);
    const Mat<N, N> in_place = A.exp();
    ASSERT_TRUE(SameBits<N>(MatrixExponential<N>(A), in_place)) << "N = " << N << ", " << trial;
  }
}

TEST(DenseKernels, FixedSizesGiveTheInPlaceBits) {
  std::mt19937 rng(38);
  CheckEigenBits<1>(&rng);
  CheckEigenBits<2>(&rng);
  CheckEigenBits<3>(&rng);
  CheckEigenBits<4>(&rng);
  CheckEigenBits<6>(&rng);
  CheckEigenBits<16>(&rng);
  CheckExpBits<1>(&rng);
  CheckExpBits<3>(&rng);
  CheckExpBits<4>(&rng);  // the KF of a 2-state, 1-input model with a ramp: 2 + 2 + 1
  CheckExpBits<7>(&rng);
  CheckExpBits<24>(&rng);
}

// InnovationCholesky against Eigen's LLT in place: the same success, and on
// success the same bits of L, for positive definite, indefinite, singular,
// nearly singular and NaN matrices.
template <int M>
void CheckCholeskyBits(std::mt19937* rng) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  int failures = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Mat<M, M> A = Symmetric<M>(rng, trial % 4);
    if (trial % 50 == 7) A(M - 1, 0) = A(0, M - 1) = nan;
    if (trial % 50 == 9) A(M - 1, M - 1) = nan;
    if (trial % 50 == 11) A.setZero();
    const Eigen::LLT<Mat<M, M>> llt(A);
    Mat<M, M> L = Mat<M, M>::Constant(5.0);
    const bool ok = InnovationCholesky<M>(A, &L);
    ASSERT_EQ(ok, llt.info() == Eigen::Success) << "M = " << M << ", trial " << trial;
    failures += !ok;
    if (!ok) continue;
    const Mat<M, M> expected = llt.matrixL();
    ASSERT_TRUE(SameBits<M>(L, expected)) << "M = " << M << ", trial " << trial << "\n" << A;
  }
  EXPECT_GT(failures, 100);  // the indefinite and zero matrices were refused
}

TEST(DenseKernels, InnovationCholeskyGivesEigensLltBits) {
  std::mt19937 rng(39);
  CheckCholeskyBits<1>(&rng);
  CheckCholeskyBits<2>(&rng);
  CheckCholeskyBits<3>(&rng);  // Eigen's own, through the same function
}

// Symmetrize in place gives the bits of (P + P^T) / 2 through a temporary.
template <int N>
void CheckSymmetrizeBits(std::mt19937* rng) {
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 500; ++trial) {
    Mat<N, N> P;
    for (int i = 0; i < N * N; ++i) P.data()[i] = std::ldexp(normal(*rng), trial % 40 - 20);
    const Mat<N, N> expected = (0.5 * (P + P.transpose())).eval();
    Symmetrize<N>(&P);
    ASSERT_TRUE(SameBits<N>(P, expected)) << "N = " << N << ", trial " << trial;
  }
}

TEST(DenseKernels, SymmetrizeInPlaceGivesTheTemporarysBits) {
  std::mt19937 rng(40);
  CheckSymmetrizeBits<1>(&rng);
  CheckSymmetrizeBits<2>(&rng);
  CheckSymmetrizeBits<4>(&rng);
  CheckSymmetrizeBits<7>(&rng);
}

TEST(DenseKernels, LargerSizesSatisfyTheDefiningIdentities) {
  constexpr int n = kMaxFixedEigenSize + 3;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd B(n, n);
  for (int i = 0; i < n * n; ++i) B.data()[i] = normal(rng);
  const Eigen::MatrixXd A = B * B.transpose() - 2.0 * Eigen::MatrixXd::Identity(n, n);
  Eigen::VectorXd values(n);
  Eigen::MatrixXd vectors(n, n);
  ASSERT_TRUE(SymmetricEigen(A.data(), n, values.data(), vectors.data()));
  for (int i = 1; i < n; ++i) EXPECT_LE(values(i - 1), values(i));  // ascending
  EXPECT_LT((A * vectors - vectors * values.asDiagonal()).norm(), 1e-11 * A.norm());
  EXPECT_LT((vectors.transpose() * vectors - Eigen::MatrixXd::Identity(n, n)).norm(), 1e-12);

  const int m = kMaxFixedExpSize + 2;
  Eigen::MatrixXd C(m, m);
  for (int i = 0; i < m * m; ++i) C.data()[i] = 0.3 * normal(rng);
  Eigen::MatrixXd e(m, m), e_neg(m, m);
  const Eigen::MatrixXd minus_c = -C;
  MatrixExponential(C.data(), m, e.data());
  MatrixExponential(minus_c.data(), m, e_neg.data());
  EXPECT_LT((e * e_neg - Eigen::MatrixXd::Identity(m, m)).norm(), 1e-12);
  // and the Taylor series to 40 terms agrees
  Eigen::MatrixXd term = Eigen::MatrixXd::Identity(m, m), series = term;
  for (int k = 1; k <= 40; ++k) {
    term = term * C / double(k);
    series += term;
  }
  EXPECT_LT((e - series).norm(), 1e-12 * series.norm());
}

}  // namespace
}  // namespace estlab
