// Filter-step benchmarks (issue "Performance"): one predict + update per
// iteration, beside the bare transition evaluations the step needs, which
// are the arithmetic floor the filter is compared with.
//
//   make bench    # Release build, writes bench/results/latest.json
//
// Names: <Filter>/<model>/n<states>m<outputs>/<integrator>[/particles].
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <memory>
#include <tuple>

#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/particle.h"
#include "src/filters/sigma_point.h"
#include "src/ode/transition_impl.h"

namespace estlab {
namespace {

// Constant velocity in 2-D with measured positions: the cheap 4x2 model of
// the LowLevelParticleFilters.jl comparison (0.35 us per UKF step there).
struct ConstantVelocity2d {
  static constexpr const char* kName = "cv2d";
  static constexpr const char* kDescription = "constant velocity in 2-D";
  static constexpr int kStateDim = 4;
  static constexpr bool kHasInput = false;
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 4> kStateNames = {"px", "vx", "py", "vy"};
  static constexpr std::array<bool, 4> kAngleStates = {false, false, false, false};
  static constexpr std::array<std::pair<int, int>, 2> kPositionRatePairs = {{{0, 1}, {2, 3}}};
  struct Params {
    double unused = 0.0;
  };
  static constexpr std::array<ParamSpec<Params>, 1> kParams = {
      {{"unused", &Params::unused, "", Constraint::kAny}}};
  template <class T>
  static Vec<T, 4> Rhs(const T&, const Vec<T, 4>& x, double, const Params&) {
    return Vec<T, 4>(x(1), T(0.0), x(3), T(0.0));
  }
  struct Positions {
    static constexpr const char* kName = "positions";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"px", "py"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 4>& x, const Params&) {
      return Vec<T, 2>(x(0), x(2));
    }
  };
  using Measurements = std::tuple<Positions>;
};

template <class Model>
Vec<double, Model::kStateDim> StartState() {
  Vec<double, Model::kStateDim> x = Vec<double, Model::kStateDim>::Zero();
  x(0) = 0.7;
  if (Model::kStateDim > 2) x(2) = 0.5;
  return x;
}

// Runs predict + update on a fixed measurement that the filter tracks, so the
// state stays bounded over millions of iterations.
template <class Model, class Meas, class MakeFilter>
void FilterStep(benchmark::State& state, Integrator integrator, MakeFilter make) {
  constexpr int N = Model::kStateDim, M = Meas::kDim;
  typename Model::Params params;
  TransitionOptions topt;
  topt.integrator = integrator;
  topt.rtol = 1e-8;
  topt.atol = 1e-10;
  auto transition = MakeTransition<Model>(params, topt);
  auto filter = make(transition.get(), params);
  const Vec<double, N> x0 = StartState<Model>();
  const Mat<N, N> P0 = 0.01 * Mat<N, N>::Identity();
  const Mat<N, N> Q = 1e-4 * Mat<N, N>::Identity();
  const Mat<M, M> R = 1e-2 * Mat<M, M>::Identity();
  const Vec<double, M> z = Meas::template Eval<double>(x0, params);
  filter->Initialize(x0, P0);
  const double dt = 0.01;
  double t = 0.0;
  long steps = 0;
  for (auto _ : state) {
    filter->Predict(t, t + dt, Q);
    auto r = filter->Update(z, R);
    benchmark::DoNotOptimize(r.log_likelihood);
    t += dt;
    if (++steps % 1000 == 0) {  // restart so the belief never drifts away
      filter->Initialize(x0, P0);
      t = 0.0;
    }
  }
  state.SetItemsProcessed(state.iterations());
}

template <class Model, class Meas>
void Ekf_(benchmark::State& s, Integrator integrator) {
  FilterStep<Model, Meas>(s, integrator, [](Transition<Model>* tr, const auto& p) {
    return std::make_unique<Ekf<Model, Meas>>(tr, p, EkfOptions{});
  });
}
template <class Model, class Meas>
void Kf_(benchmark::State& s) {
  FilterStep<Model, Meas>(s, Integrator::kRk4, [](Transition<Model>*, const auto& p) {
    KfOptions o;
    o.operating_point.assign(Model::kStateDim, 0.0);
    return std::make_unique<LinearizedKf<Model, Meas>>(p, o);
  });
}
template <class Model, class Meas>
void Sigma_(benchmark::State& s, Integrator integrator, SigmaRule rule) {
  FilterStep<Model, Meas>(s, integrator, [rule](Transition<Model>* tr, const auto& p) {
    SigmaPointOptions o;
    o.rule = rule;
    o.gh_order = 3;
    return std::make_unique<SigmaPointFilter<Model, Meas>>(tr, p, o);
  });
}
template <class Model, class Meas>
void Pf_(benchmark::State& s) {
  FilterStep<Model, Meas>(s, Integrator::kRk4, [&s](Transition<Model>* tr, const auto& p) {
    ParticleOptions o;
    o.num_particles = int(s.range(0));
    o.resample = ResampleScheme::kSystematic;
    o.ess_threshold = 1.0;  // resample every step
    return std::make_unique<ParticleFilter<Model, Meas>>(tr, p, o);
  });
}

// Bare transitions: `count` RK4 steps (the UKF's 2n+1 points), or one RK4
// step with its AD Jacobian (the EKF's predict).
template <class Model>
void Transitions_(benchmark::State& state, int count, bool jacobian, Integrator integrator) {
  constexpr int N = Model::kStateDim;
  typename Model::Params params;
  TransitionOptions topt;
  topt.integrator = integrator;
  topt.rtol = 1e-8;
  topt.atol = 1e-10;
  auto transition = MakeTransition<Model>(params, topt);
  Vec<double, N> x = StartState<Model>();
  Mat<N, N> F;
  for (auto _ : state) {
    for (int i = 0; i < count; ++i) {
      Vec<double, N> y = x;
      y(0) += 1e-9 * i;
      y = jacobian ? transition->StepWithJacobian(y, 0.0, 0.01, &F)
                   : transition->Step(y, 0.0, 0.01);
      benchmark::DoNotOptimize(y);
    }
  }
  state.SetItemsProcessed(state.iterations());
}

using models::DoublePendulum;
using models::Pendulum;
using Cv = ConstantVelocity2d;

void RegisterAll() {
  using benchmark::RegisterBenchmark;
  const auto us = benchmark::kMicrosecond;
  const auto rk4 = Integrator::kRk4;
  // Pendulum, y = sin(theta) (KF: y = theta, linearised at rest).
  RegisterBenchmark("KF/pendulum/n2m1/rk4", Kf_<Pendulum, Pendulum::Angle>);
  RegisterBenchmark("EKF/pendulum/n2m1/rk4", Ekf_<Pendulum, Pendulum::Sin>, rk4);
  RegisterBenchmark("UKF/pendulum/n2m1/rk4", Sigma_<Pendulum, Pendulum::Sin>, rk4,
                    SigmaRule::kUnscented);
  RegisterBenchmark("CKF/pendulum/n2m1/rk4", Sigma_<Pendulum, Pendulum::Sin>, rk4,
                    SigmaRule::kCubature);
  RegisterBenchmark("GHKF3/pendulum/n2m1/rk4", Sigma_<Pendulum, Pendulum::Sin>, rk4,
                    SigmaRule::kGaussHermite);
  RegisterBenchmark("PF/pendulum/n2m1/rk4/systematic-every-step", Pf_<Pendulum, Pendulum::Sin>)
      ->RangeMultiplier(10)
      ->Range(100, 100000)
      ->Unit(us);
  RegisterBenchmark("Floor/pendulum/rk4-with-jacobian/x1", Transitions_<Pendulum>, 1, true, rk4);
  RegisterBenchmark("Floor/pendulum/rk4/x5", Transitions_<Pendulum>, 5, false, rk4);
  // Double pendulum, both angles measured.
  using DP = DoublePendulum;
  RegisterBenchmark("KF/double-pendulum/n4m2/rk4", Kf_<DP, DP::Angles>);
  RegisterBenchmark("EKF/double-pendulum/n4m2/rk4", Ekf_<DP, DP::Angles>, rk4);
  RegisterBenchmark("UKF/double-pendulum/n4m2/rk4", Sigma_<DP, DP::Angles>, rk4,
                    SigmaRule::kUnscented);
  RegisterBenchmark("CKF/double-pendulum/n4m2/rk4", Sigma_<DP, DP::Angles>, rk4,
                    SigmaRule::kCubature);
  RegisterBenchmark("GHKF3/double-pendulum/n4m2/rk4", Sigma_<DP, DP::Angles>, rk4,
                    SigmaRule::kGaussHermite);
  RegisterBenchmark("PF/double-pendulum/n4m2/rk4/systematic-every-step", Pf_<DP, DP::Angles>)
      ->Arg(1000)
      ->Unit(us);
  RegisterBenchmark("Floor/double-pendulum/rk4-with-jacobian/x1", Transitions_<DP>, 1, true, rk4);
  RegisterBenchmark("Floor/double-pendulum/rk4/x9", Transitions_<DP>, 9, false, rk4);
  // Cheap 4x2 model.
  RegisterBenchmark("UKF/cv2d/n4m2/euler", Sigma_<Cv, Cv::Positions>, Integrator::kEuler,
                    SigmaRule::kUnscented);
  RegisterBenchmark("EKF/cv2d/n4m2/euler", Ekf_<Cv, Cv::Positions>, Integrator::kEuler);
  RegisterBenchmark("Floor/cv2d/euler/x9", Transitions_<Cv>, 9, false, Integrator::kEuler);
  // The cost of accuracy: CVODES transitions (rtol 1e-8).
  RegisterBenchmark("EKF/double-pendulum/n4m2/cvodes-rtol1e-8", Ekf_<DP, DP::Angles>,
                    Integrator::kCvodes)
      ->Unit(us);
  RegisterBenchmark("UKF/double-pendulum/n4m2/cvodes-rtol1e-8", Sigma_<DP, DP::Angles>,
                    Integrator::kCvodes, SigmaRule::kUnscented)
      ->Unit(us);
  RegisterBenchmark("Floor/double-pendulum/cvodes-with-sensitivities/x1", Transitions_<DP>, 1, true,
                    Integrator::kCvodes)
      ->Unit(us);
}

}  // namespace

void Register() { RegisterAll(); }

}  // namespace estlab

int main(int argc, char** argv) {
  estlab::Register();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
