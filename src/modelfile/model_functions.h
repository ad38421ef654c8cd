// Math for generated model headers (codegen.h) that works for every scalar
// estlab differentiates with: double, ceres::Jet<double, N> and NestedJet
// (src/ode/nested_jet.h). NestedJet provides only + - * /, comparisons,
// sin cos tan exp log sqrt abs tanh, pow(x, double) and atan2(T, T), so the
// other functions are written here in terms of those whenever the scalar has
// no overload of its own (double uses <cmath>, ceres::Jet its own functions).
//
// Usage (what generated code looks like):
//   const T r = model_fn::Asin(x(0)) + model_fn::Min(x(1), T(p.limit));
//
// WARNING: Min and Max compare values only, like ceres' comparison
// operators; the derivative is that of the selected argument.
#ifndef ESTLAB_MODELFILE_MODEL_FUNCTIONS_H_
#define ESTLAB_MODELFILE_MODEL_FUNCTIONS_H_

#include <cmath>

namespace estlab::model_fn {

template <class T>
T Asin(const T& x) {
  using std::asin;
  if constexpr (requires { asin(x); }) {
    return asin(x);
  } else {
    using std::atan2;
    using std::sqrt;
    return atan2(x, sqrt(1.0 - x * x));  // asin x = atan2(x, sqrt(1 - x^2))
  }
}

template <class T>
T Acos(const T& x) {
  using std::acos;
  if constexpr (requires { acos(x); }) {
    return acos(x);
  } else {
    using std::atan2;
    using std::sqrt;
    return atan2(sqrt(1.0 - x * x), x);  // acos x = atan2(sqrt(1 - x^2), x)
  }
}

template <class T>
T Atan(const T& x) {
  using std::atan;
  if constexpr (requires { atan(x); }) {
    return atan(x);
  } else {
    using std::atan2;
    return atan2(x, T(1.0));
  }
}

template <class T>
T Sinh(const T& x) {
  using std::sinh;
  if constexpr (requires { sinh(x); }) {
    return sinh(x);
  } else {
    using std::exp;
    return 0.5 * (exp(x) - exp(-x));
  }
}

template <class T>
T Cosh(const T& x) {
  using std::cosh;
  if constexpr (requires { cosh(x); }) {
    return cosh(x);
  } else {
    using std::exp;
    return 0.5 * (exp(x) + exp(-x));
  }
}

template <class T>
T Log1p(const T& x) {
  using std::log1p;
  if constexpr (requires { log1p(x); }) {
    return log1p(x);
  } else {
    using std::log;
    return log(1.0 + x);  // loses accuracy for |x| << 1, unlike std::log1p
  }
}

// min(a, b) = b < a ? b : a, max(a, b) = a < b ? b : a (as std::min/max).
template <class T>
T Min(const T& a, const T& b) {
  return b < a ? b : a;
}
template <class T>
T Max(const T& a, const T& b) {
  return a < b ? b : a;
}

// x^2 and x^3 as products, the same operations as writing x * x (* x).
template <class T>
T Square(const T& x) {
  return x * x;
}
template <class T>
T Cube(const T& x) {
  return x * x * x;
}

// a^b for an exponent of type T: the scalar's pow(T, T) when it has one
// (double, ceres::Jet), else exp(b log a), defined for a > 0.
template <class T>
T PowT(const T& a, const T& b) {
  using std::pow;
  if constexpr (requires { pow(a, b); }) {
    return pow(a, b);
  } else {
    using std::exp;
    using std::log;
    return exp(b * log(a));
  }
}

}  // namespace estlab::model_fn

#endif  // ESTLAB_MODELFILE_MODEL_FUNCTIONS_H_
