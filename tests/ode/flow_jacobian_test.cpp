// Flow Jacobians of the transitions for all five models (issue "done when"
// item 2): the CVODES forward-sensitivity Jacobian against central
// differences of CVODES solutions, and the AD Jacobians of the fixed-step maps
// (euler, semi-implicit-euler, rk4 with 1 and 3 substeps) against central
// differences of the same maps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "models/cart_pole.h"
#include "models/dipc.h"
#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "models/van_der_pol.h"
#include "src/ode/transition.h"

namespace estlab {
namespace {

void Report(const std::string& name, double value) {
  std::printf("[ measured ] %s = %.3g\n", name.c_str(), value);
  ::testing::Test::RecordProperty(name, std::to_string(value));
}

// Central differences of x0 -> Step(x0, 0, dt), one fresh transition per
// solve so every solve starts from the same solver state; perturbation
// 1e-6 max(1, |x_j|).
template <class Model>
Mat<Model::kStateDim, Model::kStateDim> CentralDifferences(const typename Model::Params& p,
                                                           const TransitionOptions& options,
                                                           const Vec<double, Model::kStateDim>& x,
                                                           double u, double dt) {
  constexpr int N = Model::kStateDim;
  auto solve = [&](const Vec<double, N>& x0) {
    auto tr = MakeTransition<Model>(p, options);
    tr->SetInput(u);
    return tr->Step(x0, 0.0, dt);
  };
  Mat<N, N> F;
  for (int j = 0; j < N; ++j) {
    const double eps = 1e-6 * std::max(1.0, std::abs(x(j)));
    Vec<double, N> xp = x, xm = x;
    xp(j) += eps;
    xm(j) -= eps;
    F.col(j) = (solve(xp) - solve(xm)) / (2.0 * eps);
  }
  return F;
}

// max |F - F_fd| / max |F|.
template <int N>
double RelativeError(const Mat<N, N>& F, const Mat<N, N>& F_fd) {
  return (F - F_fd).cwiseAbs().maxCoeff() / F.cwiseAbs().maxCoeff();
}

TransitionOptions TightCvodes() {
  TransitionOptions o;
  o.integrator = Integrator::kCvodes;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  return o;
}

// CVODES sensitivities (tight tolerances, and the default 1e-10 / 1e-12 the
// filters use) against central differences of tight CVODES solutions.
template <class Model>
void CheckCvodes(const std::string& label, const typename Model::Params& p,
                 const Vec<double, Model::kStateDim>& x, double u, double dt) {
  constexpr int N = Model::kStateDim;
  SCOPED_TRACE(label + " dt=" + std::to_string(dt));
  const Mat<N, N> F_fd = CentralDifferences<Model>(p, TightCvodes(), x, u, dt);
  for (const bool tight : {true, false}) {
    TransitionOptions o = tight ? TightCvodes() : TransitionOptions{};
    auto tr = MakeTransition<Model>(p, o);
    tr->SetInput(u);
    Mat<N, N> F;
    const Vec<double, N> x1 = tr->StepWithJacobian(x, 0.0, dt, &F);
    ASSERT_TRUE(F.allFinite());
    // The state from the sensitivity run is the state of a plain run.
    auto plain = MakeTransition<Model>(p, o);
    plain->SetInput(u);
    EXPECT_LT((x1 - plain->Step(x, 0.0, dt)).cwiseAbs().maxCoeff(),
              100 * o.rtol * std::max(1.0, x1.cwiseAbs().maxCoeff()));
    const double err = RelativeError<N>(F, F_fd);
    Report(label + (tight ? " cvodes(1e-12) " : " cvodes(1e-10) ") + "dt=" + std::to_string(dt) +
               " jacobian rel err",
           err);
    EXPECT_LT(err, 1e-6) << "F =\n" << F << "\ncentral differences =\n" << F_fd;
    // Not the identity: the comparison has something to compare.
    EXPECT_GT((F - Mat<N, N>::Identity()).cwiseAbs().maxCoeff(), 1e-4);
  }
}

// AD through the fixed-step map against central differences of the same map.
template <class Model>
void CheckFixedStep(const std::string& label, const typename Model::Params& p,
                    const Vec<double, Model::kStateDim>& x, double u, double dt) {
  constexpr int N = Model::kStateDim;
  for (const Integrator scheme :
       {Integrator::kEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4}) {
    for (const int substeps : {1, 3}) {
      if (scheme != Integrator::kRk4 && substeps != 1) continue;
      const std::string name = label + " " + IntegratorName(scheme) + "x" +
                               std::to_string(substeps) + " dt=" + std::to_string(dt);
      SCOPED_TRACE(name);
      TransitionOptions o;
      o.integrator = scheme;
      o.substeps = substeps;
      auto tr = MakeTransition<Model>(p, o);
      tr->SetInput(u);
      Mat<N, N> F;
      const Vec<double, N> x1 = tr->StepWithJacobian(x, 0.0, dt, &F);
      ASSERT_TRUE(F.allFinite());
      // Same map as Step() up to rounding (Jet arithmetic may round differently).
      EXPECT_LT((x1 - tr->Step(x, 0.0, dt)).cwiseAbs().maxCoeff(),
                1e-14 * std::max(1.0, x1.cwiseAbs().maxCoeff()));
      const Mat<N, N> F_fd = CentralDifferences<Model>(p, o, x, u, dt);
      ASSERT_TRUE(F_fd.allFinite());
      const double err = RelativeError<N>(F, F_fd);
      Report(name + " AD jacobian rel err", err);
      EXPECT_LT(err, 1e-8) << "F =\n" << F << "\ncentral differences =\n" << F_fd;
    }
  }
}

template <class Model>
void CheckAll(const std::string& label, const typename Model::Params& p,
              const Vec<double, Model::kStateDim>& x, double u) {
  for (const double dt : {0.01, 0.1}) {
    CheckCvodes<Model>(label, p, x, u, dt);
    CheckFixedStep<Model>(label, p, x, u, dt);
  }
}

TEST(OdeFlowJacobian, Pendulum) {
  models::Pendulum::Params p;
  CheckAll<models::Pendulum>("pendulum", p, Vec<double, 2>(0.7, 0.3), 0.0);
  p.b = 0.5;  // damped too
  CheckAll<models::Pendulum>("pendulum(b=0.5)", p, Vec<double, 2>(0.7, 0.3), 0.0);
}

TEST(OdeFlowJacobian, DoublePendulum) {
  models::DoublePendulum::Params p;
  CheckAll<models::DoublePendulum>("double-pendulum", p, Vec<double, 4>(1.0, 0.5, -0.5, 1.2), 0.0);
}

TEST(OdeFlowJacobian, CartPole) {
  models::CartPole::Params p;
  CheckAll<models::CartPole>("cart-pole", p, Vec<double, 4>(0.1, 0.2, 3.0, -0.3), 0.1);
}

TEST(OdeFlowJacobian, Dipc) {
  models::Dipc::Params p;
  Vec<double, 6> x;
  x << 0.1, -0.2, 0.3, 0.4, -0.2, -0.5;
  CheckAll<models::Dipc>("dipc", p, x, 0.1);
}

// mu = 1000 from (2, 0): the fast transient onto the slow manifold (time
// constant 1 / (mu (x^2 - 1)) = 3.3e-4 s) is over well within dt = 0.01, so
// the flow map is smooth but strongly contracting; CVODES uses BDF (the
// default for stiff models).
TEST(OdeFlowJacobian, VanDerPolStiff) {
  models::VanDerPol::Params p;
  ASSERT_EQ(p.mu, 1000.0);
  for (const double dt : {0.01, 0.1})
    CheckCvodes<models::VanDerPol>("van-der-pol", p, Vec<double, 2>(2.0, 0.0), 0.0, dt);
  // The fixed-step maps at dt = 0.01 and 0.1 are far outside RK4's stability
  // region (h |lambda| = 30..300, lambda ~ -mu (x^2 - 1) = -3000): RK4 with 3
  // substeps overflows at dt = 0.1 and amplifies by ~(h lambda)^4 / 24 per
  // step otherwise, so central differences of those maps lose ~1e-7 to
  // cancellation (measured 2e-7 for rk4 dt = 0.1 and 8e-7 for rk4x3 dt =
  // 0.01) while the AD derivative stays exact. The fixed-step check of the
  // stiff model therefore uses steps a filter could use with it, h |lambda|
  // = 0.3 and 1.5 (the non-stiff test below covers dt = 0.01 and 0.1).
  for (const double dt : {1e-4, 5e-4})
    CheckFixedStep<models::VanDerPol>("van-der-pol", p, Vec<double, 2>(2.0, 0.0), 0.0, dt);
}

TEST(OdeFlowJacobian, VanDerPolNonStiff) {
  models::VanDerPol::Params p;
  p.mu = 1.0;
  CheckAll<models::VanDerPol>("van-der-pol(mu=1)", p, Vec<double, 2>(2.0, 0.0), 0.0);
}

}  // namespace
}  // namespace estlab
