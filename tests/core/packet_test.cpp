// Packet (src/core/packet.h): arithmetic equals the scalar computation bit
// for bit in every lane; sin, cos and exp are the C library's bit for bit
// (ESTLAB_VECTOR_MATH off, the default) or, with SLEEF (on), sin and cos
// (3.5 ULP) within 4 ULP and exp (1.0 ULP) within 2 ULP of the C library's
// (itself within 0.5-1 ULP of the exact value) over grids; they agree on the
// special values; the other lane-wise functions are the C library's.
#include "src/core/packet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace estlab::testing {
namespace {

// Distance between a and b in units in the last place of b.
double UlpDistance(double a, double b) {
  if (a == b) return 0.0;
  const double ulp =
      std::nextafter(std::abs(b), std::numeric_limits<double>::infinity()) - std::abs(b);
  return std::abs(a - b) / ulp;
}

// kPacketWidth consecutive values of v from `first` (wrapping around).
Packet Load(const std::vector<double>& v, size_t first) {
  Packet p;
  for (int k = 0; k < kPacketWidth; ++k) p.Set(k, v[(first + k) % v.size()]);
  return p;
}

std::vector<double> Grid(double lo, double hi, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(lo + (hi - lo) * (i + 0.37) / n);
  return v;
}

TEST(Packet, ArithmeticIsTheScalarArithmeticInEveryLane) {
  const std::vector<double> a = Grid(-7.0, 5.0, 101), b = Grid(0.3, 11.0, 103);
  for (size_t i = 0; i < a.size(); ++i) {
    const Packet x = Load(a, i), y = Load(b, i);
    const Packet sum = x + y, diff = x - y, prod = x * y, quot = x / y, neg = -x;
    const Packet mixed = 2.5 * x - y / 3.0 + 1.0;  // double operands broadcast
    const Packet root = sqrt(y);
    for (int k = 0; k < kPacketWidth; ++k) {
      const double s = a[(i + k) % a.size()], t = b[(i + k) % b.size()];
      EXPECT_EQ(sum[k], s + t);
      EXPECT_EQ(diff[k], s - t);
      EXPECT_EQ(prod[k], s * t);
      EXPECT_EQ(quot[k], s / t);
      EXPECT_EQ(neg[k], -s);
      EXPECT_EQ(mixed[k], 2.5 * s - t / 3.0 + 1.0);
      EXPECT_EQ(root[k], std::sqrt(t));
    }
  }
}

TEST(Packet, SinCosExpWithinTheirUlpBoundsOfTheCLibrary) {
  // Off: the C library's functions lane by lane, so no difference at all.
  const double sleef = ESTLAB_VECTOR_MATH ? 1.0 : 0.0;
  struct Case {
    const char* name;
    Packet (*packet)(const Packet&);
    double (*scalar)(double);
    std::vector<double> grid;
    double max_ulp;
  };
  const std::vector<Case> cases = {
      {"sin", [](const Packet& x) { return sin(x); }, [](double x) { return std::sin(x); },
       Grid(-50.0, 50.0, 20001), 4.0 * sleef},
      {"sin (large)", [](const Packet& x) { return sin(x); }, [](double x) { return std::sin(x); },
       Grid(-1e6, 1e6, 2001), 4.0 * sleef},
      {"cos", [](const Packet& x) { return cos(x); }, [](double x) { return std::cos(x); },
       Grid(-50.0, 50.0, 20001), 4.0 * sleef},
      {"exp", [](const Packet& x) { return exp(x); }, [](double x) { return std::exp(x); },
       Grid(-700.0, 700.0, 20001), 2.0 * sleef},
  };
  for (const Case& c : cases) {
    double worst = 0.0;
    for (size_t i = 0; i < c.grid.size(); i += kPacketWidth) {
      const Packet y = c.packet(Load(c.grid, i));
      for (int k = 0; k < kPacketWidth; ++k) {
        const double x = c.grid[(i + k) % c.grid.size()];
        const double ref = c.scalar(x);
        // Near a zero of sin or cos the relative ULP is of a tiny number:
        // bound the absolute error in ULP of 1 there instead.
        const double d = std::abs(ref) < 1e-3 ? std::abs(y[k] - ref) / 2.220446049250313e-16
                                              : UlpDistance(y[k], ref);
        worst = std::max(worst, d);
      }
    }
    EXPECT_LE(worst, c.max_ulp) << c.name;
  }
}

TEST(Packet, SpecialValues) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(sin(Packet(0.0))[0], 0.0);
  EXPECT_TRUE(std::signbit(sin(Packet(-0.0))[0]));
  EXPECT_EQ(cos(Packet(0.0))[0], 1.0);
  EXPECT_EQ(exp(Packet(0.0))[0], 1.0);
  EXPECT_EQ(exp(Packet(-800.0))[0], 0.0);
  EXPECT_EQ(exp(Packet(800.0))[0], inf);
  EXPECT_EQ(exp(Packet(-inf))[0], 0.0);
  EXPECT_TRUE(std::isnan(sin(Packet(inf))[0]));
  EXPECT_TRUE(std::isnan(cos(Packet(nan))[0]));
  EXPECT_TRUE(std::isnan(exp(Packet(nan))[0]));
}

TEST(Packet, LanewiseFunctionsAreTheCLibrarys) {
  const std::vector<double> a = Grid(0.1, 9.0, 37), b = Grid(-3.0, 4.0, 41);
  for (size_t i = 0; i < a.size(); ++i) {
    const Packet x = Load(a, i), y = Load(b, i);
    const Packet l = log(x), t = tanh(y), p = pow(x, y), q = atan2(y, x), tn = tan(y);
    for (int k = 0; k < kPacketWidth; ++k) {
      const double s = a[(i + k) % a.size()], u = b[(i + k) % b.size()];
      EXPECT_EQ(l[k], std::log(s));
      EXPECT_EQ(t[k], std::tanh(u));
      EXPECT_EQ(p[k], std::pow(s, u));
      EXPECT_EQ(q[k], std::atan2(u, s));
      EXPECT_EQ(tn[k], std::tan(u));
    }
  }
}

}  // namespace
}  // namespace estlab::testing
