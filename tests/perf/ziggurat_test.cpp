// The particle filter's ziggurat normal sampler (src/filters/ziggurat.h):
// deterministic per seed, and N(0, 1) by its moments and its distribution
// function at a few points (including the tail beyond the base layer).
#include "src/filters/ziggurat.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

namespace estlab {
namespace {

TEST(ZigguratNormal, SameSeedSameNumbersDifferentSeedDifferentNumbers) {
  const ZigguratNormal& normal = ZigguratNormal::Get();
  Rng a(5), b(5), c(6);
  int differ = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x = normal(a), y = normal(b), z = normal(c);
    EXPECT_EQ(x, y);
    differ += x != z;
  }
  EXPECT_GT(differ, 990);
}

TEST(ZigguratNormal, MomentsAndDistributionFunctionOfTheStandardNormal) {
  const ZigguratNormal& normal = ZigguratNormal::Get();
  Rng rng(42);
  constexpr int kDraws = 2000000;
  const std::array<double, 7> points = {-3.6, -2.0, -0.5, 0.0, 0.7, 2.5, 3.6};
  std::array<long, 7> below{};
  double sum = 0.0, sum2 = 0.0, sum3 = 0.0, sum4 = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    const double x = normal(rng);
    ASSERT_TRUE(std::isfinite(x));
    sum += x;
    sum2 += x * x;
    sum3 += x * x * x;
    sum4 += x * x * x * x;
    for (size_t k = 0; k < points.size(); ++k) below[k] += x < points[k];
  }
  const double n = kDraws;
  // Standard errors: mean 1/sqrt(n), variance sqrt(2/n), skewness sqrt(15/n),
  // kurtosis sqrt(96/n); the bounds are about 5 of them.
  EXPECT_NEAR(sum / n, 0.0, 5.0 / std::sqrt(n));
  EXPECT_NEAR(sum2 / n, 1.0, 5.0 * std::sqrt(2.0 / n));
  EXPECT_NEAR(sum3 / n, 0.0, 5.0 * std::sqrt(15.0 / n));
  EXPECT_NEAR(sum4 / n, 3.0, 5.0 * std::sqrt(96.0 / n));
  for (size_t k = 0; k < points.size(); ++k) {
    const double p = 0.5 * std::erfc(-points[k] / std::sqrt(2.0));
    EXPECT_NEAR(below[k] / n, p, 5.0 * std::sqrt(p * (1 - p) / n) + 1e-7)
        << "P(X < " << points[k] << ")";
  }
}

}  // namespace
}  // namespace estlab
