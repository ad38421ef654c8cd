// Steady-state Kalman gain from the discrete algebraic Riccati equation,
// solved independently of the filter code by the structure-preserving
// doubling algorithm (SDA; Chu, Fan & Lin 2005) for the filter DARE
//   X = F X F^T - F X H^T (H X H^T + R)^-1 H X F^T + Q
//     = A^T X (I + G X)^-1 A + Q,  A = F^T, G = H^T R^-1 H,
//   A_{k+1} = A_k W^-1 A_k,  G_{k+1} = G_k + A_k W^-1 G_k A_k^T,
//   X_{k+1} = X_k + A_k^T X_k W^-1 A_k,  W = I + G_k X_k,
// X_k -> X (the prior covariance P-) quadratically. Gain K = X H^T (H X H^T + R)^-1.
#ifndef ESTLAB_TESTS_FILTERS_RICCATI_H_
#define ESTLAB_TESTS_FILTERS_RICCATI_H_

#include <Eigen/LU>

#include "src/core/types.h"

namespace estlab::testing {

template <int N, int M>
Mat<N, N> SolveFilterDare(const Mat<N, N>& F, const Mat<M, N>& H, const Mat<N, N>& Q,
                          const Mat<M, M>& R) {
  Mat<N, N> A = F.transpose();
  Mat<N, N> G = H.transpose() * R.partialPivLu().solve(H);
  Mat<N, N> X = Q;
  for (int k = 0; k < 100; ++k) {
    const Eigen::PartialPivLU<Mat<N, N>> W(Mat<N, N>::Identity() + G * X);
    const Mat<N, N> WA = W.solve(A);  // W^-1 A
    const Mat<N, N> WG = W.solve(G);  // W^-1 G
    const Mat<N, N> X_next = X + A.transpose() * X * WA;
    G = G + A * WG * A.transpose();
    A = A * WA;
    const double change = (X_next - X).cwiseAbs().maxCoeff();
    X = X_next;
    if (change <= 1e-16 * X.cwiseAbs().maxCoeff()) break;
  }
  return 0.5 * (X + X.transpose());
}

template <int N, int M>
Mat<N, M> RiccatiGain(const Mat<N, N>& F, const Mat<M, N>& H, const Mat<N, N>& Q,
                      const Mat<M, M>& R) {
  const Mat<N, N> X = SolveFilterDare<N, M>(F, H, Q, R);
  const Mat<M, M> S = H * X * H.transpose() + R;
  return S.transpose().partialPivLu().solve(H * X).transpose();  // X H^T S^-1
}

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_FILTERS_RICCATI_H_
