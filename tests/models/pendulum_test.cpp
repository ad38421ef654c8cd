// Simple pendulum (models/pendulum.h), issue "done when" item 3: the small-
// angle solution theta0 cos(sqrt(g/L) t) and the exact Jacobi-elliptic
// solution theta(t) = 2 asin(k cd(sqrt(g/L) t, k)), k = sin(theta0 / 2).
//
// At theta0 = 0.01 the nonlinear period is longer by theta0^2/16 = 6.25e-6
// (relative), so after omega0 t = 31.3 rad (10 s) the phase lag is ~1.96e-4
// rad and the linear solution is off by up to ~1.96e-4 theta0: the linear
// comparison holds to 1e-4 only for the first ~5 s. The exact elliptic
// solution is the 1e-4 reference over the full 10 s (CVODES matches it far
// more closely).
#include "models/pendulum.h"

#include <gtest/gtest.h>

#include <boost/math/special_functions/jacobi_elliptic.hpp>
#include <cmath>
#include <cstdio>

#include "src/ode/transition.h"

namespace estlab {
namespace {

using models::Pendulum;

void Report(const char* name, double value) {
  std::printf("[ measured ] %s = %.4g\n", name, value);
  ::testing::Test::RecordProperty(name, std::to_string(value));
}

// Exact solution released from rest at theta0.
double ExactTheta(double theta0, double omega0, double t) {
  const double k = std::sin(0.5 * theta0);
  double cn = 0, dn = 0;
  const double sn = boost::math::jacobi_elliptic(k, omega0 * t, &cn, &dn);
  (void)sn;
  return 2.0 * std::asin(k * cn / dn);
}

TEST(PendulumModel, SmallAngleMatchesLinearAndEllipticSolutions) {
  Pendulum::Params p;  // g = 9.81, L = 1, b = 0
  const double theta0 = 0.01;
  const double omega0 = std::sqrt(p.g / p.L);
  TransitionOptions o;  // CVODES, rtol 1e-10, atol 1e-12
  auto tr = MakeTransition<Pendulum>(p, o);
  Vec<double, 2> x(theta0, 0.0);
  double linear_err = 0, linear_err_5s = 0, exact_err = 0;
  for (int k = 0; k < 1000; ++k) {
    const double t = (k + 1) * 0.01;
    x = tr->Step(x, k * 0.01, t);
    const double lin = std::abs(x(0) - theta0 * std::cos(omega0 * t)) / theta0;
    linear_err = std::max(linear_err, lin);
    if (t <= 5.0) linear_err_5s = std::max(linear_err_5s, lin);
    exact_err = std::max(exact_err, std::abs(x(0) - ExactTheta(theta0, omega0, t)) / theta0);
  }
  Report("pendulum_linear_rel_err_5s", linear_err_5s);
  Report("pendulum_linear_rel_err_10s", linear_err);
  Report("pendulum_exact_rel_err_10s", exact_err);
  EXPECT_LT(linear_err_5s, 1e-4);
  // The linear solution drifts by the nonlinear phase lag, predicted max
  // omega0 * 10 * theta0^2 / 16 = 1.96e-4: more than 1e-4 but no more.
  const double predicted = omega0 * 10.0 * theta0 * theta0 / 16.0;
  EXPECT_GT(linear_err, 0.8 * predicted);
  EXPECT_LT(linear_err, 1.2 * predicted);
  // Against the exact solution CVODES holds 1e-4 with a wide margin.
  EXPECT_LT(exact_err, 1e-6);
}

TEST(PendulumModel, EllipticReferenceIsTheNonlinearPendulum) {
  // Sanity of the reference itself: theta(0) = theta0 and the period
  // 4 K(k) / omega0 against the series 2 pi / omega0 (1 + theta0^2/16 + ...).
  const double theta0 = 0.5, omega0 = 2.0;
  EXPECT_NEAR(ExactTheta(theta0, omega0, 0.0), theta0, 1e-15);
  const double k = std::sin(0.5 * theta0);
  const double K = std::comp_ellint_1(k);
  EXPECT_NEAR(ExactTheta(theta0, omega0, 4.0 * K / omega0), theta0, 1e-12);
  EXPECT_NEAR(ExactTheta(theta0, omega0, 2.0 * K / omega0), -theta0, 1e-12);
  EXPECT_NEAR(4.0 * K / (2.0 * 3.14159265358979323846),
              1.0 + theta0 * theta0 / 16.0 + 11.0 * std::pow(theta0, 4) / 3072.0, 1e-5);
}

TEST(PendulumModel, DampedEnergyDecaysUndampedIsConserved) {
  Pendulum::Params p;
  auto tr = MakeTransition<Pendulum>(p, TransitionOptions{});
  const Vec<double, 2> x0(2.5, 0.0);
  const double e0 = Pendulum::Invariants(x0, p)(0);
  Vec<double, 2> x = x0;
  double drift = 0;
  for (int k = 0; k < 1000; ++k) {
    x = tr->Step(x, k * 0.01, (k + 1) * 0.01);
    drift = std::max(drift, std::abs(Pendulum::Invariants(x, p)(0) - e0) / e0);
  }
  Report("pendulum_theta0_2.5_cvodes_energy_drift_10s", drift);
  EXPECT_LT(drift, 1e-8);

  p.b = 0.3;
  auto damped = MakeTransition<Pendulum>(p, TransitionOptions{});
  x = damped->Step(x0, 0.0, 10.0);
  EXPECT_LT(Pendulum::Invariants(x, p)(0), 0.2 * e0);
}

}  // namespace
}  // namespace estlab
