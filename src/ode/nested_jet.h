// Second-order forward-mode AD for the tuner's EKF: the flow Jacobian
// F = dPhi/dx (and the measurement Jacobian H = dh/dx) evaluated at a state
// that itself depends on the tuned parameters theta. The EKF's
// P- = F P F^T + Q then needs dF/dtheta = d2Phi/dx2 . dx/dtheta, i.e. a Jet
// (over x) of Jets (over theta).
//
// ceres::Jet<ceres::Jet<double, K>, N> holds exactly that, but the model
// code mixes it with plain doubles (`p.g / p.L * sin(x)`, `T tt(t)`), which
// ceres 2.1 only supports for one level of nesting. NestedJet<K, N> wraps the
// nested Jet and adds the double conversions and mixed operators, so every
// model's Rhs<T> and Meas::Eval<T> compile unchanged.
//
// Usage:
//   using J = ceres::Jet<double, K>;                 // derivatives in theta
//   Vec<NestedJet<K, N>, N> xs = SeedNested<K, N>(x);  // x: Vec<J, N>
//   Vec<NestedJet<K, N>, N> y = FixedPropagate<Model, NestedJet<K, N>>(...);
//   y(i).j.a      -> Phi_i(x) as a J,
//   y(i).j.v(c)   -> F(i, c) as a J (its .v holds dF(i, c)/dtheta).
//
// WARNING: only the operations the models use are provided (+ - * /, sin,
// cos, tan, exp, log, sqrt, pow, abs, atan2, tanh, comparisons). A model that
// calls something else fails to compile here, not silently.
#ifndef ESTLAB_ODE_NESTED_JET_H_
#define ESTLAB_ODE_NESTED_JET_H_

#include <ceres/jet.h>

#include <Eigen/Core>
#include <cmath>

#include "src/core/types.h"

namespace estlab {

template <int K, int N>
struct NestedJet {
  using Inner = ceres::Jet<double, K>;
  using Base = ceres::Jet<Inner, N>;
  Base j;

  NestedJet() = default;
  NestedJet(double s) : j(Inner(s)) {}       // NOLINT: implicit, like a double literal
  NestedJet(int s) : j(Inner(double(s))) {}  // NOLINT
  explicit NestedJet(const Inner& a) : j(a) {}
  explicit NestedJet(const Base& b) : j(b) {}

  double scalar() const { return j.a.a; }

  NestedJet& operator+=(const NestedJet& y) {
    j += y.j;
    return *this;
  }
  NestedJet& operator-=(const NestedJet& y) {
    j -= y.j;
    return *this;
  }
  NestedJet& operator*=(const NestedJet& y) {
    j *= y.j;
    return *this;
  }
  NestedJet& operator/=(const NestedJet& y) {
    j /= y.j;
    return *this;
  }
};

#define ESTLAB_NESTED_JET_BINARY(op)                                                       \
  template <int K, int N>                                                                  \
  inline NestedJet<K, N> operator op(const NestedJet<K, N>& f, const NestedJet<K, N>& g) { \
    return NestedJet<K, N>(typename NestedJet<K, N>::Base(f.j op g.j));                    \
  }                                                                                        \
  template <int K, int N>                                                                  \
  inline NestedJet<K, N> operator op(const NestedJet<K, N>& f, double s) {                 \
    return NestedJet<K, N>(                                                                \
        typename NestedJet<K, N>::Base(f.j op typename NestedJet<K, N>::Inner(s)));        \
  }                                                                                        \
  template <int K, int N>                                                                  \
  inline NestedJet<K, N> operator op(double s, const NestedJet<K, N>& f) {                 \
    return NestedJet<K, N>(                                                                \
        typename NestedJet<K, N>::Base(typename NestedJet<K, N>::Inner(s) op f.j));        \
  }
ESTLAB_NESTED_JET_BINARY(+)
ESTLAB_NESTED_JET_BINARY(-)
ESTLAB_NESTED_JET_BINARY(*)
ESTLAB_NESTED_JET_BINARY(/)
#undef ESTLAB_NESTED_JET_BINARY

template <int K, int N>
inline NestedJet<K, N> operator-(const NestedJet<K, N>& f) {
  return NestedJet<K, N>(typename NestedJet<K, N>::Base(-f.j));
}
template <int K, int N>
inline NestedJet<K, N> operator+(const NestedJet<K, N>& f) {
  return f;
}

// Comparisons look at the value only (as ceres::Jet's do).
#define ESTLAB_NESTED_JET_COMPARE(op)                                           \
  template <int K, int N>                                                       \
  inline bool operator op(const NestedJet<K, N>& f, const NestedJet<K, N>& g) { \
    return f.scalar() op g.scalar();                                            \
  }                                                                             \
  template <int K, int N>                                                       \
  inline bool operator op(const NestedJet<K, N>& f, double s) {                 \
    return f.scalar() op s;                                                     \
  }                                                                             \
  template <int K, int N>                                                       \
  inline bool operator op(double s, const NestedJet<K, N>& f) {                 \
    return s op f.scalar();                                                     \
  }
ESTLAB_NESTED_JET_COMPARE(<)
ESTLAB_NESTED_JET_COMPARE(<=)
ESTLAB_NESTED_JET_COMPARE(>)
ESTLAB_NESTED_JET_COMPARE(>=)
ESTLAB_NESTED_JET_COMPARE(==)
ESTLAB_NESTED_JET_COMPARE(!=)
#undef ESTLAB_NESTED_JET_COMPARE

#define ESTLAB_NESTED_JET_UNARY(fn)                                         \
  template <int K, int N>                                                   \
  inline NestedJet<K, N> fn(const NestedJet<K, N>& f) {                     \
    return NestedJet<K, N>(typename NestedJet<K, N>::Base(ceres::fn(f.j))); \
  }
ESTLAB_NESTED_JET_UNARY(sin)
ESTLAB_NESTED_JET_UNARY(cos)
ESTLAB_NESTED_JET_UNARY(tan)
ESTLAB_NESTED_JET_UNARY(exp)
ESTLAB_NESTED_JET_UNARY(log)
ESTLAB_NESTED_JET_UNARY(sqrt)
ESTLAB_NESTED_JET_UNARY(abs)
ESTLAB_NESTED_JET_UNARY(tanh)
#undef ESTLAB_NESTED_JET_UNARY

template <int K, int N>
inline NestedJet<K, N> pow(const NestedJet<K, N>& f, double g) {
  using Base = typename NestedJet<K, N>::Base;
  using Inner = typename NestedJet<K, N>::Inner;
  // d(f^g) = g f^(g-1) df, written out because ceres::pow(Jet, double) is not
  // defined for nested Jets.
  const Inner value = ceres::pow(f.j.a, g);
  const Inner slope = g * ceres::pow(f.j.a, g - 1.0);
  return NestedJet<K, N>(Base(value, slope * f.j.v));
}
template <int K, int N>
inline NestedJet<K, N> atan2(const NestedJet<K, N>& y, const NestedJet<K, N>& x) {
  return NestedJet<K, N>(typename NestedJet<K, N>::Base(ceres::atan2(y.j, x.j)));
}

// The value part of a nested Jet (ScalarPart of double and Jet: types.h).
template <int K, int N>
double ScalarPart(const NestedJet<K, N>& x) {
  return x.scalar();
}

// The Jet type that carries d/dx (N directions) on top of scalar T: a plain
// Jet for T = double, a NestedJet for T = Jet<double, K>.
template <class T, int N>
struct Tangent;
template <int N>
struct Tangent<double, N> {
  using type = ceres::Jet<double, N>;
  static type Seed(double v, int i) { return type(v, i); }
  static double Value(const type& y) { return y.a; }
  static double Deriv(const type& y, int c) { return y.v(c); }
};
template <int K, int N>
struct Tangent<ceres::Jet<double, K>, N> {
  using Inner = ceres::Jet<double, K>;
  using type = NestedJet<K, N>;
  static type Seed(const Inner& v, int i) { return type(typename type::Base(v, i)); }
  static Inner Value(const type& y) { return y.j.a; }
  static Inner Deriv(const type& y, int c) { return y.j.v(c); }
};

// f(x) and its Jacobian df/dx for x of any scalar T (see Tangent); the
// Jacobian is skipped when null. For T = double this is ValueAndJacobian
// (autodiff.h).
template <int Mout, int N, class T, class F>
Eigen::Matrix<T, Mout, 1> ValueAndJacobianT(F&& f, const Eigen::Matrix<T, N, 1>& x,
                                            Eigen::Matrix<T, Mout, N>* jacobian) {
  using Tg = Tangent<T, N>;
  Eigen::Matrix<typename Tg::type, N, 1> xs;
  for (int i = 0; i < N; ++i) xs(i) = Tg::Seed(x(i), i);
  const Eigen::Matrix<typename Tg::type, Mout, 1> y = f(xs);
  Eigen::Matrix<T, Mout, 1> value;
  for (int r = 0; r < Mout; ++r) {
    value(r) = Tg::Value(y(r));
    if (jacobian != nullptr)
      for (int c = 0; c < N; ++c) (*jacobian)(r, c) = Tg::Deriv(y(r), c);
  }
  return value;
}

}  // namespace estlab

namespace Eigen {

template <int K, int N>
struct NumTraits<estlab::NestedJet<K, N>> {
  using Self = estlab::NestedJet<K, N>;
  using Real = Self;
  using NonInteger = Self;
  using Nested = Self;
  using Literal = Self;
  static Self dummy_precision() { return Self(1e-12); }
  static Self epsilon() { return Self(std::numeric_limits<double>::epsilon()); }
  static int digits10() { return NumTraits<double>::digits10(); }
  static Self highest() { return Self(std::numeric_limits<double>::max()); }
  static Self lowest() { return Self(-std::numeric_limits<double>::max()); }
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    ReadCost = 1,
    AddCost = 1,
    MulCost = 3,
    HasFloatingPoint = 1,
    RequireInitialization = 1
  };
};

template <typename BinaryOp, int K, int N>
struct ScalarBinaryOpTraits<estlab::NestedJet<K, N>, double, BinaryOp> {
  using ReturnType = estlab::NestedJet<K, N>;
};
template <typename BinaryOp, int K, int N>
struct ScalarBinaryOpTraits<double, estlab::NestedJet<K, N>, BinaryOp> {
  using ReturnType = estlab::NestedJet<K, N>;
};

}  // namespace Eigen

#endif  // ESTLAB_ODE_NESTED_JET_H_
