// FixedPropagatePoints (src/ode/packet_propagate.h): every built-in model
// moved kPacketWidth points per call agrees with the one-point FixedPropagate
// of the same points (to rounding of sin / cos, bit for bit for a model
// without them), for every fixed-step integrator and for point counts that
// are not a multiple of the width; a point's result does not depend on the
// points beside it; and only FixedStepTransition::StepCloud takes this path.
#include "src/ode/packet_propagate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <type_traits>

#include "models/cart_pole.h"
#include "models/dipc.h"
#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "models/van_der_pol.h"
#include "src/core/random.h"
#include "src/ode/transition_impl.h"

namespace estlab::testing {
namespace {

template <class Model>
using Points = Eigen::Matrix<double, Model::kStateDim, Eigen::Dynamic>;

template <class Model>
Points<Model> RandomPoints(int count, uint64_t seed) {
  Rng rng(seed);
  Points<Model> x(Model::kStateDim, count);
  for (int j = 0; j < count; ++j)
    for (int i = 0; i < Model::kStateDim; ++i) x(i, j) = 2.0 * rng.Normal();
  return x;
}

// Largest |packet - scalar| / max(1, |scalar|) over the points.
template <class Model>
double PacketVsScalar(Integrator scheme, int count) {
  const typename Model::Params p;
  const Points<Model> x = RandomPoints<Model>(count, 42 + count);
  Points<Model> packed(Model::kStateDim, count);
  FixedPropagatePoints<Model>(scheme, x, 0.3, 0.35, 3, 0.7, p, &packed);
  double worst = 0.0;
  for (int j = 0; j < count; ++j) {
    const Vec<double, Model::kStateDim> one = FixedPropagate<Model, double>(
        scheme, Vec<double, Model::kStateDim>(x.col(j)), 0.3, 0.35, 3, 0.7, p);
    for (int i = 0; i < Model::kStateDim; ++i)
      worst = std::max(worst, std::abs(packed(i, j) - one(i)) / std::max(1.0, std::abs(one(i))));
  }
  return worst;
}

template <class Model>
void ExpectAgreement(double tolerance) {
  static_assert(kPacketModel<Model>);
  for (Integrator scheme : {Integrator::kEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4})
    for (int count : {1, kPacketWidth - 1, kPacketWidth, 2 * kPacketWidth + 1, 257}) {
      if (count < 1) continue;
      EXPECT_LE(PacketVsScalar<Model>(scheme, count), tolerance)
          << Model::kName << " " << IntegratorName(scheme) << " " << count << " points";
    }
}

TEST(PacketPropagate, EveryBuiltInModelAgreesWithOnePointAtATime) {
  // sin / cos differ from the C library's in the last bit at most: a few
  // 1e-16 after the three RK4 steps.
  ExpectAgreement<models::Pendulum>(1e-14);
  ExpectAgreement<models::DoublePendulum>(1e-14);
  ExpectAgreement<models::CartPole>(1e-14);
  ExpectAgreement<models::Dipc>(1e-14);
  ExpectAgreement<models::VanDerPol>(0.0);  // arithmetic only: bit for bit
}

TEST(PacketPropagate, APointsResultDoesNotDependOnItsNeighbours) {
  using Model = models::DoublePendulum;
  const Model::Params p;
  const Points<Model> x = RandomPoints<Model>(11, 7);
  Points<Model> all(4, 11);
  FixedPropagatePoints<Model>(Integrator::kRk4, x, 0.0, 0.01, 1, 0.0, p, &all);
  for (int j = 0; j < 11; ++j) {
    Points<Model> alone(4, 1);
    FixedPropagatePoints<Model>(Integrator::kRk4, Points<Model>(x.col(j)), 0.0, 0.01, 1, 0.0, p,
                                &alone);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(alone(i, 0), all(i, j)) << "point " << j;
  }
}

// The pendulum with a count of its right-hand-side calls per scalar type.
template <bool kPacket>
struct CountingPendulum : models::Pendulum {
  static constexpr bool kPacketRhs = kPacket;
  static inline int packet_calls = 0, double_calls = 0;
  template <class T, class P>
  static Vec<T, 2> Rhs(const T& t, const Vec<T, 2>& x, double u, const P& p) {
    if constexpr (std::is_same_v<T, Packet>) ++packet_calls;
    if constexpr (std::is_same_v<T, double>) ++double_calls;
    return models::Pendulum::Rhs(t, x, u, p);
  }
};

template <bool kPacket>
void StepNinePoints(bool cloud) {
  using Model = CountingPendulum<kPacket>;
  TransitionOptions options;
  options.integrator = Integrator::kRk4;
  options.substeps = 2;
  auto transition = MakeTransition<Model>(typename Model::Params{}, options);
  const Points<Model> x = RandomPoints<Model>(9, 3);
  Points<Model> stepped(2, 9);
  Model::packet_calls = Model::double_calls = 0;
  if (cloud)
    transition->StepCloud(x, 0.0, 0.02, &stepped);
  else
    transition->StepPoints(x, 0.0, 0.02, &stepped);
}

// StepCloud (particles) moves a packet model's points in packets; StepPoints
// (sigma points) and every other model keep one scalar call per point.
TEST(PacketPropagate, OnlyStepCloudOfAPacketModelTakesThePacketPath) {
  StepNinePoints<true>(true);  // ceil(9 / width) packets x 2 RK4 steps x 4 stages
  EXPECT_EQ(CountingPendulum<true>::packet_calls, (9 + kPacketWidth - 1) / kPacketWidth * 8);
  EXPECT_EQ(CountingPendulum<true>::double_calls, 0);
  StepNinePoints<true>(false);  // 9 points x 2 x 4
  EXPECT_EQ(CountingPendulum<true>::packet_calls, 0);
  EXPECT_EQ(CountingPendulum<true>::double_calls, 72);
  StepNinePoints<false>(true);
  EXPECT_EQ(CountingPendulum<false>::packet_calls, 0);
  EXPECT_EQ(CountingPendulum<false>::double_calls, 72);
}

}  // namespace
}  // namespace estlab::testing
