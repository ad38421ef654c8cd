// Discrete-time models (kDiscreteTime, a Step map instead of Rhs) run with
// the transition 'discrete' only: on a linear step map every Gaussian filter
// (KF, EKF, UKF, CKF) equals the hand-written Kalman filter with the map's
// own F and G (written out by hand below, not by AD); substeps apply the map
// to dt / substeps; a continuous model refuses 'discrete' and a discrete one
// every other integrator, with a message naming the model.
#include <gtest/gtest.h>

#include <array>
#include <string>
#include <tuple>
#include <utility>

#include "linear_fixture.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/sigma_point.h"

namespace estlab::testing {
namespace {

// A linear step map whose coefficients depend on the step length:
//   x1+ = x1 + dt x2
//   x2+ = (1 - a dt) x2 + dt x3 + dt u
//   x3+ = b x3                            (b per step, whatever dt is)
// measured z = (x1, x1 + x3).
struct DiscreteLinear {
  static constexpr const char* kName = "discrete-linear";
  static constexpr const char* kDescription = "linear step map (test model)";
  static constexpr int kStateDim = 3;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 3> kStateNames = {"x1", "x2", "x3"};
  static constexpr std::array<const char*, 3> kStateUnits = {"m", "m/s", "m/s^2"};
  static constexpr std::array<bool, 3> kAngleStates = {false, false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};
  struct Params {
    double a = 0.4;
    double b = 0.9;
  };
  static constexpr std::array<ParamSpec<Params>, 2> kParams = {{
      {"a", &Params::a, "decay [1/s]", Constraint::kNonNegative},
      {"b", &Params::b, "step factor", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 3> Step(const T& /*t*/, const Vec<T, 3>& x, double dt, double u, const Params& p) {
    Vec<T, 3> next;
    next(0) = x(0) + dt * x(1);
    next(1) = (1.0 - p.a * dt) * x(1) + dt * x(2) + dt * u;
    next(2) = p.b * x(2);
    return next;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 3>&, const Params&) {
    return Vec<double, 0>();
  }
  // The map written out by hand.
  static Mat<3, 3> F(const Params& p, double dt) {
    return (Mat<3, 3>() << 1, dt, 0, 0, 1 - p.a * dt, dt, 0, 0, p.b).finished();
  }
  static Vec<double, 3> G(double dt) { return Vec<double, 3>(0, dt, 0); }

  struct Pair {
    static constexpr const char* kName = "pair";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"x1", "x1_plus_x3"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 3>& x, const Params&) {
      return Vec<T, 2>(x(0), x(0) + x(2));
    }
    static Mat<2, 3> H() { return (Mat<2, 3>() << 1, 0, 0, 1, 0, 1).finished(); }
  };
  using Measurements = std::tuple<Pair>;
};
using DL = DiscreteLinear;
static_assert(DynamicModel<DL> && kDiscreteTime<DL> && !kDiscreteTime<DampedOscillator>);

constexpr double kDt = 0.1;

TransitionOptions DiscreteOptions(int substeps = 1) {
  TransitionOptions o;
  o.integrator = Integrator::kDiscrete;
  o.substeps = substeps;
  return o;
}

HandKf<3, 2> Reference(const DL::Params& p) {
  HandKf<3, 2> ref;
  ref.F = DL::F(p, kDt);
  ref.G = DL::G(kDt);
  ref.H = DL::Pair::H();
  return ref;
}

TEST(DiscreteTimeTest, TransitionIsTheMapAndItsJacobian) {
  const DL::Params p;
  auto tr = MakeTransition<DL>(p, DiscreteOptions());
  EXPECT_EQ(tr->Name(), "discrete");
  tr->SetInput(0.3);
  const Vec<double, 3> x(0.5, -1.0, 2.0);
  Mat<3, 3> F;
  const Vec<double, 3> next = tr->StepWithJacobian(x, 1.0, 1.0 + kDt, &F);
  EXPECT_LT(ScaledDiff(next, Vec<double, 3>(DL::F(p, kDt) * x + DL::G(kDt) * 0.3)), 1e-15);
  EXPECT_LT(ScaledDiff(F, DL::F(p, kDt)), 1e-15);
  EXPECT_EQ(tr->stats().internal_steps, 1);
  EXPECT_EQ(tr->stats().rhs_evals, 1);
}

TEST(DiscreteTimeTest, SubstepsApplyTheMapToDtOverSubsteps) {
  const DL::Params p;
  auto tr = MakeTransition<DL>(p, DiscreteOptions(4));
  const Vec<double, 3> x(0.5, -1.0, 2.0);
  Vec<double, 3> expected = x;
  for (int i = 0; i < 4; ++i) expected = DL::F(p, kDt / 4) * expected;
  EXPECT_LT(ScaledDiff(tr->Step(x, 0.0, kDt), expected), 1e-15);
}

TEST(DiscreteTimeTest, IntegratorMustMatchTheModel) {
  for (Integrator i : {Integrator::kEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4,
                       Integrator::kCvodes}) {
    TransitionOptions o;
    o.integrator = i;
    try {
      (void)MakeTransition<DL>(DL::Params{}, o);
      ADD_FAILURE() << IntegratorName(i) << " accepted for a discrete-time model";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("'discrete-linear' is discrete-time"), std::string::npos)
          << e.what();
    }
  }
  try {
    (void)MakeTransition<DampedOscillator>(DampedOscillator::Params{}, DiscreteOptions());
    ADD_FAILURE() << "discrete accepted for a continuous model";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'damped-oscillator' is continuous"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ParseIntegrator("discrete"), Integrator::kDiscrete);
  EXPECT_STREQ(IntegratorName(Integrator::kDiscrete), "discrete");
}

class DiscreteFilterTest : public ::testing::Test {
 protected:
  const DL::Params params_;
  const HandKf<3, 2> ref_ = Reference(params_);
  const LinearData<3, 2> data_ = MakeLinearData<3, 2>(ref_.F, ref_.G, ref_.H, 120, 907);
  std::unique_ptr<Transition<DL>> transition_ = MakeTransition<DL>(params_, DiscreteOptions());
};

TEST_F(DiscreteFilterTest, KfLinearisesTheMapExactly) {
  KfOptions elsewhere;  // an operating point and input away from the data: d and Gamma must cancel
  elsewhere.operating_point = {1.0, -2.0, 0.5};
  elsewhere.operating_input = {0.7};
  for (const KfOptions& o : {KfOptions{}, elsewhere}) {
    LinearizedKf<DL, DL::Pair> kf(params_, o);
    EXPECT_TRUE(
        DeviationBelow(CompareWithReference<DL, DL::Pair>(kf, ref_, data_, data_.Q), 1e-10));
  }
}

TEST_F(DiscreteFilterTest, EkfEqualsKalmanFilter) {
  Ekf<DL, DL::Pair> ekf(transition_.get(), params_, EkfOptions{});
  EXPECT_TRUE(DeviationBelow(CompareWithReference<DL, DL::Pair>(ekf, ref_, data_, data_.Q), 1e-10));
}

TEST_F(DiscreteFilterTest, SigmaPointFiltersEqualKalmanFilter) {
  for (SigmaRule rule : {SigmaRule::kUnscented, SigmaRule::kCubature, SigmaRule::kGaussHermite}) {
    SigmaPointOptions o;
    o.rule = rule;
    o.alpha = 1.0;
    o.update = SigmaPointOptions::Update::kRedraw;  // Q in S and C, as the Kalman filter
    SigmaPointFilter<DL, DL::Pair> filter(transition_.get(), params_, o);
    EXPECT_TRUE(
        DeviationBelow(CompareWithReference<DL, DL::Pair>(filter, ref_, data_, data_.Q), 1e-10))
        << int(rule);
  }
}

}  // namespace
}  // namespace estlab::testing
