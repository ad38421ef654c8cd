// Small numerical pieces shared by the filters, written once for any scalar
// (double, ceres::Jet): symmetrisation, small Cholesky factorisations and
// solves, the Kalman gain, the Joseph-form covariance update, the whitened
// innovation and its Gaussian log-likelihood, weighted moments of a point set
// (no wrapping inside a set), and a square root of a positive semidefinite
// covariance.
//
// Usage (H, nu and R masked where z is missing, missing.h):
//   const MissingMask<1> missing(z);
//   Mat<1, 1> S, L;
//   Mat<2, 1> K;
//   if (!KalmanGain<2, 1>(H, P, R, missing, &S, &L, &K)) return failure;  // S not PD
//   StepResult<1> r;
//   SetInnovation<1>(nu, S, L, missing, &r);  // nis, log N(nu; 0, S)
//   P = JosephUpdate<2, 1>(P, K, H, R, missing);
//
// All functions work on fixed-size Eigen types and allocate nothing.
#ifndef ESTLAB_FILTERS_FILTER_UTIL_H_
#define ESTLAB_FILTERS_FILTER_UTIL_H_

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <type_traits>

#include "src/core/types.h"
#include "src/filters/filter.h"
#include "src/filters/missing.h"
#include "src/filters/symmetric_eigen.h"

namespace estlab {

inline constexpr double kLog2Pi = 1.83787706640934548356;  // log(2 pi)

// Every function below is written once for any scalar T: double when a filter
// runs, ceres::Jet when the tuner differentiates the likelihood
// (adaptive/likelihood.h). The double path is the one the benchmarks measure.

// P <- (P + P^T) / 2, in place: entry (i, j) and (j, i) both become
// 0.5 (P_ij + P_ji) (the same number either way round), the diagonal
// 0.5 (P_ii + P_ii); the bits of the expression with a temporary, without it.
template <int N, class T = double>
void Symmetrize(MatT<T, N, N>* P) {
  MatT<T, N, N>& p = *P;
  for (int j = 0; j < N; ++j) {
    p(j, j) = 0.5 * (p(j, j) + p(j, j));
    for (int i = j + 1; i < N; ++i) p(i, j) = p(j, i) = 0.5 * (p(i, j) + p(j, i));
  }
}

// Cholesky factor of a small fixed-size symmetric matrix: *L lower triangular
// with L L^T = A, from the lower triangle of A (the column algorithm of
// Eigen's unblocked LLT, written out for compile-time N: Eigen's LLT of a
// 4 x 4 runs through its generic block code, ~5x the instructions). Returns
// false when a pivot is not > 0 (not numerically positive definite, or NaN).
template <int N, class T = double>
bool SmallCholesky(const MatT<T, N, N>& A, MatT<T, N, N>* L) {
  using std::sqrt;
  MatT<T, N, N>& l = *L;
  l.setZero();
  for (int k = 0; k < N; ++k) {
    T d = A(k, k);
    for (int j = 0; j < k; ++j) d -= l(k, j) * l(k, j);
    if (!(d > 0.0)) return false;
    const T lkk = sqrt(d);
    l(k, k) = lkk;
    for (int i = k + 1; i < N; ++i) {
      T s = A(i, k);
      for (int j = 0; j < k; ++j) s -= l(i, j) * l(k, j);
      l(i, k) = s / lkk;
    }
  }
  return true;
}

// The Cholesky factor of Eigen's LLT, *L = llt.matrixL(), true when
// llt.info() == Success: for double and M <= 2 written out in the order of
// Eigen's unblocked LLT (l00 = sqrt(a00), l10 = a10 / l00,
// l11 = sqrt(a11 - l10 l10): the same bits), failing as Eigen does only on a
// pivot <= 0 (a NaN pivot passes, and the caller's finiteness check reports
// it). Eigen's LLT of a 2 x 2 also computes an l1 norm and runs its generic
// block code, about 5x the instructions of the innovation covariance's
// factorisation (issue 39). Larger sizes and Jets go through Eigen::LLT.
template <int M, class T = double>
bool InnovationCholesky(const MatT<T, M, M>& A, MatT<T, M, M>* L) {
  if constexpr (std::is_same_v<T, double> && M <= 2) {
    using std::sqrt;
    MatT<T, M, M>& l = *L;
    if (A(0, 0) <= 0.0) return false;
    l(0, 0) = sqrt(A(0, 0));
    if constexpr (M == 2) {
      l(0, 1) = 0.0;
      l(1, 0) = A(1, 0) / l(0, 0);
      const double d = A(1, 1) - l(1, 0) * l(1, 0);
      if (d <= 0.0) return false;
      l(1, 1) = sqrt(d);
    }
    return true;
  } else {
    const Eigen::LLT<MatT<T, M, M>> llt(A);
    if (llt.info() != Eigen::Success) return false;
    *L = llt.matrixL();
    return true;
  }
}

// L^-1 b for lower-triangular L (forward substitution).
template <int M, class T = double>
Vec<T, M> ForwardSubstitute(const MatT<T, M, M>& L, const Vec<T, M>& b) {
  Vec<T, M> y;
  for (int i = 0; i < M; ++i) {
    T s = b(i);
    for (int j = 0; j < i; ++j) s -= L(i, j) * y(j);
    y(i) = s / L(i, i);
  }
  return y;
}

// S^-1 B for S = L L^T, L lower triangular: forward then back substitution,
// column by column (Eigen's LLT::solve with several right-hand sides goes
// through its blocked triangular-matrix solver).
template <int M, int C, class T = double>
MatT<T, M, C> CholeskySolve(const MatT<T, M, M>& L, const MatT<T, M, C>& B) {
  MatT<T, M, C> X;
  for (int c = 0; c < C; ++c) {
    const Vec<T, M> y = ForwardSubstitute<M, T>(L, B.col(c));
    for (int i = M - 1; i >= 0; --i) {  // L^T x = y
      T s = y(i);
      for (int j = i + 1; j < M; ++j) s -= L(j, i) * X(j, c);
      X(i, c) = s / L(i, i);
    }
  }
  return X;
}

// True when every entry is finite (for any scalar: its value part).
template <class Derived>
bool AllFiniteT(const Eigen::MatrixBase<Derived>& a) {
  using T = typename Derived::Scalar;
  if constexpr (std::is_same_v<T, double>) {
    return a.allFinite();
  } else {
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      for (Eigen::Index j = 0; j < a.cols(); ++j)
        if (!std::isfinite(ScalarPart(a(i, j)))) return false;
    return true;
  }
}

// S = H P H^T + R,  K = P H^T S^-1, with K^T = S^-1 (H P) solved by Cholesky
// (S = L L^T); P is symmetric so (P H^T)^T = H P. Writes S and its factor L.
// Returns false (and leaves *K unset) when S is not numerically positive
// definite.
template <int N, int M, class T = double>
bool KalmanGain(const MatT<T, M, N>& H, const MatT<T, N, N>& P, const MatT<T, M, M>& R,
                MatT<T, M, M>* S, MatT<T, M, M>* L, MatT<T, N, M>* K) {
  const MatT<T, M, N> HP = H * P;
  S->noalias() = HP * H.transpose();
  *S += R;
  Symmetrize<M, T>(S);
  if (!InnovationCholesky<M, T>(*S, L)) return false;
  *K = CholeskySolve<M, N, T>(*L, HP).transpose();
  return AllFiniteT(*K);
}

// The same with the observed components of z only: H's and R's missing rows
// masked (missing.h). With one component j observed out of M > 1 (one
// sensor of several reported), the update at size 1, without the masked
// rows' work:
//   s = h_j P h_j^T + R_jj,  l = sqrt(s),  K_j = ((P h_j^T) / l) / l,
// and S, L, K in the masked form (S_ii = L_ii = 1 and K's column i zero for
// a missing i): the numbers of the size-M solve, to rounding.
template <int N, int M, class T = double>
bool KalmanGain(const MatT<T, M, N>& H, const MatT<T, N, N>& P, const MatT<T, M, M>& R,
                const MissingMask<M>& missing, MatT<T, M, M>* S, MatT<T, M, M>* L,
                MatT<T, N, M>* K) {
  if constexpr (M > 1) {
    if (missing.Observed() == 1) {
      using std::sqrt;
      const int j = missing.FirstObserved();
      const Eigen::Matrix<T, 1, N> hp = H.row(j) * P;
      const T s = hp.dot(H.row(j)) + R(j, j);
      if (!(ScalarPart(s) > 0.0)) return false;
      const T l = sqrt(s);
      S->setIdentity();
      (*S)(j, j) = s;
      L->setIdentity();
      (*L)(j, j) = l;
      K->setZero();
      K->col(j) = (hp.transpose() / l) / l;
      return AllFiniteT(*K);
    }
  }
  return KalmanGain<N, M, T>(H, P, R, S, L, K);
}

// Joseph form, valid for any gain K:  P+ = (I - K H) P (I - K H)^T + K R K^T,
// symmetrised.
template <int N, int M, class T = double>
MatT<T, N, N> JosephUpdate(const MatT<T, N, N>& P, const MatT<T, N, M>& K, const MatT<T, M, N>& H,
                           const MatT<T, M, M>& R) {
  const MatT<T, N, N> IKH = MatT<T, N, N>::Identity() - K * H;
  MatT<T, N, N> Pp = IKH * P * IKH.transpose() + K * R * K.transpose();
  Symmetrize<N, T>(&Pp);
  return Pp;
}

// The same with the observed components of z only (KalmanGain's masked
// form); with one component j observed, at size 1: K H = k_j h_j and
// K R K^T = k_j R_jj k_j^T (the masked rows add nothing).
template <int N, int M, class T = double>
MatT<T, N, N> JosephUpdate(const MatT<T, N, N>& P, const MatT<T, N, M>& K, const MatT<T, M, N>& H,
                           const MatT<T, M, M>& R, const MissingMask<M>& missing) {
  if constexpr (M > 1) {
    if (missing.Observed() == 1) {
      const int j = missing.FirstObserved();
      const MatT<T, N, N> IKH = MatT<T, N, N>::Identity() - K.col(j) * H.row(j);
      MatT<T, N, N> Pp = IKH * P * IKH.transpose() + (K.col(j) * R(j, j)) * K.col(j).transpose();
      Symmetrize<N, T>(&Pp);
      return Pp;
    }
  }
  return JosephUpdate<N, M, T>(P, K, H, R);
}

// The innovation of one update in whitened form: with S = L L^T,
// e = L^-1 nu and log det S = 2 sum_i log L_ii. The likelihood term of the
// step is log N(nu; 0, S) = -1/2 (log det S + e^T e + M log 2 pi); the
// tuner's least-squares form uses e and log det S directly.
template <int M, class T = double>
void Whiten(const MatT<T, M, M>& L, const Vec<T, M>& nu, Vec<T, M>* whitened, T* log_det) {
  using std::log;
  *whitened = ForwardSubstitute<M, T>(L, nu);
  T sum(0.0);
  for (int i = 0; i < M; ++i) sum += 2.0 * log(L(i, i));
  *log_det = sum;
}
// `observed`: the components of z the update used (missing.h: a masked
// component adds 0 to the whitened norm and to log det S, and nothing to
// the constant).
template <int M, class T = double>
T GaussianLogLikelihood(const Vec<T, M>& whitened, const T& log_det, int observed = M) {
  return -0.5 * (log_det + whitened.squaredNorm() + observed * kLog2Pi);
}

// Fills the diagnostics of `result` from the innovation nu, its covariance S
// and the Cholesky factor L of S (masked where components of z are missing,
// missing.h): nis = nu^T S^-1 nu = |L^-1 nu|^2 and log_likelihood =
// log N(nu; 0, S) over the observed components; the missing ones are NaN in
// the reported innovation and S.
template <int M>
void SetInnovation(const Vec<double, M>& nu, const Mat<M, M>& S, const Mat<M, M>& L,
                   const MissingMask<M>& missing, StepResult<M>* result) {
  Vec<double, M> whitened;
  double log_det;
  Whiten<M>(L, nu, &whitened, &log_det);
  result->innovation = nu;
  result->innovation_cov = S;
  result->nis = whitened.squaredNorm();
  result->log_likelihood = GaussianLogLikelihood<M>(whitened, log_det, missing.Observed());
  result->observed = missing.Observed();
  if (missing.Any()) missing.MarkReported(&result->innovation, &result->innovation_cov);
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
  Vec<double, N> values;
  Mat<N, N> vectors;
  if (!SymmetricEigen<N>(C, &values, &vectors))
    return fail("eigendecomposition of the covariance failed");
  const double min_eig = values.minCoeff();
  if (min_eig < -1e-12 * scale)
    return fail("covariance is not positive semidefinite (smallest eigenvalue " +
                std::to_string(min_eig) + ")");
  *L = vectors * values.cwiseMax(0.0).cwiseSqrt().asDiagonal();
  return true;
}

// Moments of a weighted point set (sigma points), for any scalar. They are
// plain weighted sums: NO angle wrapping inside a point set. A difference
// X_i - X_j between points drawn from one Gaussian and propagated together is
// continuous in the points; wrapping it to (-pi, pi] is only right when the
// spread is far below pi and breaks wide priors (issue "One filter core",
// defect 6). Angles are wrapped only where a value really jumps: innovations
// against data, errors against truth.
//
// Weighted mean, centred on the reference point X_0 (the mean the points were
// drawn from, propagated, for the unscented rule):
//   m = X_0 + sum_{i >= 1} w_i (X_i - X_0)
// which equals sum_i w_i X_i when sum_i w_i = 1 and keeps the rounding error
// small when the weights are large and of both signs (scaled unscented
// points with small alpha).
template <int D, class Points, class Weights>
Vec<typename Points::Scalar, D> WeightedMean(const Points& points, const Weights& weights) {
  using T = typename Points::Scalar;
  const Vec<T, D> ref = points.col(0);
  Vec<T, D> acc = Vec<T, D>::Zero();
  for (Eigen::Index i = 1; i < points.cols(); ++i) acc += weights(i) * (points.col(i) - ref);
  return ref + acc;
}

// C = sum_i w_i (A_i - a)(B_i - b)^T.
template <int D, int E, class PointsA, class PointsB, class Weights>
MatT<typename PointsA::Scalar, D, E> WeightedCrossCov(
    const PointsA& a_points, const Vec<typename PointsA::Scalar, D>& a_mean,
    const PointsB& b_points, const Vec<typename PointsA::Scalar, E>& b_mean,
    const Weights& weights) {
  using T = typename PointsA::Scalar;
  MatT<T, D, E> C = MatT<T, D, E>::Zero();
  for (Eigen::Index i = 0; i < a_points.cols(); ++i) {
    const Vec<T, D> da = a_points.col(i) - a_mean;
    const Vec<T, E> db = b_points.col(i) - b_mean;
    C.noalias() += weights(i) * da * db.transpose();
  }
  return C;
}

// C = sum_i w_i (A_i - a)(A_i - a)^T.
template <int D, class Points, class Weights>
MatT<typename Points::Scalar, D, D> WeightedCov(const Points& points,
                                                const Vec<typename Points::Scalar, D>& mean,
                                                const Weights& weights) {
  using T = typename Points::Scalar;
  MatT<T, D, D> C = MatT<T, D, D>::Zero();
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Vec<T, D> d = points.col(i) - mean;
    C.noalias() += weights(i) * d * d.transpose();
  }
  return C;
}

// True when every entry of the mean and the covariance is finite.
template <int N, class T = double>
bool BeliefFinite(const Vec<T, N>& x, const MatT<T, N, N>& P) {
  return AllFiniteT(x) && AllFiniteT(P);
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
  bool PredictCrossCov(StateCov* C) const override {
    if (!have_cross_) return false;
    *C = cross_;
    return true;
  }

 protected:
  void SetPrior(const State& x, const StateCov& P) {
    x_ = x;
    P_ = P;
    error_.clear();
    prior_error_.clear();
    initialized_ = true;
    have_cross_ = false;
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

  // A successful Predict from (x_, P_) to (x_pred, P_pred) with cross-
  // covariance C (see Filter::PredictCrossCov).
  void SetPredicted(const State& x_pred, const StateCov& P_pred, const StateCov& C) {
    x_ = x_pred;
    P_ = P_pred;
    cross_ = C;
    have_cross_ = true;
  }
  // ... whose cross-covariance the filter forms itself, on demand (an
  // override of PredictCrossCov).
  void SetPredicted(const State& x_pred, const StateCov& P_pred) {
    x_ = x_pred;
    P_ = P_pred;
    have_cross_ = false;
  }

  State x_ = State::Zero();
  StateCov P_ = StateCov::Identity();
  StateCov cross_ = StateCov::Zero();
  bool have_cross_ = false;
  std::string error_;

 private:
  std::string prior_error_;
  bool initialized_ = false;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_FILTER_UTIL_H_
