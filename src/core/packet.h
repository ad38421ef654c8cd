// Packet: kPacketWidth doubles computed together, a scalar type for the
// models' Rhs<T> and Eval<T>, so that a particle cloud or a sigma-point set
// is moved kPacketWidth points per call with SIMD arithmetic and vectorised
// sin, cos and exp (SLEEF, Debian's libsleef-dev) instead of one libm call
// per point.
//
// Usage:
//   Vec<Packet, 2> x;                          // lane k = point k
//   for (int k = 0; k < kPacketWidth; ++k) { x(0).Set(k, theta[k]); x(1).Set(k, omega[k]); }
//   const Vec<Packet, 2> dx = models::Pendulum::Rhs(Packet(0.0), x, 0.0, params);
//   double dtheta_of_point_1 = dx(0)[1];
//
// Numbers: +, -, *, / and sqrt are IEEE double lane by lane, so each lane
// equals the scalar computation exactly. sin and cos are SLEEF's
// deterministic 3.5-ULP functions, exp its 1.0-ULP one (Sleef_cinz_*: no
// FMA; Sleef_finz_* in an AVX2+FMA build): identical on every machine for
// one build, but they may differ from the C library's in the last two bits
// (the 1.0-ULP sin costs as many instructions as glibc's in SSE2; the
// 3.5-ULP one 2.6 times fewer). Other functions are the C library's, lane by
// lane.
//
// Width: 2 (SSE2, every x86-64) by default; 4 when compiled for AVX
// (cmake -DESTLAB_NATIVE=ON on an AVX2 machine).
//
// WARNING: a packet has no order. Only models that declare
// `static constexpr bool kPacketRhs = true;` (branch-free Rhs and Eval:
// no if, ?:, comparison, min or max on T) are evaluated on packets
// (kPacketModel, models/model.h); others keep one scalar call per point.
#ifndef ESTLAB_CORE_PACKET_H_
#define ESTLAB_CORE_PACKET_H_

#include <cmath>

#include <Eigen/Core>

#include <sleef.h>
// sleef.h's own helper macros, not part of its API.
#undef CONST
#undef IMPORT

// The width is part of every packet symbol's name (an inline namespace), so
// code compiled for another width (say -mavx against a portable estlab)
// fails to link instead of mixing 16- and 32-byte packets.
#if defined(__AVX__)
#define ESTLAB_PACKET_ABI packet4
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

#if defined(__AVX2__) && defined(__FMA__)
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
