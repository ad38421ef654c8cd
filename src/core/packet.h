// Packet: kPacketWidth doubles computed together, a scalar type for the
// models' Rhs<T> and Eval<T>, so that a particle cloud is moved kPacketWidth
// particles per model call with SIMD arithmetic instead of one call per point.
//
// Usage:
//   Vec<Packet, 2> x;                          // lane k = point k
//   for (int k = 0; k < kPacketWidth; ++k) { x(0).Set(k, theta[k]); x(1).Set(k, omega[k]); }
//   const Vec<Packet, 2> dx = models::Pendulum::Rhs(Packet(0.0), x, 0.0, params);
//   double dtheta_of_point_1 = dx(0)[1];
//
// Numbers: +, -, *, / and sqrt are IEEE double lane by lane, so each lane
// equals the scalar computation exactly. sin, cos and exp depend on the
// CMake option ESTLAB_VECTOR_MATH:
//  - OFF (the default): the C library's, lane by lane. Every lane is the
//    scalar result bit for bit, so the packet path gives the same numbers as
//    one scalar call per point (studies are byte-identical to a scalar
//    build); the gain is the SIMD arithmetic only.
//  - ON: SLEEF's (Debian's libsleef-dev) vectorised functions, sin and cos
//    the deterministic 3.5-ULP ones, exp the 1.0-ULP one (Sleef_cinz_*: no
//    FMA; Sleef_finz_* in an AVX2+FMA build). The same on every machine for
//    one build, 2.4 (sin) and 1.5 (exp) times fewer instructions than glibc,
//    but they may differ from the C library's in the last two bits, so a
//    particle filter's results move by about 1e-15 relative
//    (docs/performance.md).
// Other functions are always the C library's, lane by lane.
//
// Width: 2 (SSE2, every x86-64) by default; 4 when compiled for AVX
// (cmake -DESTLAB_NATIVE=ON on an AVX2 machine). Width and vector math are
// part of the packet functions' symbols (an inline namespace): a model
// library built with other settings than estlab fails to link.
//
// WARNING: a packet has no order. Only models that declare
// `static constexpr bool kPacketRhs = true;` (branch-free Rhs and Eval:
// no if, ?:, comparison, min or max on T) are evaluated on packets
// (kPacketModel, models/model.h); others keep one scalar call per point.
// WARNING: functions that do not name Packet in their signature (the
// particle filter's Update, say) have the same symbol in every setting: do
// not link objects of builds with different settings together.
#ifndef ESTLAB_CORE_PACKET_H_
#define ESTLAB_CORE_PACKET_H_

#include <cmath>

#include <Eigen/Core>

#ifndef ESTLAB_VECTOR_MATH  // set by CMake (estlab_core's interface) to 0 or 1
#define ESTLAB_VECTOR_MATH 0
#endif
#if ESTLAB_VECTOR_MATH
#if !defined(__SSE2__)
#error "ESTLAB_VECTOR_MATH needs SSE2 or AVX (x86-64); configure with -DESTLAB_VECTOR_MATH=OFF"
#endif
#include <sleef.h>
// sleef.h's own helper macros, not part of its API.
#undef CONST
#undef IMPORT
#endif

// Width and vector math are part of every packet symbol's name (an inline
// namespace), so code compiled with other settings (say -mavx against a
// portable estlab) fails to link instead of mixing 16- and 32-byte packets
// or two sin functions.
#if defined(__AVX__) && ESTLAB_VECTOR_MATH
#define ESTLAB_PACKET_ABI packet4v
#elif defined(__AVX__)
#define ESTLAB_PACKET_ABI packet4
#elif ESTLAB_VECTOR_MATH
#define ESTLAB_PACKET_ABI packet2v
#else
#define ESTLAB_PACKET_ABI packet2
#endif

namespace estlab {
inline namespace ESTLAB_PACKET_ABI {

#if defined(__AVX__)
inline constexpr int kPacketWidth = 4;
#else
inline constexpr int kPacketWidth = 2;
#endif

struct Packet {
  using V = double __attribute__((vector_size(8 * kPacketWidth)));
  V v;

  Packet() : v(V{}) {}
  Packet(double s) : v(V{}) {  // NOLINT: implicit, every lane s (as Jet(double))
    for (int k = 0; k < kPacketWidth; ++k) v[k] = s;  // (V{} + s would turn -0 into +0)
  }
  explicit Packet(V x) : v(x) {}

  double operator[](int lane) const { return v[lane]; }
  void Set(int lane, double s) { v[lane] = s; }

  Packet& operator+=(const Packet& o) {
    v += o.v;
    return *this;
  }
  Packet& operator-=(const Packet& o) {
    v -= o.v;
    return *this;
  }
  Packet& operator*=(const Packet& o) {
    v *= o.v;
    return *this;
  }
  Packet& operator/=(const Packet& o) {
    v /= o.v;
    return *this;
  }
};

inline Packet operator+(const Packet& a, const Packet& b) { return Packet(a.v + b.v); }
inline Packet operator-(const Packet& a, const Packet& b) { return Packet(a.v - b.v); }
inline Packet operator*(const Packet& a, const Packet& b) { return Packet(a.v * b.v); }
inline Packet operator/(const Packet& a, const Packet& b) { return Packet(a.v / b.v); }
inline Packet operator+(const Packet& a) { return a; }
inline Packet operator-(const Packet& a) { return Packet(-a.v); }

// The C library's f on every lane.
template <class F>
Packet Lanewise(F f, const Packet& x) {
  Packet y;
  for (int k = 0; k < kPacketWidth; ++k) y.v[k] = f(x.v[k]);
  return y;
}
template <class F>
Packet Lanewise(F f, const Packet& x, const Packet& z) {
  Packet y;
  for (int k = 0; k < kPacketWidth; ++k) y.v[k] = f(x.v[k], z.v[k]);
  return y;
}

#if !ESTLAB_VECTOR_MATH
inline Packet sin(const Packet& x) {
  return Lanewise([](double s) { return std::sin(s); }, x);
}
inline Packet cos(const Packet& x) {
  return Lanewise([](double s) { return std::cos(s); }, x);
}
inline Packet exp(const Packet& x) {
  return Lanewise([](double s) { return std::exp(s); }, x);
}
#elif defined(__AVX2__) && defined(__FMA__)
inline Packet sin(const Packet& x) { return Packet(Sleef_finz_sind4_u35avx2(x.v)); }
inline Packet cos(const Packet& x) { return Packet(Sleef_finz_cosd4_u35avx2(x.v)); }
inline Packet exp(const Packet& x) { return Packet(Sleef_finz_expd4_u10avx2(x.v)); }
#elif defined(__AVX__)
inline Packet sin(const Packet& x) { return Packet(Sleef_cinz_sind4_u35avx(x.v)); }
inline Packet cos(const Packet& x) { return Packet(Sleef_cinz_cosd4_u35avx(x.v)); }
inline Packet exp(const Packet& x) { return Packet(Sleef_cinz_expd4_u10avx(x.v)); }
#else
inline Packet sin(const Packet& x) { return Packet(Sleef_cinz_sind2_u35sse2(x.v)); }
inline Packet cos(const Packet& x) { return Packet(Sleef_cinz_cosd2_u35sse2(x.v)); }
inline Packet exp(const Packet& x) { return Packet(Sleef_cinz_expd2_u10sse2(x.v)); }
#endif
inline Packet sqrt(const Packet& x) {
  return Lanewise([](double s) { return std::sqrt(s); }, x);
}
inline Packet log(const Packet& x) {
  return Lanewise([](double s) { return std::log(s); }, x);
}
inline Packet tan(const Packet& x) {
  return Lanewise([](double s) { return std::tan(s); }, x);
}
inline Packet tanh(const Packet& x) {
  return Lanewise([](double s) { return std::tanh(s); }, x);
}
inline Packet atan2(const Packet& y, const Packet& x) {
  return Lanewise([](double a, double b) { return std::atan2(a, b); }, y, x);
}
inline Packet pow(const Packet& x, const Packet& e) {
  return Lanewise([](double a, double b) { return std::pow(a, b); }, x, e);
}

}  // namespace ESTLAB_PACKET_ABI
}  // namespace estlab

namespace Eigen {

template <>
struct NumTraits<estlab::Packet> : GenericNumTraits<estlab::Packet> {
  using Real = estlab::Packet;
  using NonInteger = estlab::Packet;
  using Nested = estlab::Packet;
  using Literal = estlab::Packet;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 0,
    ReadCost = 1,
    AddCost = 1,
    MulCost = 1
  };
};
template <class BinaryOp>
struct ScalarBinaryOpTraits<estlab::Packet, double, BinaryOp> {
  using ReturnType = estlab::Packet;
};
template <class BinaryOp>
struct ScalarBinaryOpTraits<double, estlab::Packet, BinaryOp> {
  using ReturnType = estlab::Packet;
};

}  // namespace Eigen

#endif  // ESTLAB_CORE_PACKET_H_
