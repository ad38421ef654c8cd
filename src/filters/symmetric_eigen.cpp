#include "src/filters/symmetric_eigen.h"

#include <Eigen/Eigenvalues>
#include <array>
#include <utility>

namespace estlab {

namespace {

using Solve = bool (*)(const double*, double*, double*);

// Eigen's solver for an N x N matrix (N = Eigen::Dynamic: any n).
template <int N>
bool Solver(const double* a, int n, double* values, double* vectors) {
  using M = Eigen::Matrix<double, N, N>;
  const M m = Eigen::Map<const M>(a, n, n);
  const Eigen::SelfAdjointEigenSolver<M> eig(m);
  Eigen::Map<Eigen::Matrix<double, N, 1>>(values, n) = eig.eigenvalues();
  Eigen::Map<M>(vectors, n, n) = eig.eigenvectors();
  return eig.info() == Eigen::Success;
}

template <int N>
bool Fixed(const double* a, double* values, double* vectors) {
  return Solver<N>(a, N, values, vectors);
}

template <int... I>
constexpr std::array<Solve, sizeof...(I)> FixedTable(std::integer_sequence<int, I...>) {
  return {&Fixed<I + 1>...};
}

// kFixed[n - 1]: the solver for n x n.
constexpr auto kFixed = FixedTable(std::make_integer_sequence<int, kMaxFixedEigenSize>());

}  // namespace

bool SymmetricEigen(const double* a, int n, double* values, double* vectors) {
  if (n >= 1 && n <= kMaxFixedEigenSize) return kFixed[size_t(n - 1)](a, values, vectors);
  return Solver<Eigen::Dynamic>(a, n, values, vectors);
}

}  // namespace estlab
