// Subset updates: a measurement z_k with some components missing (NaN: an
// empty cell, a sensor that did not report) updates with the observed
// components only (issue 35).
//
// Written as a mask on the full-size matrices, so that every filter keeps
// its fixed sizes and allocates nothing: for each missing component j,
//   row j of H (the EKF's, the KF's) or of the measurement points'
//   deviations (sigma-point rules) is zero,  nu_j = 0,
//   row and column j of R (and of S) are zero with R_jj = S_jj = 1.
// Then S = [S_oo 0; 0 I] up to a permutation, K = P H^T S^-1 has zero
// columns j, and x+, P+, log det S and nu^T S^-1 nu are those of the update
// with the observed rows alone (H_o, R_oo, S_oo) -- exactly, not
// approximately: the Cholesky factor of S is that of S_oo with ones for the
// missing rows. Only the constant of the log-likelihood counts the observed
// components: log N(nu_o; 0, S_oo) = -1/2 (log det S + nu^T S^-1 nu +
// m_o log 2 pi) (GaussianLogLikelihood's `observed`), and NIS has m_o
// degrees of freedom.
//
// Usage:
//   const MissingMask<M> missing(z);
//   nu = wrap(z - h(x));  missing.MaskRows(&nu);  missing.MaskRows(&H);
//   const MatT<T, M, M>& Ru = missing.Noise(R, &scratch);  // S = H P H^T + Ru ...
//   SetInnovation(nu, S, L, missing, &result);  // NaN reported where missing
#ifndef ESTLAB_FILTERS_MISSING_H_
#define ESTLAB_FILTERS_MISSING_H_

#include <array>
#include <cmath>
#include <limits>

#include "src/core/types.h"

namespace estlab {

template <int M>
class MissingMask {
 public:
  explicit MissingMask(const Vec<double, M>& z) {
    for (int j = 0; j < M; ++j) {
      missing_[size_t(j)] = !std::isfinite(z(j));
      observed_ -= missing_[size_t(j)] ? 1 : 0;
    }
  }

  bool Any() const { return observed_ < M; }
  bool Missing(int j) const { return missing_[size_t(j)]; }
  int Observed() const { return observed_; }  // m_o
  // The first observed component (M when none is).
  int FirstObserved() const {
    int j = 0;
    while (j < M && missing_[size_t(j)]) ++j;
    return j;
  }

  // Rows j of A (H, nu, the measurement points' deviations) set to zero.
  template <class Derived>
  void MaskRows(Eigen::MatrixBase<Derived>* A) const {
    using T = typename Derived::Scalar;
    for (int j = 0; j < M; ++j)
      if (missing_[size_t(j)]) A->row(j).setConstant(T(0.0));
  }
  // Columns j of A (a cross-covariance P_xz) set to zero.
  template <class Derived>
  void MaskCols(Eigen::MatrixBase<Derived>* A) const {
    using T = typename Derived::Scalar;
    for (int j = 0; j < M; ++j)
      if (missing_[size_t(j)]) A->col(j).setConstant(T(0.0));
  }
  // Rows and columns j of a covariance (R, S) set to zero, its (j, j) to 1.
  template <class T>
  void MaskCov(MatT<T, M, M>* C) const {
    for (int j = 0; j < M; ++j) {
      if (!missing_[size_t(j)]) continue;
      C->row(j).setConstant(T(0.0));
      C->col(j).setConstant(T(0.0));
      (*C)(j, j) = T(1.0);
    }
  }
  // The noise an update uses: R itself when nothing is missing, else R
  // masked in *scratch.
  template <class T>
  const MatT<T, M, M>& Noise(const MatT<T, M, M>& R, MatT<T, M, M>* scratch) const {
    if (!Any()) return R;
    *scratch = R;
    MaskCov(scratch);
    return *scratch;
  }
  // What a filter reports for the missing components: NaN in the
  // innovation, in its covariance's rows and columns.
  void MarkReported(Vec<double, M>* nu, Mat<M, M>* S) const {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    for (int j = 0; j < M; ++j) {
      if (!missing_[size_t(j)]) continue;
      (*nu)(j) = nan;
      S->row(j).setConstant(nan);
      S->col(j).setConstant(nan);
    }
  }

 private:
  std::array<bool, size_t(M)> missing_{};
  int observed_ = M;
};

// Whether the reported innovation is finite in every component z observed.
template <int M>
bool InnovationFinite(const Vec<double, M>& z, const Vec<double, M>& nu) {
  for (int j = 0; j < M; ++j)
    if (std::isfinite(z(j)) && !std::isfinite(nu(j))) return false;
  return true;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_MISSING_H_
