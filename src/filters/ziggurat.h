// Standard normal draws by the ziggurat method (Marsaglia & Tsang 2000, with
// Doornik's 2005 correction: the layer index and the uniform come from
// disjoint bits of one 64-bit draw), for the particle filter's many draws per
// step. About 99% of draws cost one generator call, a multiply and a compare,
// against two uniforms, a log, a sqrt and a division per pair (with 21%
// rejections) for the polar method of Rng::Normal.
//
// Usage:
//   Rng rng(seed);
//   const ZigguratNormal& normal = ZigguratNormal::Get();
//   double z = normal(rng);          // N(0, 1)
//
// Deterministic like Rng: the same seed gives the same numbers (the tables
// are computed once from exp / log / sqrt, as the polar method uses log and
// sqrt). The sequence is NOT the one of Rng::Normal.
#ifndef ESTLAB_FILTERS_ZIGGURAT_H_
#define ESTLAB_FILTERS_ZIGGURAT_H_

#include <cmath>
#include <cstdint>

#include "src/core/random.h"

namespace estlab {

class ZigguratNormal {
 public:
  static constexpr int kLayers = 128;

  // The tables, computed on first use (thread-safe static initialisation).
  static const ZigguratNormal& Get() {
    static const ZigguratNormal tables;
    return tables;
  }

  double operator()(Rng& rng) const {
    for (;;) {
      const uint64_t bits = rng.Next();
      const int i = int(bits & (kLayers - 1));                      // low 7 bits: layer
      const double u = 2.0 * double(bits >> 11) * 0x1.0p-53 - 1.0;  // top 53 bits: [-1, 1)
      if (std::abs(u) < ratio_[i]) return u * x_[i];                // inside the layer's rectangle
      if (i == 0) return Tail(rng, u < 0.0);
      // The wedge between the rectangle and the density.
      const double x = u * x_[i];
      const double f0 = std::exp(-0.5 * (x_[i] * x_[i] - x * x));
      const double f1 = std::exp(-0.5 * (x_[i + 1] * x_[i + 1] - x * x));
      if (f1 + rng.Uniform() * (f0 - f1) < 1.0) return x;
    }
  }

 private:
  static constexpr double kR = 3.442619855899;       // start of the tail
  static constexpr double kV = 9.91256303526217e-3;  // area of each layer

  ZigguratNormal() {
    double f = std::exp(-0.5 * kR * kR);
    x_[0] = kV / f;  // the base layer includes the tail
    x_[1] = kR;
    x_[kLayers] = 0.0;
    for (int i = 2; i < kLayers; ++i) {
      x_[i] = std::sqrt(-2.0 * std::log(kV / x_[i - 1] + f));
      f = std::exp(-0.5 * x_[i] * x_[i]);
    }
    for (int i = 0; i < kLayers; ++i) ratio_[i] = x_[i + 1] / x_[i];
  }

  // Marsaglia's tail beyond kR: x = -log(U1) / R, y = -log(U2) until 2y > x^2.
  static double Tail(Rng& rng, bool negative) {
    double x, y;
    do {
      x = std::log(1.0 - rng.Uniform()) / kR;  // log of (0, 1]: <= 0
      y = std::log(1.0 - rng.Uniform());
    } while (-2.0 * y < x * x);
    return negative ? x - kR : kR - x;
  }

  double x_[kLayers + 1];
  double ratio_[kLayers];
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_ZIGGURAT_H_
