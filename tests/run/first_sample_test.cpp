// x0 = first-sample (src/run/first_sample.h): each dataset's prior mean is its
// first finite measurement of every state an output of the same name
// measures; the other states keep the spec's x0.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "src/run/first_sample.h"

namespace estlab {
namespace {

using Angle = models::Pendulum::Angle;
using Sin = models::Pendulum::Sin;

Vec<double, 2> Prior(const FilterSpec& spec, const FilterData& d, bool sin = false) {
  return sin ? PriorMean<models::Pendulum, Sin>(spec, d)
             : PriorMean<models::Pendulum, Angle>(spec, d);
}

TEST(FirstSample, TakesTheFirstFiniteMeasurementOfEachMeasuredState) {
  FilterSpec spec;
  spec.x0 = {0.3, -2.0};
  FilterData d;
  d.m = 1;
  d.t = {0.0, 0.1, 0.2};
  d.z = {std::nan(""), 1.25, 1.5};
  // Off: the spec's x0.
  EXPECT_EQ(Prior(spec, d), (Vec<double, 2>(0.3, -2.0)));
  spec.x0_first_sample = true;
  // theta from the first finite z_theta; omega is not measured: the spec's.
  EXPECT_EQ(Prior(spec, d), (Vec<double, 2>(1.25, -2.0)));
  // sin(theta) is not a state: nothing is taken.
  EXPECT_EQ(Prior(spec, d, true), (Vec<double, 2>(0.3, -2.0)));
}

TEST(FirstSample, EachOutputOfATwoAngleMeasurement) {
  using DP = models::DoublePendulum;
  FilterSpec spec;
  spec.x0 = {0.0, 0.0, 0.0, 0.0};
  spec.x0_first_sample = true;
  FilterData d;
  d.m = 2;
  d.t = {0.0, 0.1};
  d.z = {0.5, std::nan(""), 0.6, -0.7};
  const Vec<double, 4> x0 = PriorMean<DP, DP::Angles>(spec, d);
  EXPECT_EQ(x0(0), 0.5);   // theta1
  EXPECT_EQ(x0(1), 0.0);   // omega1
  EXPECT_EQ(x0(2), -0.7);  // theta2: the first finite z_theta2
  EXPECT_EQ(x0(3), 0.0);   // omega2
}

}  // namespace
}  // namespace estlab
