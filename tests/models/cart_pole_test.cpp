// Cart-pole (models/cart_pole.h): the right-hand side against an independent
// 2x2 solve of the paper-004 equations (issue item 5), and the linearisation
// about the upright position against STUDIES.md's A and B (issue item 6).
#include "models/cart_pole.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "src/ode/autodiff.h"
#include "src/ode/transition.h"

namespace estlab {
namespace {

using models::CartPole;
using State = Vec<double, 4>;
constexpr double kPi = 3.14159265358979323846;

void Report(const char* name, double value) {
  std::printf("[ measured ] %s = %.4g\n", name, value);
  ::testing::Test::RecordProperty(name, std::to_string(value));
}

//   (M + m) x'' + b x' + m l theta'' cos(theta) - m l theta'^2 sin(theta) = F
//   (I + m l^2) theta'' + m g l sin(theta) = -m l x'' cos(theta)
State IndependentRhs(const State& s, double F, const CartPole::Params& p) {
  const double v = s(1), th = s(2), w = s(3);
  Eigen::Matrix2d A;
  A << p.M + p.m, p.m * p.l * std::cos(th),  //
      p.m * p.l * std::cos(th), p.I + p.m * p.l * p.l;
  const Eigen::Vector2d r(F - p.b * v + p.m * p.l * w * w * std::sin(th),
                          -p.m * p.g * p.l * std::sin(th));
  const Eigen::Vector2d acc = A.fullPivLu().solve(r);
  return State(v, acc(0), w, acc(1));
}

TEST(CartPoleModel, RhsMatchesTwoByTwoSolve) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-kPi, kPi), rate(-5.0, 5.0), input(-10.0, 10.0),
      param(0.2, 2.0);
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    CartPole::Params p;
    if (trial % 2 == 1) {
      p.M = param(rng);
      p.m = param(rng);
      p.b = param(rng);
      p.I = param(rng);
      p.l = param(rng);
      p.g = 9.81;
    }
    const State x(rate(rng), rate(rng), angle(rng), rate(rng));
    double u = input(rng);
    if (u == 0.0) u = 1.0;
    const State f = CartPole::Rhs(0.0, x, u, p);
    const State g = IndependentRhs(x, u, p);
    const double err = (f - g).cwiseAbs().maxCoeff() / std::max(1.0, g.cwiseAbs().maxCoeff());
    worst = std::max(worst, err);
    ASSERT_LT(err, 1e-12) << "x = " << x.transpose() << " u = " << u;
  }
  Report("cart_pole_rhs_vs_2x2_max_rel_err", worst);
}

// STUDIES.md, linearisation about theta = pi (upright), p = I (M+m) + M m l^2.
void ExpectedLinearisation(const CartPole::Params& c, Mat<4, 4>* A, Vec<double, 4>* B) {
  const double p = c.I * (c.M + c.m) + c.M * c.m * c.l * c.l;
  const double Iml2 = c.I + c.m * c.l * c.l;
  *A << 0, 1, 0, 0,                                            //
      0, -Iml2 * c.b / p, c.m * c.m * c.g * c.l * c.l / p, 0,  //
      0, 0, 0, 1,                                              //
      0, -c.m * c.l * c.b / p, c.m * c.g * c.l * (c.M + c.m) / p, 0;
  *B << 0, Iml2 / p, 0, c.m * c.l / p;
}

void CheckLinearisation(const CartPole::Params& p) {
  const State x_up(0.0, 0.0, kPi, 0.0);
  Mat<4, 4> A;
  const State f0 = ValueAndJacobian<4, 4>(
      [&](const auto& xj) {
        using T = typename std::decay_t<decltype(xj)>::Scalar;
        return CartPole::Rhs(T(0.0), xj, 0.0, p);
      },
      x_up, &A);
  EXPECT_LT(f0.cwiseAbs().maxCoeff(), 1e-14);  // an equilibrium (sin(pi) = 1.2e-16)
  const double h = 1e-6;
  const State B = (CartPole::Rhs(0.0, x_up, h, p) - CartPole::Rhs(0.0, x_up, -h, p)) / (2 * h);
  Mat<4, 4> A_expected;
  State B_expected;
  ExpectedLinearisation(p, &A_expected, &B_expected);
  EXPECT_LT((A - A_expected).cwiseAbs().maxCoeff(), 1e-12) << "A =\n"
                                                           << A << "\nexpected\n"
                                                           << A_expected;
  EXPECT_LT((B - B_expected).cwiseAbs().maxCoeff(), 1e-9)
      << "B = " << B.transpose() << "\nexpected " << B_expected.transpose();
}

TEST(CartPoleModel, LinearisationAboutUprightMatchesStudies) {
  CartPole::Params p;  // all constants 1: p = 3
  Mat<4, 4> A;
  State B;
  ExpectedLinearisation(p, &A, &B);
  Mat<4, 4> A_unit;
  A_unit << 0, 1, 0, 0, 0, -2.0 / 3, 1.0 / 3, 0, 0, 0, 0, 1, 0, -1.0 / 3, 2.0 / 3, 0;
  EXPECT_LT((A - A_unit).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LT((B - State(0, 2.0 / 3, 0, 1.0 / 3)).cwiseAbs().maxCoeff(), 1e-15);
  CheckLinearisation(p);
  // And away from unit constants (the CTMS example's values).
  CartPole::Params q;
  q.M = 0.5;
  q.m = 0.2;
  q.b = 0.1;
  q.I = 0.006;
  q.l = 0.3;
  q.g = 9.8;
  CheckLinearisation(q);
}

TEST(CartPoleModel, FrictionlessUnforcedConservesEnergyAndMomentum) {
  CartPole::Params p;
  p.b = 0.0;
  auto tr = MakeTransition<CartPole>(p, TransitionOptions{});
  const State x0(0.0, 0.5, 2.0, -1.0);
  const Vec<double, 2> inv0 = CartPole::Invariants(x0, p);
  State x = x0;
  Vec<double, 2> drift = Vec<double, 2>::Zero();
  for (int k = 0; k < 1000; ++k) {
    x = tr->Step(x, k * 0.01, (k + 1) * 0.01);
    drift = drift.cwiseMax(
        ((CartPole::Invariants(x, p) - inv0).cwiseAbs().array() / inv0.cwiseAbs().array())
            .matrix());
  }
  Report("cart_pole_energy_rel_drift_10s", drift(0));
  Report("cart_pole_momentum_rel_drift_10s", drift(1));
  EXPECT_LT(drift(0), 1e-8);
  EXPECT_LT(drift(1), 1e-8);
}

}  // namespace
}  // namespace estlab
