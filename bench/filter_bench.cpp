// Benchmarks of issue "Performance": filter steps (one predict + update per
// iteration) beside the bare transition evaluations the step needs, which
// are the arithmetic floor the filter is compared with; the likelihood tuner
// (8-parameter double pendulum, 2000 steps); two studies end to end.
//
//   make bench    # Release build, writes bench/results/latest.json and
//                 # bench/results/latest.md (a short table)
//   build/bench/estlab_bench --benchmark_filter='UKF|Floor'
//       --benchmark_repetitions=5 --benchmark_report_aggregates_only=true   (one line)
//
// Names: <Filter>/<model>/n<states>m<outputs>/<integrator>[/particles],
// Tuner/..., Study/<name>/jobs<k>. `double-pendulum-file` is
// examples/models/double_pendulum.model, built in by estlab_add_model (the
// user-model path; bit-identical numbers): its rows against the built-in's,
// interleaved, give the cost of a user model
//   build/bench/estlab_bench --benchmark_filter='^(EKF|UKF|RunFilter)/double-pendulum(-file)?/'
//       --benchmark_repetitions=10 --benchmark_enable_random_interleaving=true
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "estlab_bench_dp_file/model.h"  // generated (bench/CMakeLists.txt)
#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/particle.h"
#include "src/filters/sigma_point.h"
#include "src/ode/transition_impl.h"
#include "src/registry/registry.h"
#include "studies/config/study_config.h"
#include "studies/run/study_runner.h"

namespace estlab {
namespace {

// Constant velocity in 2-D with measured positions: the cheap 4x2 model of
// the LowLevelParticleFilters.jl comparison (0.35 us per UKF step there).
struct ConstantVelocity2d {
  static constexpr const char* kName = "cv2d";
  static constexpr const char* kDescription = "constant velocity in 2-D";
  static constexpr int kStateDim = 4;
  static constexpr int kInputDim = 0;
  static constexpr bool kStiff = false;
  static constexpr bool kPacketRhs = true;  // branch-free (src/core/packet.h)
  static constexpr std::array<const char*, 4> kStateNames = {"px", "vx", "py", "vy"};
  static constexpr std::array<const char*, 4> kStateUnits = {"m", "m/s", "m", "m/s"};
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
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 4>&, const Params&) { return {}; }
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

// A cart driven by a DC motor (examples/dc_cart/dc_cart.model), position and
// motor current measured (the current sees the voltage: h(x, u)), with the
// motor voltage only (Inputs = 1) or also a load force (Inputs = 2): the
// same size, for the cost of a second input (issue 34, done-when 5).
template <int Inputs>
struct DcCartBench {
  static constexpr const char* kName = "dc-cart-bench";
  static constexpr const char* kDescription = "DC-motor cart";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = Inputs;
  static constexpr std::array<const char*, Inputs> kInputNames = [] {
    if constexpr (Inputs == 1)
      return std::array<const char*, 1>{"V"};
    else
      return std::array<const char*, 2>{"V", "F"};
  }();
  static constexpr std::array<const char*, Inputs> kInputUnits = [] {
    if constexpr (Inputs == 1)
      return std::array<const char*, 1>{"V"};
    else
      return std::array<const char*, 2>{"V", "N"};
  }();
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 2> kStateNames = {"x", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};
  using Input = InputOf<DcCartBench>;
  struct Params {
    double m = 2.0, b = 3.0, K = 0.05, R = 1.5, r = 0.02;
  };
  static constexpr std::array<ParamSpec<Params>, 1> kParams = {
      {{"m", &Params::m, "mass [kg]", Constraint::kPositive}}};
  static double Voltage(const Input& u) { return InputComponent<DcCartBench>(u, 0); }
  static double Load(const Input& u) {
    return Inputs > 1 ? InputComponent<DcCartBench>(u, Inputs - 1) : 0.0;
  }
  template <class T>
  static Vec<T, 2> Rhs(const T&, const Vec<T, 2>& x, const Input& u, const Params& p) {
    const T i = (Voltage(u) - p.K * x(1) / p.r) / p.R;
    return Vec<T, 2>(x(1), (p.K * i / p.r - p.b * x(1) + Load(u)) / p.m);
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, const Input&) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) { return {}; }
  struct EncoderCurrent {
    static constexpr const char* kName = "encoder-current";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"x", "current"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const Input& u, const Params& p) {
      return Vec<T, 2>(x(0), (Voltage(u) - p.K * x(1) / p.r) / p.R);
    }
  };
  using Measurements = std::tuple<EncoderCurrent>;
};

template <class Model>
Vec<double, Model::kStateDim> StartState() {
  Vec<double, Model::kStateDim> x = Vec<double, Model::kStateDim>::Zero();
  x(0) = 0.7;
  if (Model::kStateDim > 2) x(2) = 0.5;
  return x;
}

// Runs predict + update on a fixed measurement that the filter tracks, so the
// state stays bounded over millions of iterations. missing >= 0: that
// component of z is missing (NaN) in every other step, the subset update of
// a slower sensor's gap (src/filters/missing.h), with the state held where
// the full row holds it (a component never observed would let its estimate
// drift, and large angles cost sin/cos more).
template <class Model, class Meas, class MakeFilter>
void FilterStep(benchmark::State& state, Integrator integrator, MakeFilter make, int missing = -1) {
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
  const Vec<double, M> z =
      EvalMeasurement<Model, Meas, double>(0.0, x0, transition->input(), params);
  Vec<double, M> z_gap = z;
  if (missing >= 0) z_gap(missing) = std::numeric_limits<double>::quiet_NaN();
  filter->Initialize(x0, P0);
  const double dt = 0.01;
  double t = 0.0;
  long steps = 0;
  for (auto _ : state) {
    filter->Predict(t, t + dt, Q);
    auto r = filter->Update(steps % 2 ? z_gap : z, R);
    benchmark::DoNotOptimize(r.log_likelihood);
    t += dt;
    if (++steps % 1000 == 0) {  // restart so the belief never drifts away
      filter->Initialize(x0, P0);
      t = 0.0;
    }
  }
  state.SetItemsProcessed(state.iterations());
}

// The *Gap_ forms leave component `missing` of z out of every update.
template <class Model, class Meas>
void EkfGap_(benchmark::State& s, Integrator integrator, int missing) {
  FilterStep<Model, Meas>(
      s, integrator,
      [](Transition<Model>* tr, const auto& p) {
        return std::make_unique<Ekf<Model, Meas>>(tr, p, EkfOptions{});
      },
      missing);
}
// The EKF with a constant nonzero input (1 V, and 0.5 N for a second input).
template <class Model, class Meas>
void EkfInput_(benchmark::State& s) {
  FilterStep<Model, Meas>(s, Integrator::kRk4, [](Transition<Model>* tr, const auto& p) {
    const double u[2] = {1.0, 0.5};
    tr->SetInput(InputFrom<Model>(u));
    return std::make_unique<Ekf<Model, Meas>>(tr, p, EkfOptions{});
  });
}
// The same with a linear hold: the input ramps over every step from (1 V,
// 0.5 N) to (1.2 V, 0.4 N), evaluated at each RK4 stage.
template <class Model, class Meas>
void EkfInputLinear_(benchmark::State& s) {
  FilterStep<Model, Meas>(s, Integrator::kRk4, [](Transition<Model>* tr, const auto& p) {
    const double u0[2] = {1.0, 0.5}, u1[2] = {1.2, 0.4};
    tr->SetInput(InputFrom<Model>(u0), InputFrom<Model>(u1));
    return std::make_unique<Ekf<Model, Meas>>(tr, p, EkfOptions{});
  });
}
template <class Model, class Meas>
void KfGap_(benchmark::State& s, int missing) {
  FilterStep<Model, Meas>(
      s, Integrator::kRk4,
      [](Transition<Model>*, const auto& p) {
        KfOptions o;
        o.operating_point.assign(Model::kStateDim, 0.0);
        return std::make_unique<LinearizedKf<Model, Meas>>(p, o);
      },
      missing);
}
template <class Model, class Meas>
void SigmaGap_(benchmark::State& s, Integrator integrator, SigmaRule rule, int missing) {
  FilterStep<Model, Meas>(
      s, integrator,
      [rule](Transition<Model>* tr, const auto& p) {
        SigmaPointOptions o;
        o.rule = rule;
        o.gh_order = 3;
        return std::make_unique<SigmaPointFilter<Model, Meas>>(tr, p, o);
      },
      missing);
}
template <class Model, class Meas>
void PfGap_(benchmark::State& s, int missing) {
  FilterStep<Model, Meas>(
      s, Integrator::kRk4,
      [&s](Transition<Model>* tr, const auto& p) {
        ParticleOptions o;
        o.num_particles = int(s.range(0));
        o.resample = ResampleScheme::kSystematic;
        o.ess_threshold = 1.0;  // resample every step
        return std::make_unique<ParticleFilter<Model, Meas>>(tr, p, o);
      },
      missing);
}
template <class Model, class Meas>
void Ekf_(benchmark::State& s, Integrator integrator) {
  EkfGap_<Model, Meas>(s, integrator, -1);
}
template <class Model, class Meas>
void Kf_(benchmark::State& s) {
  KfGap_<Model, Meas>(s, -1);
}
template <class Model, class Meas>
void Sigma_(benchmark::State& s, Integrator integrator, SigmaRule rule) {
  SigmaGap_<Model, Meas>(s, integrator, rule, -1);
}
template <class Model, class Meas>
void Pf_(benchmark::State& s) {
  PfGap_<Model, Meas>(s, -1);
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

// The tuner test's problem (tests/adaptive/tuner_test.cpp,
// TunerDoublePendulum): 2000 RK4 steps of the double pendulum with full-state
// measurements, UKF (alpha 1), diagonal Q and R (8 log parameters), started a
// factor `guess` (100 or 0.01) away from the true variances. One iteration
// is one full tune (one start); with `std_errors` false the Hessian of the
// standard errors is skipped, leaving the time to converge (the common-scale
// pre-search and L-BFGS).
void Tuner_(benchmark::State& state, double guess, bool std_errors, int jobs) {
  const ModelEntry& model = FindModel("double-pendulum");
  SimulationSpec sim;
  sim.params = model.ResolveParams({});
  const double pi = 3.14159265358979323846;
  sim.x0 = {pi / 4, 0.0, pi / 6, 0.0};
  sim.dt = 0.01;
  sim.t_end = 19.99;  // 2000 rows
  sim.transition.integrator = Integrator::kRk4;
  const std::vector<double> q_true = {1e-6, 1e-4, 1e-6, 1e-4};
  const std::vector<double> r_true = {0.05 * 0.05, 0.03 * 0.03, 0.04 * 0.04, 0.02 * 0.02};
  sim.process_noise_var = q_true;
  sim.measurement = "full";
  sim.meas_noise_var = r_true;
  sim.seed = 71;
  const SimulationResult s = model.simulate(sim);
  if (!s.ok || s.rows.size() != 2000u) {
    state.SkipWithError("simulation failed");
    return;
  }
  FilterData d;
  d.m = 4;
  for (const auto& row : s.rows) {
    d.t.push_back(row[0]);
    d.lines.push_back(long(d.t.size()) + 1);
    for (int j = 0; j < 4; ++j) d.z.push_back(row[5 + j]);
  }
  const std::vector<FilterData> data = {d};
  FilterSpec spec;
  spec.params = sim.params;
  spec.measurement = "full";
  spec.filter = SigmaPointOptions{.rule = SigmaRule::kUnscented, .alpha = 1.0};
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = sim.x0;
  spec.p0.assign(16, 0.0);
  for (int i = 0; i < 4; ++i) spec.p0[i * 5] = 1e-4;
  spec.q.assign(16, 0.0);
  spec.r.assign(16, 0.0);
  for (int i = 0; i < 4; ++i) {
    spec.q[i * 5] = guess * q_true[i];
    spec.r[i * 5] = guess * r_true[i];
  }
  TunerOptions options;
  options.q_param = NoiseParam::kDiag;
  options.r_param = NoiseParam::kDiag;
  options.compute_std_errors = std_errors;
  options.jobs = jobs;  // one start: the gradient's three passes in parallel
  int iterations = 0;
  for (auto _ : state) {
    const TuneResult r = model.tune(spec, options, data);
    if (!r.IsSolutionUsable()) {
      state.SkipWithError(("tune failed: " + r.message).c_str());
      return;
    }
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.nll_tuned);
  }
  state.counters["lbfgs_iterations"] = iterations;
}

// A study end to end (engine API, as `estlab study CONFIG --jobs k`) into a
// fresh temporary folder per iteration, progress off.
void Study_(benchmark::State& state, const std::string& file, int jobs) {
  namespace fs = std::filesystem;
  StudyConfig config;
  try {
    config = LoadStudyConfig(std::string(ESTLAB_SOURCE_DIR) + "/studies/" + file);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const fs::path out =
      fs::temp_directory_path() / ("estlab_bench_study_" + std::to_string(::getpid()));
  long runs = 0;
  for (auto _ : state) {
    fs::remove_all(out);
    StudyRunOptions options;
    options.out_dir = out.string();
    options.jobs = jobs;
    options.progress = false;
    const StudyRunSummary summary = RunStudy(config, options);
    if (summary.finished_runs != summary.total_runs) {
      state.SkipWithError("study did not finish");
      break;
    }
    runs = summary.total_runs;
  }
  fs::remove_all(out);
  state.counters["runs"] = double(runs);
}

// One filter run through the model's registry entry (ModelEntry::run_filter:
// the code in its entry translation unit, the generated one of the built-in
// or the entry.cpp of estlab_add_model), over `steps` steps of data
// simulated once with RK4; items = steps.
// `measurement` has two outputs; `every` their sensor periods in rows (empty:
// every row; src/sim/simulation.h).
void RunFilter_(benchmark::State& state, const std::string& model_name, FilterKindOptions kind,
                const std::string& measurement, std::vector<int> every) {
  const ModelEntry& model = FindModel(model_name);
  SimulationSpec sim;
  sim.params = model.ResolveParams({});
  sim.x0 = {0.7, 0.0, 0.5, 0.0};
  sim.dt = 0.01;
  sim.t_end = 9.99;  // 1000 rows
  sim.transition.integrator = Integrator::kRk4;
  sim.process_noise_var = {1e-6, 1e-4, 1e-6, 1e-4};
  sim.measurement = measurement;
  sim.meas_noise_var = {1e-2, 1e-2};
  sim.output_every = every;
  const SimulationResult s = model.simulate(sim);
  FilterData d;
  d.m = 2;
  for (const auto& row : s.rows) {
    d.t.push_back(row[0]);
    d.lines.push_back(long(d.t.size()) + 1);
    d.z.insert(d.z.end(), {row[5], row[6]});
  }
  FilterSpec spec;
  spec.params = sim.params;
  spec.measurement = measurement;
  spec.filter = kind;
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = sim.x0;
  spec.p0 = {1e-2, 0, 0, 0, 0, 1e-2, 0, 0, 0, 0, 1e-2, 0, 0, 0, 0, 1e-2};
  spec.q = {1e-6, 0, 0, 0, 0, 1e-4, 0, 0, 0, 0, 1e-6, 0, 0, 0, 0, 1e-4};
  spec.r = {1e-2, 0, 0, 1e-2};
  for (auto _ : state) {
    const FilterRunOutput out = model.run_filter(spec, d);
    if (!out.summary.ok) {
      state.SkipWithError(out.summary.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(out.summary.loglik);
  }
  state.SetItemsProcessed(state.iterations() * long(d.t.size()));
}

using models::DoublePendulum;
using models::Pendulum;
using DpFile = user_models::DoublePendulumFileModel;
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
  // One input against two on a model of the same size (the EKF step; the
  // current sensor sees the voltage).
  using Dc1 = DcCartBench<1>;
  using Dc2 = DcCartBench<2>;
  RegisterBenchmark("EKF/dc-cart/n2m2/one-input/rk4", EkfInput_<Dc1, Dc1::EncoderCurrent>);
  RegisterBenchmark("EKF/dc-cart/n2m2/two-inputs/rk4", EkfInput_<Dc2, Dc2::EncoderCurrent>);
  RegisterBenchmark("EKF/dc-cart/n2m2/two-inputs-linear-hold/rk4",
                    EkfInputLinear_<Dc2, Dc2::EncoderCurrent>);
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
  // One of the two angles missing in every other step (a slower sensor's gap):
  // the subset update on the full-size matrices (src/filters/missing.h).
  RegisterBenchmark("KF/double-pendulum/n4m2/rk4/theta2-every-other-step", KfGap_<DP, DP::Angles>,
                    1);
  RegisterBenchmark("EKF/double-pendulum/n4m2/rk4/theta2-every-other-step", EkfGap_<DP, DP::Angles>,
                    rk4, 1);
  RegisterBenchmark("UKF/double-pendulum/n4m2/rk4/theta2-every-other-step",
                    SigmaGap_<DP, DP::Angles>, rk4, SigmaRule::kUnscented, 1);
  RegisterBenchmark("PF/double-pendulum/n4m2/rk4/systematic-every-step/theta2-every-other-step",
                    PfGap_<DP, DP::Angles>, 1)
      ->Arg(1000)
      ->Unit(us);
  RegisterBenchmark("Floor/double-pendulum/rk4-with-jacobian/x1", Transitions_<DP>, 1, true, rk4);
  RegisterBenchmark("Floor/double-pendulum/rk4/x9", Transitions_<DP>, 9, false, rk4);
  // The same model from examples/models/double_pendulum.model (estlab_add_model).
  RegisterBenchmark("EKF/double-pendulum-file/n4m2/rk4", Ekf_<DpFile, DpFile::AnglesMeasurement>,
                    rk4);
  RegisterBenchmark("UKF/double-pendulum-file/n4m2/rk4", Sigma_<DpFile, DpFile::AnglesMeasurement>,
                    rk4, SigmaRule::kUnscented);
  // Whole runs through the registry entries (1000 steps), built-in and file.
  for (const char* name : {"double-pendulum", "double-pendulum-file"}) {
    RegisterBenchmark((std::string("RunFilter/") + name + "/ekf-rk4/1000-steps").c_str(),
                      RunFilter_, std::string(name), FilterKindOptions{EkfOptions{}},
                      std::string("angles"), std::vector<int>{})
        ->Unit(us);
    RegisterBenchmark((std::string("RunFilter/") + name + "/ukf-rk4/1000-steps").c_str(),
                      RunFilter_, std::string(name), FilterKindOptions{SigmaPointOptions{}},
                      std::string("angles"), std::vector<int>{})
        ->Unit(us);
  }
  // A measurement of two sensor groups (cart-pole x-theta: position and
  // encoder, each group's NIS tallied): both every row, and the position in
  // every tenth row only.
  for (const bool gaps : {false, true}) {
    const std::vector<int> every = gaps ? std::vector<int>{10, 1} : std::vector<int>{};
    const std::string tail = gaps ? "/position-every-10th" : "/all-observed";
    RegisterBenchmark(("RunFilter/cart-pole/ekf-rk4/1000-steps" + tail).c_str(), RunFilter_,
                      std::string("cart-pole"), FilterKindOptions{EkfOptions{}},
                      std::string("x-theta"), every)
        ->Unit(us);
    RegisterBenchmark(("RunFilter/cart-pole/ukf-rk4/1000-steps" + tail).c_str(), RunFilter_,
                      std::string("cart-pole"), FilterKindOptions{SigmaPointOptions{}},
                      std::string("x-theta"), every)
        ->Unit(us);
  }
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
  // Tuner: 8 parameters (diagonal Q and R), 2000 steps, UKF with RK4.
  const auto ms = benchmark::kMillisecond;
  // jobs2: one start on two threads (adaptive/tuner_objective.h: the double
  // run and the two chunks of Jets of each gradient in parallel).
  for (bool std_errors : {true, false})
    for (double guess : {100.0, 0.01})
      for (int jobs : {1, 2})
        RegisterBenchmark(
            (std::string("Tuner/double-pendulum/ukf-rk4/diag-q-r-8-params/2000-steps/guess-x") +
             (guess > 1 ? "100" : "0.01") + (std_errors ? "/with-std-errors" : "/converge") +
             (jobs > 1 ? "/jobs2" : ""))
                .c_str(),
            Tuner_, guess, std_errors, jobs)
            ->Unit(ms)
            ->Iterations(1)
            ->MeasureProcessCPUTime()  // worker threads
            ->UseRealTime();
  // Studies end to end; wall time is the figure (threads).
  for (const char* study : {"paper000_noise_grid", "paper002_pendulum_mc"})
    for (int jobs : {1, 2})
      RegisterBenchmark((std::string("Study/") + study + "/jobs" + std::to_string(jobs)).c_str(),
                        Study_, std::string(study) + ".ini", jobs)
          ->Unit(ms)
          ->Iterations(1)
          ->MeasureProcessCPUTime()  // worker threads
          ->UseRealTime();
}

// Console output as usual, plus a Markdown table of every run (or of the
// medians when repeated) written to `path` at the end.
class TableReporter : public benchmark::ConsoleReporter {
 public:
  // Colours only on a terminal (a custom display reporter does not read
  // --benchmark_color).
  explicit TableReporter(std::string path)
      : ConsoleReporter(isatty(STDOUT_FILENO) ? OO_Defaults : OO_Tabular), path_(std::move(path)) {}
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name != "median") continue;
      if (r.error_occurred) continue;
      rows_.push_back(r);
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    if (path_.empty()) return;
    // Keep medians when there are any for a benchmark, else the single run.
    std::map<std::string, bool> has_median;
    for (const Run& r : rows_)
      if (r.run_type == Run::RT_Aggregate) has_median[r.run_name.str()] = true;
    std::ofstream out(path_);
    out << "| benchmark | real time | CPU time | iterations |\n|---|---:|---:|---:|\n";
    for (const Run& r : rows_) {
      if (r.run_type != Run::RT_Aggregate && has_median.count(r.run_name.str())) continue;
      const char* unit = benchmark::GetTimeUnitString(r.time_unit);
      char line[512];
      std::snprintf(line, sizeof line, "| %s | %.4g %s | %.4g %s | %lld |\n",
                    r.benchmark_name().c_str(), r.GetAdjustedRealTime(), unit,
                    r.GetAdjustedCPUTime(), unit, static_cast<long long>(r.iterations));
      out << line;
    }
  }

 private:
  std::string path_;
  std::vector<Run> rows_;
};

}  // namespace

void Register() { RegisterAll(); }

}  // namespace estlab

// With --benchmark_out=X.json the table goes to X.md.
int main(int argc, char** argv) {
  estlab::Register();
  std::string table;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const std::string key = "--benchmark_out=";
    if (a.rfind(key, 0) == 0) {
      table = a.substr(key.size());
      const auto dot = table.rfind(".json");
      table = (dot == std::string::npos ? table : table.substr(0, dot)) + ".md";
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  estlab::TableReporter reporter(table);
  benchmark::RunSpecifiedBenchmarks(&reporter);
  if (!table.empty()) std::printf("table: %s\n", table.c_str());
  benchmark::Shutdown();
  return 0;
}
