// CvodesTransition behaviour: continuing steps, input changes between steps,
// statistics, method selection and failures.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "models/cart_pole.h"
#include "models/double_pendulum.h"
#include "models/van_der_pol.h"
#include "src/ode/transition.h"

namespace estlab {
namespace {

TEST(CvodesTransition, ManyContinuingStepsMatchOneLongStep) {
  models::DoublePendulum::Params p;
  auto stepped = MakeTransition<models::DoublePendulum>(p, TransitionOptions{});
  auto single = MakeTransition<models::DoublePendulum>(p, TransitionOptions{});
  const Vec<double, 4> x0(1.0, 0.0, 0.5, 0.0);
  Vec<double, 4> x = x0;
  for (int k = 0; k < 100; ++k) x = stepped->Step(x, k * 0.01, (k + 1) * 0.01);
  const Vec<double, 4> y = single->Step(x0, 0.0, 1.0);
  EXPECT_LT((x - y).cwiseAbs().maxCoeff(), 1e-8) << x.transpose() << "\n" << y.transpose();
  EXPECT_EQ(stepped->Name(), "cvodes-adams");
  // Continuing steps keep the step size: far fewer than 100 fresh starts.
  EXPECT_LT(stepped->stats().internal_steps, 3 * single->stats().internal_steps);
}

// A step that continues in time and state but with a new input must integrate
// [t0, t1] with the new input only.
TEST(CvodesTransition, InputChangeBetweenStepsTakesEffectAtT0) {
  models::CartPole::Params p;
  auto tr = MakeTransition<models::CartPole>(p, TransitionOptions{});
  const Vec<double, 4> x0(0.0, 0.0, 3.0, 0.0);
  Vec<double, 4> x = x0;
  tr->SetInput(0.0);
  for (int k = 0; k < 50; ++k) x = tr->Step(x, k * 0.01, (k + 1) * 0.01);
  const Vec<double, 4> x_half = x;
  tr->SetInput(2.0);
  for (int k = 50; k < 100; ++k) x = tr->Step(x, k * 0.01, (k + 1) * 0.01);

  auto fresh = MakeTransition<models::CartPole>(p, TransitionOptions{});
  fresh->SetInput(2.0);
  const Vec<double, 4> expected = fresh->Step(x_half, 0.5, 1.0);
  EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-8) << x.transpose() << "\n"
                                                        << expected.transpose();
}

TEST(CvodesTransition, StiffModelDefaultsToBdf) {
  models::VanDerPol::Params p;
  EXPECT_EQ(MakeTransition<models::VanDerPol>(p, TransitionOptions{})->Name(), "cvodes-bdf");
  TransitionOptions adams;
  adams.method = CvodesMethod::kAdams;
  EXPECT_EQ(MakeTransition<models::VanDerPol>(p, adams)->Name(), "cvodes-adams");
}

TEST(CvodesTransition, TooMuchWorkThrowsNumericalErrorWithReason) {
  models::VanDerPol::Params p;
  TransitionOptions o;
  o.max_steps = 1;
  auto tr = MakeTransition<models::VanDerPol>(p, o);
  try {
    tr->Step(Vec<double, 2>(2.0, 0.0), 0.0, 1.0);
    FAIL() << "expected NumericalError";
  } catch (const NumericalError& e) {
    EXPECT_NE(std::string(e.what()).find("CV_TOO_MUCH_WORK"), std::string::npos) << e.what();
  }
}

TEST(CvodesTransition, InvalidOptionsAreInputErrors) {
  models::VanDerPol::Params p;
  TransitionOptions o;
  o.rtol = 0.0;
  EXPECT_THROW(MakeTransition<models::VanDerPol>(p, o), InputError);
  o = TransitionOptions{};
  o.atol = NAN;
  EXPECT_THROW(MakeTransition<models::VanDerPol>(p, o), InputError);
  o = TransitionOptions{};
  o.integrator = Integrator::kRk4;
  o.substeps = 0;
  EXPECT_THROW(MakeTransition<models::VanDerPol>(p, o), InputError);
  EXPECT_THROW(ParseIntegrator("rk5"), InputError);
  EXPECT_EQ(ParseIntegrator("semi-implicit-euler"), Integrator::kSemiImplicitEuler);
}

}  // namespace
}  // namespace estlab
