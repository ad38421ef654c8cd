// LinearizedKf: the zero-order-hold discretisation equals a hand Kalman filter
// with F = exp(A dt) (Taylor series here); the cart-pole linearisation equals
// paper 004's closed form; the steady-state gain is the Riccati gain;
// failures are statuses.
#include "src/filters/kalman.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "linear_fixture.h"
#include "models/cart_pole.h"
#include "riccati.h"

namespace estlab::testing {
namespace {

using Osc = DampedOscillator;

// exp(A dt) = sum_k (A dt)^k / k!  and  Gamma = int_0^dt exp(A s) ds B
// = sum_k A^k dt^(k+1) / (k+1)! B, both to 40 terms (|A dt| < 1 here).
template <int N>
void TaylorZoh(const Mat<N, N>& A, const Vec<double, N>& B, double dt, Mat<N, N>* F,
               Vec<double, N>* G) {
  Mat<N, N> term = Mat<N, N>::Identity();  // (A dt)^k / k!
  *F = Mat<N, N>::Zero();
  Mat<N, N> integral = Mat<N, N>::Zero();  // sum_k A^k dt^(k+1) / (k+1)!
  for (int k = 0; k < 40; ++k) {
    *F += term;
    integral += term * (dt / (k + 1));
    term = (term * A * dt / (k + 1)).eval();
  }
  *G = integral * B;
}

template <class Model, class Meas>
HandKf<Model::kStateDim, Meas::kDim> ZohReference(const typename Model::Params& params, double dt) {
  HandKf<Model::kStateDim, Meas::kDim> ref;
  TaylorZoh<Model::kStateDim>(Model::A(params), Model::B(), dt, &ref.F, &ref.G);
  ref.H = Meas::H();
  return ref;
}

template <class Model, class Meas>
Deviation RunKfVersusZoh(const KfOptions& options, uint64_t seed) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const typename Model::Params params;
  LinearizedKf<Model, Meas> kf(params, options);
  const HandKf<N, M> ref = ZohReference<Model, Meas>(params, 0.1);
  const LinearData<N, M> data = MakeLinearData<N, M>(ref.F, ref.G, ref.H, 150, seed);
  return CompareWithReference<Model, Meas>(kf, ref, data, data.Q);
}

TEST(LinearizedKfTest, ZeroOrderHoldEqualsKalmanFilterWithMatrixExponential) {
  KfOptions about_prior;              // x* = prior mean, u* = 0
  KfOptions elsewhere;                // an arbitrary operating point and input: the affine
  elsewhere.operating_input = {0.7};  // terms c and d must cancel exactly
  const Deviation d1 = RunKfVersusZoh<Osc, Osc::Position>(about_prior, 61);
  const Deviation d2 = RunKfVersusZoh<Osc, Osc::Mixed>(about_prior, 62);
  elsewhere.operating_point = {0.4, -1.3};
  const Deviation d3 = RunKfVersusZoh<Osc, Osc::Mixed>(elsewhere, 63);
  elsewhere.operating_point = {0.4, -1.3, 2.0, 0.5};
  const Deviation d4 =
      RunKfVersusZoh<CoupledOscillators, CoupledOscillators::Relative>(elsewhere, 64);
  std::printf("[ measured ] kf (zoh) vs hand KF: %.1e %.1e %.1e %.1e\n", d1.Max(), d2.Max(),
              d3.Max(), d4.Max());
  EXPECT_TRUE(DeviationBelow(d1, 1e-10));
  EXPECT_TRUE(DeviationBelow(d2, 1e-10));
  EXPECT_TRUE(DeviationBelow(d3, 1e-10));
  EXPECT_TRUE(DeviationBelow(d4, 1e-10));
  // The Euler map is a different discretisation: the comparison can fail.
  const Osc::Params params;
  LinearizedKf<Osc, Osc::Mixed> kf(params, about_prior);
  const HandKf<2, 2> euler = EulerReference<Osc, Osc::Mixed>(params, 0.1);
  const LinearData<2, 2> data = MakeLinearData<2, 2>(euler.F, euler.G, euler.H, 20, 65);
  const Deviation d = CompareWithReference<Osc, Osc::Mixed>(kf, euler, data, data.Q);
  EXPECT_GT(d.Max(), 1e-4);
}

TEST(LinearizedKfTest, DiscretisationFollowsTheStep) {
  const Osc::Params params;
  LinearizedKf<Osc, Osc::Position> kf(params, KfOptions{});
  kf.Initialize(Vec<double, 2>(0.1, 0.2), Mat<2, 2>::Identity());
  Mat<2, 2> F;
  Vec<double, 2> G;
  for (double dt : {0.1, 0.05, 0.1, 0.3}) {
    ASSERT_EQ(kf.Predict(1.0, 1.0 + dt, Mat<2, 2>::Zero()), FilterStatus::kOk);
    TaylorZoh<2>(Osc::A(params), Osc::B(), dt, &F, &G);
    EXPECT_LT((kf.Phi() - F).cwiseAbs().maxCoeff(), 1e-14) << "dt " << dt;
    EXPECT_LT((kf.Gamma() - G).cwiseAbs().maxCoeff(), 1e-14) << "dt " << dt;
  }
}

TEST(LinearizedKfTest, CartPoleLinearisationMatchesPaper004ClosedForm) {
  using CP = models::CartPole;
  const CP::Params p;  // all constants 1
  KfOptions options;
  options.operating_point = {0.0, 0.0, M_PI, 0.0};
  LinearizedKf<CP, CP::XTheta> kf(p, options);
  // p = I (M + m) + M m l^2
  const double d = p.I * (p.M + p.m) + p.M * p.m * p.l * p.l;
  Mat<4, 4> A;
  A << 0, 1, 0, 0,                                                                //
      0, -(p.I + p.m * p.l * p.l) * p.b / d, p.m * p.m * p.g * p.l * p.l / d, 0,  //
      0, 0, 0, 1,                                                                 //
      0, -p.m * p.l * p.b / d, p.m * p.g * p.l * (p.M + p.m) / d, 0;
  const Vec<double, 4> B(0, (p.I + p.m * p.l * p.l) / d, 0, p.m * p.l / d);
  const double a_err = (kf.A() - A).cwiseAbs().maxCoeff();
  const double b_err = (kf.B() - B).cwiseAbs().maxCoeff();
  std::printf("[ measured ] cart-pole |A - A_paper| = %.1e, |B - B_paper| = %.1e\n", a_err, b_err);
  EXPECT_LT(a_err, 1e-12);
  EXPECT_LT(b_err, 1e-12);
  // The free function gives the same A; the upright point is an equilibrium.
  EXPECT_LT((ContinuousJacobian<CP>(Vec<double, 4>(0, 0, M_PI, 0), 0.0, p) - A).norm(), 1e-12);
  EXPECT_LT(kf.c().norm(), 1e-15);
  EXPECT_TRUE((kf.H() == (Mat<2, 4>() << 1, 0, 0, 0, 0, 0, 1, 0).finished()));
  // Hanging down (theta = 0) the pendulum terms change sign: the test can fail.
  EXPECT_GT((ContinuousJacobian<CP>(Vec<double, 4>::Zero(), 0.0, p) - A).norm(), 0.5);
}

TEST(LinearizedKfTest, AngleDeviationsFromTheOperatingPointAreWrapped) {
  using CP = models::CartPole;
  const CP::Params p;
  KfOptions options;
  options.operating_point = {0.0, 0.0, M_PI, 0.0};
  LinearizedKf<CP, CP::XTheta> a(p, options), b(p, options);
  a.Initialize(Vec<double, 4>(0.1, 0.0, M_PI + 0.05, 0.0), 0.1 * Mat<4, 4>::Identity());
  b.Initialize(Vec<double, 4>(0.1, 0.0, -M_PI + 0.05, 0.0), 0.1 * Mat<4, 4>::Identity());
  ASSERT_EQ(a.Predict(0.0, 0.1, Mat<4, 4>::Zero()), FilterStatus::kOk);
  ASSERT_EQ(b.Predict(0.0, 0.1, Mat<4, 4>::Zero()), FilterStatus::kOk);
  EXPECT_LT((a.mean() - b.mean()).norm(), 1e-14);
  // The innovation of the angle is wrapped.
  const StepResult<2> r =
      a.Update(Vec<double, 2>(a.mean()(0), a.mean()(2) - 2 * M_PI), 0.01 * Mat<2, 2>::Identity());
  EXPECT_LT(r.innovation.norm(), 1e-12);
}

TEST(LinearizedKfTest, SteadyStateGainIsTheRiccatiGain) {
  const CoupledOscillators::Params params;
  const double dt = 0.1;
  LinearizedKf<CoupledOscillators, CoupledOscillators::Relative> kf(params, KfOptions{});
  const auto ref = ZohReference<CoupledOscillators, CoupledOscillators::Relative>(params, dt);
  Mat<4, 4> Q = 0.01 * Mat<4, 4>::Identity();
  Q(0, 1) = Q(1, 0) = 0.004;
  const Mat<2, 2> R = (Mat<2, 2>() << 0.1, 0.03, 0.03, 0.05).finished();
  const Mat<4, 2> K_dare = RiccatiGain<4, 2>(ref.F, ref.H, Q, R);
  kf.Initialize(Vec<double, 4>(1, 0, -1, 0), 10.0 * Mat<4, 4>::Identity());
  StepResult<2> r;
  for (int k = 0; k < 2000; ++k) {
    if (k > 0) {
      ASSERT_EQ(kf.Predict((k - 1) * dt, k * dt, Q), FilterStatus::kOk);
    }
    r = kf.Update(Vec<double, 2>(std::cos(0.05 * k), 0.1), R);
    ASSERT_EQ(r.status, FilterStatus::kOk);
  }
  const double err = (Mat<4, 2>(r.gain) - K_dare).cwiseAbs().maxCoeff();
  std::printf("[ measured ] kf steady-state gain - DARE gain: %.1e\n", err);
  EXPECT_LT(err, 1e-8);
  EXPECT_GT(K_dare.cwiseAbs().maxCoeff(), 0.05);  // a non-trivial gain
}

TEST(LinearizedKfTest, OptionsAndFailures) {
  const Osc::Params params;
  KfOptions options;
  options.operating_point = {1.0, std::nan("")};
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("operating point"), std::string::npos);
  EXPECT_THROW((LinearizedKf<Osc, Osc::Position>(params, options)), InputError);
  options.operating_point = {1.0, 2.0, 3.0};
  EXPECT_TRUE(options.IsValid(nullptr));
  EXPECT_THROW((LinearizedKf<Osc, Osc::Position>(params, options)), InputError);

  LinearizedKf<Osc, Osc::Mixed> kf(params, KfOptions{});
  EXPECT_EQ(kf.Name(), "kf");
  kf.Initialize(Vec<double, 2>(1, 0), (Mat<2, 2>() << 1, 0, 0, -1).finished());
  EXPECT_EQ(kf.Predict(0.0, 0.1, Mat<2, 2>::Identity()), FilterStatus::kFactorizationFailed);
  EXPECT_NE(kf.last_error().find("P0"), std::string::npos) << kf.last_error();
  kf.Initialize(Vec<double, 2>(1, 0), 0.1 * Mat<2, 2>::Identity());
  const StepResult<2> r = kf.Update(Vec<double, 2>(1, 1), -Mat<2, 2>::Identity());
  EXPECT_EQ(r.status, FilterStatus::kFactorizationFailed);
  EXPECT_FALSE(r.message.empty());
  EXPECT_EQ(kf.Predict(0.0, -0.1, Mat<2, 2>::Identity()), FilterStatus::kNonFinite);
}

}  // namespace
}  // namespace estlab::testing
