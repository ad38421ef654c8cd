// Double inverted pendulum on a cart (models/dipc.h), issue "done when" item
// 5: the right-hand side against an independent Eigen LDLT solve of
// D q'' = H u - C q' - G, and conservation of energy and horizontal momentum
// with u = 0 under CVODES.
#include "models/dipc.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "src/ode/transition.h"

namespace estlab {
namespace {

using models::Dipc;
using State = Vec<double, 6>;

void Report(const char* name, double value) {
  std::printf("[ measured ] %s = %.4g\n", name, value);
  ::testing::Test::RecordProperty(name, std::to_string(value));
}

// Bogdanov (2004) with uniform rods, written out from the parameters (not
// from Dipc::Coeffs): rod i has mass mi, length Li, centre of mass at Li/2
// and inertia mi Li^2 / 12 about it.
State IndependentRhs(const State& s, double u, const Dipc::Params& p) {
  const double l1 = p.L1 / 2, l2 = p.L2 / 2;
  const double I1 = p.m1 * p.L1 * p.L1 / 12, I2 = p.m2 * p.L2 * p.L2 / 12;
  const double d1 = p.m0 + p.m1 + p.m2;
  const double d2 = p.m1 * l1 + p.m2 * p.L1;
  const double d3 = p.m2 * l2;
  const double d4 = p.m1 * l1 * l1 + p.m2 * p.L1 * p.L1 + I1;
  const double d5 = p.m2 * p.L1 * l2;
  const double d6 = p.m2 * l2 * l2 + I2;
  const double f1 = (p.m1 * l1 + p.m2 * p.L1) * p.g;
  const double f2 = p.m2 * l2 * p.g;
  const double th1 = s(2), th2 = s(4);
  const Eigen::Vector3d qd(s(1), s(3), s(5));
  Eigen::Matrix3d D;
  D << d1, d2 * std::cos(th1), d3 * std::cos(th2),       //
      d2 * std::cos(th1), d4, d5 * std::cos(th1 - th2),  //
      d3 * std::cos(th2), d5 * std::cos(th1 - th2), d6;
  Eigen::Matrix3d C;
  C << 0, -d2 * std::sin(th1) * qd(1), -d3 * std::sin(th2) * qd(2),  //
      0, 0, d5 * std::sin(th1 - th2) * qd(2),                        //
      0, -d5 * std::sin(th1 - th2) * qd(1), 0;
  const Eigen::Vector3d G(0, -f1 * std::sin(th1), -f2 * std::sin(th2));
  const Eigen::Vector3d H(1, 0, 0);
  const Eigen::Vector3d qdd = D.ldlt().solve(H * u - C * qd - G);
  State f;
  f << s(1), qdd(0), s(3), qdd(1), s(5), qdd(2);
  return f;
}

TEST(DipcModel, RhsMatchesEigenLdltSolve) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-3.14, 3.14), rate(-4.0, 4.0), input(-10.0, 10.0),
      param(0.3, 2.0);
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Dipc::Params p;
    if (trial % 2 == 1) {
      p.m0 = param(rng);
      p.m1 = param(rng);
      p.m2 = param(rng);
      p.L1 = param(rng);
      p.L2 = param(rng);
    }
    State x;
    x << rate(rng), rate(rng), angle(rng), rate(rng), angle(rng), rate(rng);
    double u = input(rng);
    if (u == 0.0) u = 1.0;
    const State f = Dipc::Rhs(0.0, x, u, p);
    const State g = IndependentRhs(x, u, p);
    const double err = (f - g).cwiseAbs().maxCoeff() / std::max(1.0, g.cwiseAbs().maxCoeff());
    worst = std::max(worst, err);
    ASSERT_LT(err, 1e-12) << "x = " << x.transpose() << " u = " << u << "\nrhs = " << f.transpose()
                          << "\nldlt = " << g.transpose();
  }
  Report("dipc_rhs_vs_ldlt_max_rel_err", worst);
}

TEST(DipcModel, CvodesConservesEnergyAndMomentumWithZeroInput) {
  Dipc::Params p;
  const auto k = Dipc::Coeffs(p);
  State x0;
  x0 << 0.0, 0.0, 0.3, 0.0, -0.2, 0.0;
  const Vec<double, 2> inv0 = Dipc::Invariants(x0, p);
  EXPECT_EQ(inv0(1), 0.0);                                 // momentum starts at 0
  auto tr = MakeTransition<Dipc>(p, TransitionOptions{});  // Adams, rtol 1e-10, atol 1e-12
  tr->SetInput(0.0);
  State x = x0;
  double energy_drift = 0, max_momentum = 0, max_v = 0, max_angle_change = 0;
  for (int i = 0; i < 500; ++i) {
    x = tr->Step(x, i * 0.01, (i + 1) * 0.01);
    const Vec<double, 2> inv = Dipc::Invariants(x, p);
    energy_drift = std::max(energy_drift, std::abs(inv(0) - inv0(0)) / inv0(0));
    max_momentum = std::max(max_momentum, std::abs(inv(1)));
    max_v = std::max(max_v, std::abs(x(1)));
    max_angle_change = std::max(max_angle_change, std::abs(x(2) - x0(2)));
  }
  // Momentum is 0 at the start, so its drift is measured against the
  // characteristic momentum d1 max|v| of the run (cart mass times its
  // largest speed).
  const double momentum_scale = k.d1 * max_v;
  Report("dipc_energy_rel_drift_5s", energy_drift);
  Report("dipc_momentum_abs_drift_5s", max_momentum);
  Report("dipc_momentum_scale_d1_max_v", momentum_scale);
  Report("dipc_momentum_rel_drift_5s", max_momentum / momentum_scale);
  EXPECT_GT(max_v, 0.1);             // the cart really moves
  EXPECT_GT(max_angle_change, 1.0);  // the rods really fall over
  EXPECT_LT(energy_drift, 1e-8);
  EXPECT_LT(max_momentum / momentum_scale, 1e-8);
}

}  // namespace
}  // namespace estlab
