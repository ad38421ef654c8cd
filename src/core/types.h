// Core types shared by every part of estlab: fixed-size Eigen aliases, the
// error type for bad user input, and small numeric helpers.
//
// Usage:
//   estlab::Vec<double, 4> x = estlab::Vec<double, 4>::Zero();
//   if (!(dt > 0)) throw estlab::InputError("--dt must be > 0, got " + ...);
#ifndef ESTLAB_CORE_TYPES_H_
#define ESTLAB_CORE_TYPES_H_

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace estlab {

template <class T, int N>
using Vec = Eigen::Matrix<T, N, 1>;

template <int R, int C>
using Mat = Eigen::Matrix<double, R, C>;

// A fixed-size matrix of any scalar (double, ceres::Jet): the filter steps
// are written once on it (src/filters/*_step.h).
template <class T, int R, int C>
using MatT = Eigen::Matrix<T, R, C>;

// Bad user input: unknown names, wrong lengths, non-finite numbers,
// non-positive-definite covariances, malformed files. The CLI prints
// "estlab: error: <what()>" and exits with status 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A numerical failure during a run (CVODES error, divergence). The CLI exits
// with status 1 and keeps what was computed so far.
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Wraps an angle to (-pi, pi].
inline double WrapAngle(double a) {
  constexpr double kPi = 3.14159265358979323846;
  double w = std::remainder(a, 2.0 * kPi);  // in [-pi, pi]
  if (w <= -kPi) w += 2.0 * kPi;
  return w;
}

// Values already in (-pi, pi] are returned as they are (WrapAngle would return
// them unchanged too: std::remainder is exact), without the remainder call.
inline double WrapAngleFast(double a) {
  constexpr double kPi = 3.14159265358979323846;
  return (a > -kPi && a <= kPi) ? a : WrapAngle(a);
}

// The value part of a double or a ceres::Jet (recursively; NestedJet adds its
// own overload in src/ode/nested_jet.h): for control flow (angle wrapping,
// divergence checks), never for derivatives.
template <class T>
double ScalarPart(const T& v) {
  if constexpr (std::is_arithmetic_v<T>) {
    return double(v);
  } else {
    return ScalarPart(v.a);
  }
}

// Wraps an angle-valued quantity of any scalar to (-pi, pi] by shifting its
// value by a multiple of 2 pi; derivatives are unchanged.
template <class T>
T WrapAngleT(const T& a) {
  if constexpr (std::is_same_v<T, double>) {
    return WrapAngleFast(a);
  } else {
    const double value = ScalarPart(a);
    return a + (WrapAngle(value) - value);
  }
}

// Short human-readable number ("%.6g") for messages.
inline std::string FormatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace estlab

#endif  // ESTLAB_CORE_TYPES_H_
