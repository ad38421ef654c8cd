// The symmetric eigendecomposition behind the rare paths of the filters and
// the simulator: a covariance square root when Cholesky fails
// (CovarianceSqrt, filter_util.h), the adaptive filters' eigenvalue floor
// (ClipToPositiveDefinite, noise_adapter.h) and a full process-noise factor
// (ProcessNoiseFactor, src/sim/simulator_impl.h).
//
// Compiled once, in symmetric_eigen.cpp, for every size up to
// kMaxFixedEigenSize with Eigen's fixed-size solver: the same numbers, bit for
// bit, as instantiating Eigen::SelfAdjointEigenSolver<Mat<N, N>> in place,
// without every model's translation unit and every model file's library
// compiling the solver again (issue 38: it was about a quarter of a model
// file's first compile). Larger sizes use the dynamic-size solver.
//
//   A = V diag(values) V^T,  values ascending, V's columns the eigenvectors
//
// Usage:
//   Vec<double, N> values;  Mat<N, N> vectors;
//   if (!SymmetricEigen<N>(A, &values, &vectors)) ...   // did not converge
#ifndef ESTLAB_FILTERS_SYMMETRIC_EIGEN_H_
#define ESTLAB_FILTERS_SYMMETRIC_EIGEN_H_

#include "src/core/types.h"

namespace estlab {

inline constexpr int kMaxFixedEigenSize = 16;

// `a`: n x n, column-major, symmetric (only its lower triangle is read);
// `values` n doubles, `vectors` n x n column-major. False when the solver
// does not converge (values and vectors are then what it left).
bool SymmetricEigen(const double* a, int n, double* values, double* vectors);

template <int N>
bool SymmetricEigen(const Mat<N, N>& A, Vec<double, N>* values, Mat<N, N>* vectors) {
  return SymmetricEigen(A.data(), N, values->data(), vectors->data());
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_SYMMETRIC_EIGEN_H_
