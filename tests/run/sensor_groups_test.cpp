// Sensor groups (issue 35): a measurement whose outputs come from several
// sensors (models/model.h, kGroups), each with its own R block, tuned R, NIS
// and simulated rate. Each check against a reference written here:
//   * `--measure imu,gps` names the measurement with exactly those groups, in
//     any order; a group named twice, an unknown one or a part of a
//     measurement's groups is refused, naming it;
//   * R given per group fills its block (0 between groups); an unknown
//     group, a group given twice, a group left out, and mixing the forms
//     are refused, naming the key;
//   * a blockwise R parameterisation (full for one group, scalar for
//     another) equals the hand-built block-diagonal matrix, and its initial
//     parameters give back the initial R;
//   * the tuner's NLL with a blockwise R is minus the run's log-likelihood,
//     and its gradient matches central differences on a record whose slow
//     sensor is missing in most rows;
//   * each group's NIS is nu_o' S_oo^-1 nu_o over its observed components
//     (a hand solve with dynamic sizes), counted over the updates that saw
//     the group; on data simulated with the filter's own Q and R every
//     group's mean NIS lies in its chi-square bounds;
//   * sensor rates in Hz or rows become each output's period, and simulated
//     data at those rates equal the full-rate data with the cells between
//     samples emptied.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "adaptive/noise_param.h"
#include "adaptive/tuner.h"
#include "adaptive/tuner_impl.h"
#include "src/core/random.h"
#include "src/filters/filters.h"
#include "src/ode/transition_impl.h"
#include "src/options/filter_settings.h"
#include "src/options/sensor_rates.h"
#include "src/registry/registry.h"
#include "src/run/filter_run_impl.h"
#include "src/run/group_nis.h"
#include "tests/adaptive/tuner_fixture.h"

namespace estlab {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A cart as a discrete-time map, position p and speed v, commanded
// acceleration u, drag c:
//   p+ = p + dt v,   v+ = v + dt (u - c v)
// measured by an inertial unit (the acceleration it feels, which sees the
// input, and a wheel speed) and a position fix:
//   imu: [u - c v, v],   gps: [p]
struct Cart {
  static constexpr const char* kName = "groups-test";
  static constexpr const char* kDescription = "cart with an imu and a position fix (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 2> kStateNames = {"p", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};
  struct Params {
    double c = 0.4;
  };
  static constexpr std::array<ParamSpec<Params>, 1> kParams = {{
      {"c", &Params::c, "drag", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double dt, double u, const Params& p) {
    Vec<T, 2> next;
    next(0) = x(0) + dt * x(1);
    next(1) = x(1) + dt * (u - p.c * x(1));
    return next;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct Nav {
    static constexpr const char* kName = "nav";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"acc", "speed", "pos"};
    static constexpr std::array<bool, 3> kAngleOutputs = {false, false, false};
    static constexpr std::array<OutputGroupSpec, 2> kGroups = {{{"imu", 0, 2}, {"gps", 2, 1}}};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 2>& x, double u, const Params& p) {
      return Vec<T, 3>(u - p.c * x(1), x(1), x(0));
    }
  };
  using Measurements = std::tuple<Nav>;
};

const Mat<2, 2> kQ = (Mat<2, 2>() << 1e-6, 0.0, 0.0, 4e-4).finished();
const Mat<3, 3> kR =
    (Mat<3, 3>() << 0.01, 0.002, 0.0, 0.002, 0.004, 0.0, 0.0, 0.0, 0.25).finished();

// n rows every 0.1 s, u = sin(0.3 t), simulated with kQ and kR (Rng seed);
// the position fix only in every `gps_every`-th row.
FilterData CartRecord(int n, int gps_every, uint64_t seed) {
  const Cart::Params p;
  Rng rng(seed);
  const Eigen::LLT<Mat<3, 3>> r_chol(kR);
  FilterData d;
  d.path = "cart.csv";
  d.m = 3;
  d.nu = 1;
  Vec<double, 2> x(0.0, 0.5);
  for (int k = 0; k < n; ++k) {
    const double t = 0.1 * k, u = std::sin(0.3 * t);
    if (k > 0) {
      x = Cart::Step<double>(t, x, 0.1, d.u.back(), p);
      x += Vec<double, 2>(std::sqrt(kQ(0, 0)) * rng.Normal(), std::sqrt(kQ(1, 1)) * rng.Normal());
    }
    const Vec<double, 3> w(rng.Normal(), rng.Normal(), rng.Normal());
    const Vec<double, 3> z = Cart::Nav::Eval<double>(x, u, p) + r_chol.matrixL() * w;
    d.t.push_back(t);
    d.u.push_back(u);
    d.lines.push_back(k + 2);
    for (int j = 0; j < 3; ++j) d.z.push_back(j < 2 || k % gps_every == 0 ? z(j) : kNaN);
  }
  return d;
}

FilterSpec CartSpec(const FilterKindOptions& kind) {
  FilterSpec spec;
  spec.params = {Cart::Params{}.c};
  spec.measurement = "nav";
  spec.transition.integrator = Integrator::kDiscrete;
  spec.filter = kind;
  spec.x0 = {0.0, 0.5};
  spec.p0 = {0.1, 0.0, 0.0, 0.1};
  spec.q.assign(kQ.data(), kQ.data() + 4);
  spec.r.assign(kR.data(), kR.data() + 9);
  return spec;
}

std::string ErrorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SensorGroups, MeasureNamesTheMeasurementWithThoseGroups) {
  const ModelEntry& model = FindModel("cart-pole");
  EXPECT_EQ(model.FindMeasurement("position,encoder").name, "x-theta");
  EXPECT_EQ(model.FindMeasurement(" encoder , position ").name, "x-theta");
  EXPECT_EQ(model.FindMeasurement("x-theta").name, "x-theta");
  const MeasurementDesc& m = model.FindMeasurement("x-theta");
  ASSERT_EQ(m.groups.size(), 2u);
  EXPECT_EQ(m.groups[0].name, "position");
  EXPECT_EQ(m.groups[1].first, 1);
  EXPECT_NE(ErrorOf([&] {
              model.FindMeasurement("position,position");
            }).find("sensor group 'position' is named twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              model.FindMeasurement("position");
            }).find("names 1 of the 2 sensor groups of measurement 'x-theta'"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              model.FindMeasurement("gyro,encoder");
            }).find("unknown sensor group 'gyro' in 'gyro,encoder' for model 'cart-pole'"),
            std::string::npos);
  EXPECT_EQ(model.FindMeasurement("x-theta ").name, "x-theta");
  EXPECT_NE(ErrorOf([&] {
              model.FindMeasurement("x-theta,position");
            }).find("'x-theta' in 'x-theta,position' is a measurement, not a sensor group"),
            std::string::npos);
  // A plain unknown name keeps its message, here and for a model without groups.
  EXPECT_EQ(ErrorOf([&] { model.FindMeasurement("angles"); })
                .rfind("unknown measurement 'angles' for model 'cart-pole' (known: x-theta; "
                       "sensor groups: position, encoder)",
                       0),
            0u);
  EXPECT_EQ(ErrorOf([&] {
              FindModel("pendulum").FindMeasurement("cos");
            }).rfind("unknown measurement 'cos' for model 'pendulum' (known: ", 0),
            0u);
}

FilterSettings CartPoleSettings() {
  FilterSettings s;
  s.Set("model", "cart-pole");
  s.Set("measure", "encoder,position");
  s.Set("q-diag", "1e-6,1e-4,1e-6,1e-4");
  return s;
}

TEST(SensorGroups, RPerGroupFillsItsBlock) {
  const ModelEntry& model = FindModel("cart-pole");
  FilterSettings s = CartPoleSettings();
  s.Add("r-diag", "position=0.01");
  s.Add("r", "encoder=4e-4");
  const FilterSpec spec = BuildFilterSpec(s, model);
  EXPECT_EQ(spec.measurement, "x-theta");
  EXPECT_EQ(spec.r, (std::vector<double>{0.01, 0.0, 0.0, 4e-4}));
  auto error = [&](const std::vector<std::pair<std::string, std::string>>& r) {
    FilterSettings t = CartPoleSettings();
    for (const auto& [k, v] : r) t.Add(k, v);
    return ErrorOf([&] { BuildFilterSpec(t, model); });
  };
  EXPECT_NE(
      error({{"r-diag", "gyro=1"}, {"r-diag", "position=1"}, {"r-diag", "encoder=1"}})
          .find("--r-diag: unknown sensor group 'gyro' (groups of x-theta: position, encoder)"),
      std::string::npos);
  EXPECT_NE(error({{"r-diag", "position=1"}, {"r", "position=2"}, {"r-diag", "encoder=1"}})
                .find("sensor group 'position' is given twice"),
            std::string::npos);
  EXPECT_NE(error({{"r-diag", "position=1"}}).find("no R for sensor group 'encoder'"),
            std::string::npos);
  EXPECT_NE(error({{"r-diag", "position=1"}, {"r-diag", "1"}}).find("not both"), std::string::npos);
  EXPECT_NE(error({{"r-diag", "position=1,2"}, {"r-diag", "encoder=1"}})
                .find("one per output of group 'position'"),
            std::string::npos);
  EXPECT_NE(error({{"r-diag", "position=-1"}, {"r-diag", "encoder=1"}})
                .find("--r-diag: R of group 'position' is not positive definite"),
            std::string::npos);
  // The whole form still works, and twice is refused.
  EXPECT_EQ(BuildFilterSpec(
                [&] {
                  FilterSettings t = CartPoleSettings();
                  t.Add("r-diag", "0.5,0.25");
                  return t;
                }(),
                model)
                .r,
            (std::vector<double>{0.5, 0.0, 0.0, 0.25}));
  EXPECT_NE(error({{"r-diag", "1,1"}, {"r-diag", "2,2"}})
                .find("--r-diag: is given more than once (once per sensor group takes "
                      "GROUP=values)"),
            std::string::npos);
  EXPECT_NE(error({{"r-diag", "1,1"}, {"r", "2,0;0,2"}})
                .find("--r-diag: give exactly one of --r-diag, --r (measurement noise R)"),
            std::string::npos);
  EXPECT_NE(error({{"r", "encoder=1"}}).find("--r: no R for sensor group 'position'"),
            std::string::npos);
}

TEST(SensorGroups, BlockwiseCovarianceEqualsTheHandBlockDiagonalMatrix) {
  const std::vector<std::string> names = {"acc", "speed", "pos"};
  InitialCovariance<3> initial;
  initial.matrix = kR;
  const CovarianceParam<3> r(
      NoiseParam::kDiag, "r", names, {}, initial, 0.0,
      {{NoiseParam::kFull, 0, 2, "imu"}, {NoiseParam::kScalar, 2, 1, "gps"}});
  EXPECT_TRUE(r.Blockwise());
  ASSERT_EQ(r.NumParams(), 4);
  EXPECT_EQ(r.Names()[3], "log r_gps");
  EXPECT_EQ(r.Names()[1], "Lr(speed,acc)");
  EXPECT_EQ(r.OffDiagonalRow()[1], 1);
  EXPECT_LT((r.Matrix<double>(r.InitialTheta().data(), 0.0) - kR).cwiseAbs().maxCoeff(), 1e-15);
  const std::vector<double> theta = {-3.0, 0.3, -5.0, 0.7};
  Mat<3, 3> hand = Mat<3, 3>::Zero();
  Mat<2, 2> L;
  L << std::exp(-1.5), 0.0, 0.3, std::exp(-2.5);
  hand.block<2, 2>(0, 0) = L * L.transpose();
  hand(2, 2) = std::exp(0.7);
  EXPECT_LT((r.Matrix<double>(theta.data(), 0.0) - hand).cwiseAbs().maxCoeff(), 1e-15);
  // A full block after another: its off-diagonal parameter names its
  // absolute row.
  Mat<3, 3> bd = kR;
  bd(0, 1) = bd(1, 0) = 0.0;
  bd(1, 2) = bd(2, 1) = 0.003;
  initial.matrix = bd;
  const CovarianceParam<3> second(NoiseParam::kDiag, "r", names, {}, initial, 0.0,
                                  {{NoiseParam::kDiag, 0, 1, "a"}, {NoiseParam::kFull, 1, 2, "b"}});
  ASSERT_EQ(second.NumParams(), 4);
  EXPECT_EQ(second.Names()[2], "Lr(pos,speed)");
  EXPECT_EQ(second.OffDiagonalRow(), (std::vector<int>{-1, -1, 2, -1}));
  EXPECT_LT((second.Matrix<double>(second.InitialTheta().data(), 0.0) - bd).cwiseAbs().maxCoeff(),
            1e-15);
  // One group of a kind is that kind over the whole matrix, as without groups.
  initial.matrix = kR;
  for (const NoiseParam kind : {NoiseParam::kFull, NoiseParam::kScalar}) {
    const CovarianceParam<3> one(NoiseParam::kDiag, "r", names, {}, initial, 0.0,
                                 {{kind, 0, 3, "nav"}});
    const CovarianceParam<3> whole(kind, "r", names, {}, initial, 0.0);
    EXPECT_EQ(one.kind(), kind);
    EXPECT_FALSE(one.Blockwise());
    EXPECT_EQ(one.Names(), whole.Names());
    EXPECT_EQ(one.InitialTheta(), whole.InitialTheta());
  }
  // Every group fixed: the initial R with 0 between the groups.
  const CovarianceParam<3> fixed(
      NoiseParam::kDiag, "r", names, {}, initial, 0.0,
      {{NoiseParam::kFixed, 0, 1, "a"}, {NoiseParam::kFixed, 1, 2, "b"}});
  EXPECT_EQ(fixed.kind(), NoiseParam::kFixed);
  EXPECT_EQ(fixed.NumParams(), 0);
  Mat<3, 3> cut = kR;
  cut(0, 1) = cut(1, 0) = 0.0;
  EXPECT_EQ(fixed.Matrix<double>(nullptr, 0.0), cut);
  // Diag blocks throughout are diag over the whole matrix (EM and ALS take it).
  const CovarianceParam<3> d(NoiseParam::kFull, "r", names, {}, initial, 0.0,
                             {{NoiseParam::kDiag, 0, 2, "imu"}, {NoiseParam::kDiag, 2, 1, "gps"}});
  EXPECT_FALSE(d.Blockwise());
  EXPECT_EQ(d.kind(), NoiseParam::kDiag);
  EXPECT_EQ(d.NumParams(), 3);
}

TEST(SensorGroups, GroupNisIsTheObservedBlocksNisByAHandSolve) {
  const Vec<double, 3> nu(0.3, kNaN, -0.8);
  Mat<3, 3> S;
  S << 0.5, 0.1, 0.05, 0.1, 0.4, 0.02, 0.05, 0.02, 0.9;
  const Vec<double, 3> nu2(0.1, -0.2, kNaN);
  GroupNisTally<Cart::Nav> tally;
  tally.Observe(nu, S);
  tally.Observe(nu2, S);
  FilterSummary s;
  tally.Report(&s);
  ASSERT_EQ(s.group_nis.size(), 2u);
  // imu: {acc} in the first update, {acc, speed} in the second.
  Eigen::MatrixXd S2 = S.block<2, 2>(0, 0);
  Eigen::VectorXd v2 = nu2.head<2>();
  const double imu = (0.3 * 0.3 / 0.5 + v2.dot(S2.ldlt().solve(v2))) / 2.0;
  EXPECT_EQ(s.group_nis[0].group, "imu");
  EXPECT_EQ(s.group_nis[0].updates, 2);
  EXPECT_NEAR(s.group_nis[0].mean_nis, imu, 1e-14);
  double bounds[2];
  ChiSquareMeanBounds95(2, 3, bounds);  // 1 + 2 observed components
  EXPECT_EQ(s.group_nis[0].nis_bounds95[0], bounds[0]);
  EXPECT_EQ(s.group_nis[1].updates, 1);
  EXPECT_NEAR(s.group_nis[1].mean_nis, 0.64 / 0.9, 1e-14);
}

TEST(SensorGroups, RunReportsEachGroupsNisWithinItsBounds) {
  const FilterData d = CartRecord(600, 10, 7);
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{})}) {
    const FilterRunOutput out = RunFilterWith<Cart, Cart::Nav>(CartSpec(kind), d);
    SCOPED_TRACE(out.summary.filter);
    ASSERT_TRUE(out.summary.ok) << out.summary.message;
    ASSERT_EQ(out.summary.group_nis.size(), 2u);
    const FilterSummary::GroupNis& imu = out.summary.group_nis[0];
    const FilterSummary::GroupNis& gps = out.summary.group_nis[1];
    EXPECT_EQ(imu.updates, 600);
    EXPECT_EQ(gps.updates, 60);
    for (const FilterSummary::GroupNis& g : {imu, gps}) {
      EXPECT_GT(g.mean_nis, g.nis_bounds95[0]) << g.group;
      EXPECT_LT(g.mean_nis, g.nis_bounds95[1]) << g.group;
    }
  }
}

TEST(SensorGroups, TunerWithBlockwiseRIsTheRunsLikelihoodAndItsGradientIsExact) {
  const std::vector<FilterData> datasets = {CartRecord(120, 6, 3)};
  TunerOptions options;
  options.q_param = NoiseParam::kDiag;
  options.r_param_groups = {{"gps", NoiseParam::kScalar}, {"imu", NoiseParam::kFull}};
  uint64_t seed = 5;
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{.alpha = 0.5})}) {
    const FilterSpec spec = CartSpec(kind);
    const InnovationLikelihood<Cart, Cart::Nav> lik(spec, options, datasets);
    ASSERT_EQ(lik.NumParams(), 2 + 3 + 1);
    // At the initial point R is the spec's R: the NLL is the run's.
    const FilterRunOutput out = RunFilterWith<Cart, Cart::Nav>(spec, datasets[0]);
    ASSERT_TRUE(out.summary.ok) << out.summary.message;
    double nll = 0.0;
    ASSERT_TRUE(lik.Nll<double>(lik.InitialTheta().data(), &nll));
    EXPECT_NEAR(nll, -out.summary.loglik, 1e-10 * std::abs(nll));
    // Fourth-order differences: the NLL is 1e3 .. 1e4 at these points and the
    // second-order truncation error reaches 2e-6 on the small q_p gradient.
    testing::CheckGradient(lik, seed++, "blockwise R", {.h = 1e-4, .fourth_order = true});
  }
  TunerOptions bad = options;
  bad.r_param_groups = {{"imu", NoiseParam::kFull}};
  EXPECT_NE(ErrorOf([&] {
              const InnovationLikelihood<Cart, Cart::Nav> lik(CartSpec(KfOptions{}), bad, datasets);
            }).find("--r-param: no kind for sensor group 'gps'"),
            std::string::npos);
  bad.r_param_groups = {{"imu", NoiseParam::kFull}, {"gsp", NoiseParam::kDiag}};
  EXPECT_NE(ErrorOf([&] {
              const InnovationLikelihood<Cart, Cart::Nav> lik(CartSpec(KfOptions{}), bad, datasets);
            }).find("--r-param: unknown sensor group 'gsp' (groups of nav: imu, gps)"),
            std::string::npos);
  TunerOptions em = options;
  em.estimator = Estimator::kEm;
  EXPECT_NE(ErrorOf([&] {
              TuneWith<Cart, Cart::Nav>(CartSpec(KfOptions{}), em, datasets);
            }).find("is for the ml estimator; em takes one kind"),
            std::string::npos);
}

TEST(SensorGroups, RatesBecomeEachOutputsPeriod) {
  const MeasurementDesc& m = FindModel("cart-pole").FindMeasurement("x-theta");
  EXPECT_EQ(OutputEvery(m, "position=1", "", 0.01, "rate", "every"), (std::vector<int>{100, 1}));
  EXPECT_EQ(OutputEvery(m, "", "encoder=3", 0.0, "rate", "every"), (std::vector<int>{1, 3}));
  EXPECT_EQ(OutputEvery(m, "encoder=100", "position=20", 0.01, "rate", "every"),
            (std::vector<int>{20, 1}));
  EXPECT_NE(ErrorOf([&] {
              OutputEvery(m, "position=3", "", 0.01, "rate", "every");
            }).find("rate: position at 3 Hz is 33.3"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              OutputEvery(m, "position=1", "position=2", 0.01, "rate", "every");
            }).find("every: sensor group 'position' is given twice"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              OutputEvery(m, "imu=1", "", 0.01, "rate", "every");
            }).find("rate: unknown sensor group 'imu' (groups of x-theta: position, encoder)"),
            std::string::npos);
  EXPECT_NE(
      ErrorOf([&] { OutputEvery(m, "position=1", "", 0.0, "rate", "every"); }).find("uniform grid"),
      std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              OutputEvery(m, "", "encoder=0", 0.01, "rate", "every");
            }).find("every (encoder)"),
            std::string::npos);
}

TEST(SensorGroups, SimulatedRatesEmptyTheCellsOfTheFullRateData) {
  const ModelEntry& model = FindModel("cart-pole");
  SimulationSpec spec;
  spec.params = model.ResolveParams({});
  spec.x0 = {0.0, 0.0, 3.0, 0.0};
  spec.t_end = 3.0;
  spec.dt = 0.01;
  spec.measurement = "x-theta";
  spec.meas_noise_var = {1e-4, 1e-4};
  const SimulationResult full = model.simulate(spec);
  spec.output_every = {100, 1};
  const SimulationResult slow = model.simulate(spec);
  ASSERT_TRUE(full.ok && slow.ok);
  ASSERT_EQ(full.rows.size(), 301u);
  ASSERT_EQ(slow.rows.size(), full.rows.size());
  const size_t zx = full.rows[0].size() - 2;  // t, 4 states, z_x, z_theta
  int kept = 0;
  for (size_t k = 0; k < full.rows.size(); ++k) {
    for (size_t j = 0; j < full.rows[k].size(); ++j) {
      if (j == zx && k % 100 != 0) {
        EXPECT_TRUE(std::isnan(slow.rows[k][j])) << k;
        continue;
      }
      EXPECT_EQ(slow.rows[k][j], full.rows[k][j]) << k << " " << j;
      kept += j == zx;
    }
  }
  EXPECT_EQ(kept, 4);  // t = 0, 1, 2, 3
  // A period per output, each at least one row.
  for (const std::vector<int>& bad : {std::vector<int>{0, 1}, std::vector<int>{100}}) {
    spec.output_every = bad;
    EXPECT_NE(ErrorOf([&] {
                model.simulate(spec);
              }).find("sensor rates: one period >= 1 row per output of 'x-theta'"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace estlab
