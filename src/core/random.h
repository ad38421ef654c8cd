// Deterministic random numbers, identical on every platform and standard
// library: SplitMix64 to derive seeds, xoshiro256** as the generator, and a
// Marsaglia polar normal sampler (std::normal_distribution is
// implementation-defined, so it is not used).
//
// Usage:
//   Rng rng(DeriveSeed(study_seed, scenario, run));
//   double z = rng.Normal();      // N(0, 1)
//   double u = rng.Uniform();     // [0, 1)
#ifndef ESTLAB_CORE_RANDOM_H_
#define ESTLAB_CORE_RANDOM_H_

#include <cmath>
#include <cstdint>
#include <initializer_list>

namespace estlab {

inline uint64_t SplitMix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A seed that depends only on the given integers (e.g. study seed, scenario,
// run), never on thread count or order.
inline uint64_t DeriveSeed(std::initializer_list<uint64_t> parts) {
  // h <- mix(h xor (odd * p + c)): mix is the bijective SplitMix64 finaliser,
  // so for a fixed prefix distinct parts always give distinct seeds.
  uint64_t h = 0x243F6A8885A308D3ull;
  for (uint64_t p : parts) {
    uint64_t z = h ^ (p * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    h = z ^ (z >> 31);
  }
  return h;
}

class Rng {
 public:
  explicit Rng(uint64_t seed) {
    uint64_t sm = seed;
    for (auto& s : s_) s = SplitMix64(sm);
  }
  uint64_t Next() {
    const uint64_t result = Rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = Rotl(s_[3], 45);
    return result;
  }
  // Uniform on [0, 1) with 53 random bits.
  double Uniform() { return double(Next() >> 11) * 0x1.0p-53; }
  // Standard normal (Marsaglia polar method).
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2.0 * Uniform() - 1.0;
      v = 2.0 * Uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double f = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return u * f;
  }

 private:
  static uint64_t Rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace estlab

#endif  // ESTLAB_CORE_RANDOM_H_
