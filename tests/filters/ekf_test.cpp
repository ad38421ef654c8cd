// EKF and IEKF on linear models equal the hand-written Kalman filter at every
// step; the steady-state gain is the Riccati gain; failures are statuses.
#include "src/filters/ekf.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "linear_fixture.h"
#include "models/pendulum.h"
#include "riccati.h"

namespace estlab::testing {
namespace {

using Osc = DampedOscillator;

template <class Model, class Meas>
Deviation RunEkfVersusKf(int iterations, uint64_t seed) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const typename Model::Params params;
  const double dt = 0.1;
  auto transition = EulerTransition<Model>(params);
  EkfOptions options;
  options.iterations = iterations;
  Ekf<Model, Meas> ekf(transition.get(), params, options);
  const HandKf<N, M> ref = EulerReference<Model, Meas>(params, dt);
  const LinearData<N, M> data = MakeLinearData<N, M>(ref.F, ref.G, ref.H, 150, seed);
  return CompareWithReference<Model, Meas>(ekf, ref, data, data.Q);
}

TEST(EkfTest, EqualsKalmanFilterOnLinearModels) {
  for (int iterations : {1, 3}) {
    const Deviation d1 = RunEkfVersusKf<Osc, Osc::Position>(iterations, 11);
    const Deviation d2 = RunEkfVersusKf<Osc, Osc::Mixed>(iterations, 12);
    const Deviation d4 =
        RunEkfVersusKf<CoupledOscillators, CoupledOscillators::Relative>(iterations, 13);
    std::printf("[ measured ] ekf iterations=%d: max deviation %.2e / %.2e / %.2e\n", iterations,
                d1.Max(), d2.Max(), d4.Max());
    EXPECT_TRUE(DeviationBelow(d1, 1e-10)) << "iterations " << iterations;
    EXPECT_TRUE(DeviationBelow(d2, 1e-10)) << "iterations " << iterations;
    EXPECT_TRUE(DeviationBelow(d4, 1e-10)) << "iterations " << iterations;
  }
}

TEST(EkfTest, NameAndOptions) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  EkfOptions options;
  EXPECT_EQ((Ekf<Osc, Osc::Position>(transition.get(), params, options).Name()), "ekf");
  options.iterations = 4;
  EXPECT_EQ((Ekf<Osc, Osc::Position>(transition.get(), params, options).Name()), "iekf");
  options.iterations = 0;
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("iterations"), std::string::npos);
  EXPECT_THROW((Ekf<Osc, Osc::Position>(transition.get(), params, options)), InputError);
  EXPECT_THROW((Ekf<Osc, Osc::Position>(nullptr, params, EkfOptions{})), InputError);
}

TEST(EkfTest, SteadyStateGainIsTheRiccatiGain) {
  const Osc::Params params;
  const double dt = 0.1;
  auto transition = EulerTransition<Osc>(params);
  Ekf<Osc, Osc::Mixed> ekf(transition.get(), params, EkfOptions{});
  const auto ref = EulerReference<Osc, Osc::Mixed>(params, dt);
  const Mat<2, 2> Q = (Mat<2, 2>() << 0.02, 0.005, 0.005, 0.01).finished();
  const Mat<2, 2> R = (Mat<2, 2>() << 0.1, 0.02, 0.02, 0.05).finished();
  const Mat<2, 2> K_dare = RiccatiGain<2, 2>(ref.F, ref.H, Q, R);
  ekf.Initialize(Vec<double, 2>(1.0, 0.0), 5.0 * Mat<2, 2>::Identity());
  StepResult<2> r;
  for (int k = 0; k < 1000; ++k) {
    if (k > 0) {
      ASSERT_EQ(ekf.Predict((k - 1) * dt, k * dt, Q), FilterStatus::kOk);
    }
    r = ekf.Update(Vec<double, 2>(std::sin(0.1 * k), 0.0), R);
    ASSERT_EQ(r.status, FilterStatus::kOk);
  }
  const double err = (Mat<2, 2>(r.gain) - K_dare).cwiseAbs().maxCoeff();
  std::printf("[ measured ] ekf steady-state gain - DARE gain: %.2e\n", err);
  EXPECT_LT(err, 1e-8);
  // Not converged after 3 steps from P0 = 5 I: the comparison can fail.
  Ekf<Osc, Osc::Mixed> early(transition.get(), params, EkfOptions{});
  early.Initialize(Vec<double, 2>(1.0, 0.0), 5.0 * Mat<2, 2>::Identity());
  early.Predict(0.0, dt, Q);
  early.Predict(dt, 2 * dt, Q);
  r = early.Update(Vec<double, 2>(0.0, 0.0), R);
  EXPECT_GT((Mat<2, 2>(r.gain) - K_dare).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(EkfTest, IteratedUpdateReachesTheMapEstimateOfANonlinearMeasurement) {
  // Prior N(x-, P-) and z = sin(theta) + v: the IEKF is Gauss-Newton on
  // J(x) = |x - x-|^2_{P-^-1} + |z - h(x)|^2_{R^-1}, so at its fixed point the
  // gradient vanishes: P-^-1 (x - x-) - H^T R^-1 (z - h(x)) = 0.
  using P = models::Pendulum;
  const P::Params params;
  auto transition = EulerTransition<P>(params);
  EkfOptions options;
  options.iterations = 30;
  Ekf<P, P::Sin> iekf(transition.get(), params, options);
  Ekf<P, P::Sin> ekf(transition.get(), params, EkfOptions{});
  const Vec<double, 2> x_prior(0.3, 0.1);
  const Mat<2, 2> P_prior = (Mat<2, 2>() << 0.5, 0.1, 0.1, 0.2).finished();
  const Mat<1, 1> R = Mat<1, 1>::Constant(0.01);
  const Vec<double, 1> z(0.9);
  iekf.Initialize(x_prior, P_prior);
  ekf.Initialize(x_prior, P_prior);
  const StepResult<1> ri = iekf.Update(z, R);
  const StepResult<1> re = ekf.Update(z, R);
  ASSERT_EQ(ri.status, FilterStatus::kOk);
  const Vec<double, 2> x = iekf.mean();
  const Mat<1, 2> H(std::cos(x(0)), 0.0);
  const Vec<double, 2> grad =
      P_prior.llt().solve(x - x_prior) - H.transpose() * ((z(0) - std::sin(x(0))) / R(0, 0));
  EXPECT_LT(grad.cwiseAbs().maxCoeff(), 1e-9);
  // The EKF's single step is not at the MAP point here (the test can fail).
  const Vec<double, 2> xe = ekf.mean();
  const Vec<double, 2> grad_e =
      P_prior.llt().solve(xe - x_prior) -
      Vec<double, 2>(std::cos(xe(0)), 0.0) * ((z(0) - std::sin(xe(0))) / R(0, 0));
  EXPECT_GT(grad_e.cwiseAbs().maxCoeff(), 1e-2);
  // Innovation, S and log-likelihood are reported at the prior: the EKF's.
  EXPECT_DOUBLE_EQ(ri.innovation(0), re.innovation(0));
  EXPECT_DOUBLE_EQ(ri.innovation_cov(0, 0), re.innovation_cov(0, 0));
  EXPECT_DOUBLE_EQ(ri.log_likelihood, re.log_likelihood);
  // The post-fit residual is z - h(x+).
  EXPECT_NEAR(ri.residual(0), z(0) - std::sin(x(0)), 1e-15);
}

TEST(EkfTest, AngleInnovationIsWrapped) {
  using P = models::Pendulum;
  const P::Params params;
  auto transition = EulerTransition<P>(params);
  Ekf<P, P::Angle> ekf(transition.get(), params, EkfOptions{});
  ekf.Initialize(Vec<double, 2>(M_PI - 0.01, 0.0), 0.01 * Mat<2, 2>::Identity());
  const StepResult<1> r = ekf.Update(Vec<double, 1>(-M_PI + 0.01), Mat<1, 1>::Constant(0.01));
  ASSERT_EQ(r.status, FilterStatus::kOk);
  EXPECT_NEAR(r.innovation(0), 0.02, 1e-12);
  // x+ = x- + K nu with K = 0.01 / 0.02 = 1/2.
  EXPECT_NEAR(ekf.mean()(0), M_PI, 1e-12);
}

TEST(EkfTest, FailuresAreStatuses) {
  const Osc::Params params;
  auto transition = EulerTransition<Osc>(params);
  const Mat<2, 2> Q = 0.01 * Mat<2, 2>::Identity();
  {  // P0 not positive semidefinite
    Ekf<Osc, Osc::Position> ekf(transition.get(), params, EkfOptions{});
    ekf.Initialize(Vec<double, 2>(1, 0), (Mat<2, 2>() << 1, 0, 0, -1).finished());
    EXPECT_EQ(ekf.Predict(0.0, 0.1, Q), FilterStatus::kFactorizationFailed);
    EXPECT_NE(ekf.last_error().find("P0"), std::string::npos) << ekf.last_error();
    const StepResult<1> r = ekf.Update(Vec<double, 1>(1.0), Mat<1, 1>::Constant(0.1));
    EXPECT_EQ(r.status, FilterStatus::kFactorizationFailed);
    EXPECT_NE(r.message.find("P0"), std::string::npos) << r.message;
  }
  {  // R = -I makes S = H P H^T + R negative
    Ekf<Osc, Osc::Mixed> ekf(transition.get(), params, EkfOptions{});
    ekf.Initialize(Vec<double, 2>(1, 0), 0.1 * Mat<2, 2>::Identity());
    const StepResult<2> r = ekf.Update(Vec<double, 2>(1.0, 1.0), -Mat<2, 2>::Identity());
    EXPECT_EQ(r.status, FilterStatus::kFactorizationFailed);
    EXPECT_NE(r.message.find("S = H P H^T + R"), std::string::npos) << r.message;
    EXPECT_TRUE((ekf.mean() == Vec<double, 2>(1, 0)));  // unchanged
  }
  {  // a NaN measurement is a missing one (src/filters/missing.h): the
     // update with no component observed changes nothing
    Ekf<Osc, Osc::Position> ekf(transition.get(), params, EkfOptions{});
    ekf.Initialize(Vec<double, 2>(1, 0), 0.1 * Mat<2, 2>::Identity());
    const StepResult<1> r = ekf.Update(Vec<double, 1>(std::nan("")), Mat<1, 1>::Constant(0.1));
    EXPECT_EQ(r.status, FilterStatus::kOk);
    EXPECT_EQ(r.observed, 0);
    EXPECT_EQ(r.log_likelihood, 0.0);
    EXPECT_TRUE((ekf.mean() == Vec<double, 2>(1, 0)));
    EXPECT_TRUE((ekf.cov() == 0.1 * Mat<2, 2>::Identity()));
  }
  {  // the integrator fails
    ThrowingTransition<Osc> throwing(params);
    Ekf<Osc, Osc::Position> ekf(&throwing, params, EkfOptions{});
    ekf.Initialize(Vec<double, 2>(1, 0), 0.1 * Mat<2, 2>::Identity());
    EXPECT_EQ(ekf.Predict(0.0, 0.1, Q), FilterStatus::kTransitionFailed);
    EXPECT_NE(ekf.last_error().find("too much work"), std::string::npos);
  }
  {  // used before Initialize
    Ekf<Osc, Osc::Position> ekf(transition.get(), params, EkfOptions{});
    EXPECT_NE(ekf.Predict(0.0, 0.1, Q), FilterStatus::kOk);
  }
}

}  // namespace
}  // namespace estlab::testing
