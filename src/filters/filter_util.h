// Small numerical pieces shared by the filters: symmetrisation, the Kalman
// gain by a Cholesky solve, the Joseph-form covariance update, the Gaussian
// log-likelihood from a Cholesky factor, a square root of a positive
// semidefinite covariance, and weighted (circular where needed) moments of a
// point set.
//
// Usage:
//   Mat<1, 1> S;
//   Eigen::LLT<Mat<1, 1>> llt;
//   Mat<2, 1> K;
//   if (!KalmanGain(H, P, R, &S, &llt, &K)) return failure;   // S not PD
//   double nis;
//   const double loglik = GaussianLogLikelihood(llt, nu, &nis);
//   P = JosephUpdate(P, K, H, R);
//
// All functions work on fixed-size Eigen types and allocate nothing.
#ifndef ESTLAB_FILTERS_FILTER_UTIL_H_
#define ESTLAB_FILTERS_FILTER_UTIL_H_

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "src/core/types.h"
#include "src/filters/filter.h"

namespace estlab {

inline constexpr double kLog2Pi = 1.83787706640934548356;  // log(2 pi)

// P <- (P + P^T) / 2.
template <int N>
void Symmetrize(Mat<N, N>* P) {
  *P = (0.5 * (*P + P->transpose())).eval();
}

// Cholesky factor of a small fixed-size symmetric matrix: *L lower triangular
// with L L^T = A, from the lower triangle of A (the column algorithm of
// Eigen's unblocked LLT, written out for compile-time N: Eigen's LLT of a
// 4 x 4 runs through its generic block code, ~5x the instructions). Returns
// false when a pivot is not > 0 (not numerically positive definite, or NaN).
template <int N>
bool SmallCholesky(const Mat<N, N>& A, Mat<N, N>* L) {
  Mat<N, N>& l = *L;
  l.setZero();
  for (int k = 0; k < N; ++k) {
    double d = A(k, k);
    for (int j = 0; j < k; ++j) d -= l(k, j) * l(k, j);
    if (!(d > 0.0)) return false;
    const double lkk = std::sqrt(d);
    l(k, k) = lkk;
    for (int i = k + 1; i < N; ++i) {
      double s = A(i, k);
      for (int j = 0; j < k; ++j) s -= l(i, j) * l(k, j);
      l(i, k) = s / lkk;
    }
  }
  return true;
}

// L^-1 b for lower-triangular L (forward substitution).
template <int M>
Vec<double, M> ForwardSubstitute(const Mat<M, M>& L, const Vec<double, M>& b) {
  Vec<double, M> y;
  for (int i = 0; i < M; ++i) {
    double s = b(i);
    for (int j = 0; j < i; ++j) s -= L(i, j) * y(j);
    y(i) = s / L(i, i);
  }
  return y;
}

// S^-1 B for S = L L^T, L lower triangular: forward then back substitution,
// column by column (Eigen's LLT::solve with several right-hand sides goes
// through its blocked triangular-matrix solver).
template <int M, int C>
Mat<M, C> CholeskySolve(const Mat<M, M>& L, const Mat<M, C>& B) {
  Mat<M, C> X;
  for (int c = 0; c < C; ++c) {
    const Vec<double, M> y = ForwardSubstitute<M>(L, B.col(c));
    for (int i = M - 1; i >= 0; --i) {  // L^T x = y
      double s = y(i);
      for (int j = i + 1; j < M; ++j) s -= L(j, i) * X(j, c);
      X(i, c) = s / L(i, i);
    }
  }
  return X;
}

// S = H P H^T + R,  K = P H^T S^-1, with K^T = S^-1 (H P) solved by Cholesky
// (S = L L^T); P is symmetric so (P H^T)^T = H P. Returns false (and leaves
// *K unset) when S is not numerically positive definite.
template <int N, int M>
bool KalmanGain(const Mat<M, N>& H, const Mat<N, N>& P, const Mat<M, M>& R, Mat<M, M>* S,
                Eigen::LLT<Mat<M, M>>* llt, Mat<N, M>* K) {
  const Mat<M, N> HP = H * P;
  S->noalias() = HP * H.transpose();
  *S += R;
  Symmetrize(S);
  llt->compute(*S);
  if (llt->info() != Eigen::Success) return false;
  const Mat<M, M> L = llt->matrixL();
  *K = CholeskySolve<M, N>(L, HP).transpose();
  return K->allFinite();
}

// Joseph form, valid for any gain K:  P+ = (I - K H) P (I - K H)^T + K R K^T,
// symmetrised.
template <int N, int M>
Mat<N, N> JosephUpdate(const Mat<N, N>& P, const Mat<N, M>& K, const Mat<M, N>& H,
                       const Mat<M, M>& R) {
  const Mat<N, N> IKH = Mat<N, N>::Identity() - K * H;
  Mat<N, N> Pp = IKH * P * IKH.transpose() + K * R * K.transpose();
  Symmetrize(&Pp);
  return Pp;
}

// log N(nu; 0, S) = -1/2 (log det S + nu^T S^-1 nu + M log 2 pi) with S = L L^T:
// log det S = 2 sum_i log L_ii and nu^T S^-1 nu = |L^-1 nu|^2. Writes
// nis = nu^T S^-1 nu when nis is not null.
template <int M>
double GaussianLogLikelihood(const Eigen::LLT<Mat<M, M>>& llt, const Vec<double, M>& nu,
                             double* nis) {
  const Mat<M, M> L = llt.matrixL();
  const Vec<double, M> whitened = ForwardSubstitute<M>(L, nu);  // e = L^-1 nu
  const double mahalanobis = whitened.squaredNorm();
  double log_det = 0.0;
  for (int i = 0; i < M; ++i) log_det += 2.0 * std::log(L(i, i));
  if (nis != nullptr) *nis = mahalanobis;
  return -0.5 * (log_det + mahalanobis + M * kLog2Pi);
}

// Fills the diagnostics of `result` from the innovation nu and the Cholesky
// factor of its covariance S.
template <int M>
void SetInnovation(const Vec<double, M>& nu, const Mat<M, M>& S, const Eigen::LLT<Mat<M, M>>& llt,
                   StepResult<M>* result) {
  result->innovation = nu;
  result->innovation_cov = S;
  result->log_likelihood = GaussianLogLikelihood(llt, nu, &result->nis);
}

// A factor L with L L^T = C for a symmetric positive SEMI-definite C (used to
// sample, so a zero or singular covariance is allowed): the Cholesky factor
// when C is positive definite, otherwise V sqrt(max(D, 0)) from the
// eigendecomposition C = V D V^T. Returns false (with a reason in *why) when C
// is not finite, not symmetric, or has an eigenvalue below -1e-12 max(1, |C|).
template <int N>
bool CovarianceSqrt(const Mat<N, N>& C, Mat<N, N>* L, std::string* why) {
  auto fail = [&](const std::string& w) {
    if (why != nullptr) *why = w;
    return false;
  };
  if (!C.allFinite()) return fail("covariance is not finite");
  const double scale = std::max(1.0, C.cwiseAbs().maxCoeff());
  if ((C - C.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale)
    return fail("covariance is not symmetric");
  const Eigen::LLT<Mat<N, N>> llt(C);
  if (llt.info() == Eigen::Success) {
    *L = llt.matrixL();
    return true;
  }
  const Eigen::SelfAdjointEigenSolver<Mat<N, N>> eig(C);
  if (eig.info() != Eigen::Success) return fail("eigendecomposition of the covariance failed");
  const double min_eig = eig.eigenvalues().minCoeff();
  if (min_eig < -1e-12 * scale)
    return fail("covariance is not positive semidefinite (smallest eigenvalue " +
                std::to_string(min_eig) + ")");
  *L = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  return true;
}

// Weighted mean of the columns of `points` with angle components averaged
// relative to the first point:  m = X_0 + sum_i w_i wrap(X_i - X_0)
// (wrap only where angle_flags is true). For non-angle components this is the
// plain weighted mean when sum_i w_i = 1, written in the centred form, which
// keeps the rounding error small when weights are large and of both signs
// (scaled unscented points with small alpha).
template <int D, std::size_t K, class Points, class Weights>
Vec<double, D> WeightedMean(const Points& points, const Weights& weights,
                            const std::array<bool, K>& angle_flags) {
  const Vec<double, D> ref = points.col(0);
  Vec<double, D> acc = Vec<double, D>::Zero();
  for (Eigen::Index i = 1; i < points.cols(); ++i)
    acc += weights(i) * WrapResidual<D>(points.col(i) - ref, angle_flags);
  return ref + acc;
}

// sum_i w_i wrap(A_i - a) wrap(B_i - b)^T.
template <int D, int E, std::size_t KA, std::size_t KB, class PointsA, class PointsB, class Weights>
Mat<D, E> WeightedCrossCov(const PointsA& a_points, const Vec<double, D>& a_mean,
                           const std::array<bool, KA>& a_angles, const PointsB& b_points,
                           const Vec<double, E>& b_mean, const std::array<bool, KB>& b_angles,
                           const Weights& weights) {
  Mat<D, E> C = Mat<D, E>::Zero();
  for (Eigen::Index i = 0; i < a_points.cols(); ++i) {
    const Vec<double, D> da = WrapResidual<D>(a_points.col(i) - a_mean, a_angles);
    const Vec<double, E> db = WrapResidual<E>(b_points.col(i) - b_mean, b_angles);
    C.noalias() += weights(i) * da * db.transpose();
  }
  return C;
}

// sum_i w_i wrap(A_i - a) wrap(A_i - a)^T: WeightedCrossCov of a point set
// with itself, each residual wrapped once.
template <int D, std::size_t K, class Points, class Weights>
Mat<D, D> WeightedCov(const Points& points, const Vec<double, D>& mean,
                      const std::array<bool, K>& angles, const Weights& weights) {
  Mat<D, D> C = Mat<D, D>::Zero();
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Vec<double, D> d = WrapResidual<D>(points.col(i) - mean, angles);
    C.noalias() += weights(i) * d * d.transpose();
  }
  return C;
}

// True when every entry of the mean and the covariance is finite.
template <int N>
bool BeliefFinite(const Vec<double, N>& x, const Mat<N, N>& P) {
  return x.allFinite() && P.allFinite();
}

// What every estlab filter keeps: the belief (x, P), the last error message,
// and whether a prior was given and was usable. Initialize() stores the prior
// and checks P0 (finite, symmetric, positive semidefinite); a bad P0 is
// reported as kFactorizationFailed by the next Predict/Update (Initialize
// itself returns nothing).
template <class Model, class Meas>
class FilterCommon : public Filter<Model, Meas> {
 public:
  using Base = Filter<Model, Meas>;
  using Base::kM;
  using Base::kN;
  using typename Base::Measurement;
  using typename Base::MeasurementCov;
  using typename Base::State;
  using typename Base::StateCov;

  const State& mean() const override { return x_; }
  const StateCov& cov() const override { return P_; }
  std::string last_error() const override { return error_; }

 protected:
  void SetPrior(const State& x, const StateCov& P) {
    x_ = x;
    P_ = P;
    error_.clear();
    prior_error_.clear();
    initialized_ = true;
    StateCov L;
    std::string why;
    if (!x.allFinite()) {
      prior_error_ = "initial mean x0 is not finite";
    } else if (!CovarianceSqrt<kN>(P, &L, &why)) {
      prior_error_ = "initial covariance P0: " + why;
    }
  }
  // kOk when Predict/Update may proceed; otherwise records why not.
  FilterStatus CheckReady() {
    if (!initialized_) return Fail(FilterStatus::kNonFinite, "filter used before Initialize");
    if (!prior_error_.empty()) return Fail(FilterStatus::kFactorizationFailed, prior_error_);
    return FilterStatus::kOk;
  }
  FilterStatus Fail(FilterStatus status, const std::string& what) {
    error_ = what;
    return status;
  }
  StepResult<kM> FailResult(FilterStatus status, const std::string& what) {
    StepResult<kM> result;
    result.status = Fail(status, what);
    result.message = what;
    return result;
  }

  State x_ = State::Zero();
  StateCov P_ = StateCov::Identity();
  std::string error_;

 private:
  std::string prior_error_;
  bool initialized_ = false;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_FILTER_UTIL_H_
