#include "src/filters/matrix_exponential.h"

#include <array>
#include <unsupported/Eigen/MatrixFunctions>
#include <utility>

namespace estlab {

namespace {

using Exp = void (*)(const double*, double*);

template <int N>
void Fixed(const double* a, double* out) {
  using M = Eigen::Matrix<double, N, N>;
  const M m = Eigen::Map<const M>(a);
  const M e = m.exp();  // as `const Mat<N, N> e = m.exp()` in place
  Eigen::Map<M> result(out);
  result = e;
}

template <int... I>
constexpr std::array<Exp, sizeof...(I)> FixedTable(std::integer_sequence<int, I...>) {
  return {&Fixed<I + 1>...};
}

// kFixed[n - 1]: exp of an n x n matrix.
constexpr auto kFixed = FixedTable(std::make_integer_sequence<int, kMaxFixedExpSize>());

}  // namespace

void MatrixExponential(const double* a, int n, double* out) {
  if (n >= 1 && n <= kMaxFixedExpSize) {
    kFixed[size_t(n - 1)](a, out);
    return;
  }
  Eigen::Map<Eigen::MatrixXd>(out, n, n) = Eigen::Map<const Eigen::MatrixXd>(a, n, n).exp();
}

}  // namespace estlab
