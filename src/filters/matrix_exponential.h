// The matrix exponential behind the linearised Kalman filter's exact
// zero-order-hold (and first-order-hold) discretisation (kalman.h: the
// augmented matrix [A B c; 0 0 0] dt, Van Loan's construction).
//
// Compiled once, in matrix_exponential.cpp, for every size up to
// kMaxFixedExpSize with Eigen's fixed-size MatrixFunctions exp (scaling and
// squaring with Pade approximants): the same numbers, bit for bit, as
// calling `.exp()` on a Mat<N, N> in place, without every model's
// translation unit and every model file's library compiling it again
// (issue 38). Larger sizes use the dynamic-size exp.
//
// Usage:
//   const Mat<kA, kA> e = MatrixExponential<kA>(augmented);
#ifndef ESTLAB_FILTERS_MATRIX_EXPONENTIAL_H_
#define ESTLAB_FILTERS_MATRIX_EXPONENTIAL_H_

#include "src/core/types.h"

namespace estlab {

inline constexpr int kMaxFixedExpSize = 24;

// exp(a) of the n x n column-major `a` into `out` (n x n, column-major).
void MatrixExponential(const double* a, int n, double* out);

template <int N>
Mat<N, N> MatrixExponential(const Mat<N, N>& A) {
  Mat<N, N> e;
  MatrixExponential(A.data(), N, e.data());
  return e;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_MATRIX_EXPONENTIAL_H_
