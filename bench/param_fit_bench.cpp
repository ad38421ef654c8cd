// Benchmarks of the physical-parameter fit (`estlab tune --estimate-param`)
// on the real single-pendulum recording (examples/data/multiarm/single, 4
// training pieces of 9167 samples, built-in pendulum, angle only, EKF):
//
//   JointFit/...            one full fit of L, b, qc, R (the issue's <= 5 s)
//   Likelihood/.../nll      one NLL evaluation (double)
//   Likelihood/.../gradient one NLL + exact gradient in the 4 parameters
//                           (fixed-step: one Jet<4> pass with nested Jets;
//                           cvodes: one pass of CVODES forward sensitivities
//                           in the 4 directions, of the state and of the
//                           EKF's variational system)
//
//   build/bench/estlab_bench --benchmark_filter='JointFit|Likelihood'
//       --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//       --benchmark_report_aggregates_only=true
// gradient / nll of the same integrator is the cost of one gradient in NLLs.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "adaptive/likelihood.h"
#include "adaptive/tuner_impl.h"
#include "models/pendulum.h"
#include "src/options/column_map.h"
#include "src/options/filter_flags.h"
#include "src/registry/registry.h"

namespace estlab {
namespace {

using P = models::Pendulum;

std::vector<FilterData> Recording() {
  const ModelEntry& model = FindModel("pendulum");
  const MeasurementDesc& meas = model.FindMeasurement("angle");
  const std::vector<ColumnMap> columns = {ParseColumnMap("z_theta=theta-pi")};
  std::vector<FilterData> data;
  for (int i = 1; i <= 4; ++i)
    data.push_back(cli::LoadFilterData(std::string(ESTLAB_SOURCE_DIR) +
                                           "/examples/data/multiarm/single/train_" +
                                           std::to_string(i) + ".csv",
                                       model, meas, columns, false));
  return data;
}

FilterSpec Spec(Integrator integrator) {
  FilterSpec spec;
  spec.params = {9.81, 0.15, 0.05};
  spec.measurement = "angle";
  spec.filter = EkfOptions{};
  spec.transition.integrator = integrator;
  spec.x0 = {0.0, 0.0};
  spec.x0_first_sample = true;
  spec.p0 = {0.01, 0.0, 0.0, 100.0};
  spec.q_white_accel = true;
  spec.qc = 1.0;
  spec.r = {1e-6};
  return spec;
}

TunerOptions Options() {
  TunerOptions o;
  o.q_param = NoiseParam::kWhiteAccel;
  o.burn_in = 50;
  o.estimate = {{.name = "L"}, {.name = "b"}};
  return o;
}

void JointFit(benchmark::State& state, Integrator integrator) {
  const std::vector<FilterData> data = Recording();
  const ModelEntry& model = FindModel("pendulum");
  int iterations = 0;
  for (auto _ : state) {
    const TuneResult r = model.tune(Spec(integrator), Options(), data);
    if (!r.IsSolutionUsable()) {
      state.SkipWithError(r.message.c_str());
      return;
    }
    iterations = r.iterations;
    benchmark::DoNotOptimize(r.nll_tuned);
  }
  state.counters["lbfgs_iterations"] = iterations;
}

// Four starts of the RK4 joint fit (spread over L, b, qc, R) on `jobs`
// threads: the jobs-2 / jobs-1 wall ratio of issue 33 (<= 0.6).
void JointFitStarts(benchmark::State& state, int jobs) {
  const std::vector<FilterData> data = Recording();
  const ModelEntry& model = FindModel("pendulum");
  TunerOptions o = Options();
  o.starts = 4;
  o.jobs = jobs;
  for (auto _ : state) {
    const TuneResult r = model.tune(Spec(Integrator::kRk4), o, data);
    if (!r.IsSolutionUsable()) {
      state.SkipWithError(r.message.c_str());
      return;
    }
    benchmark::DoNotOptimize(r.nll_tuned);
  }
}

void Likelihood(benchmark::State& state, Integrator integrator, bool gradient) {
  const std::vector<FilterData> data = Recording();
  const InnovationLikelihood<P, P::Angle> lik(Spec(integrator), Options(), data);
  const tuner_internal::Objective<P, P::Angle> objective(lik);
  // At the optimum of the 4-piece fit (docs/real-data.md).
  const std::vector<double> theta = {std::log(0.00115663), std::log(1.50346e-09),
                                     std::log(0.153156), 0.0555174};
  std::vector<double> g(theta.size());
  for (auto _ : state) {
    double f = 0.0;
    const bool ok = objective.ValueAndGradient(theta.data(), &f, gradient ? g.data() : nullptr);
    if (!ok) {
      state.SkipWithError("the filter failed");
      return;
    }
    benchmark::DoNotOptimize(f);
  }
}

const auto kMs = benchmark::kMillisecond;
BENCHMARK_CAPTURE(JointFit, rk4, Integrator::kRk4)
    ->Name("JointFit/pendulum/single-recording-4x9167/ekf-rk4/L-b-qc-r")
    ->Unit(kMs)
    ->Iterations(1);
BENCHMARK_CAPTURE(JointFit, cvodes, Integrator::kCvodes)
    ->Name("JointFit/pendulum/single-recording-4x9167/ekf-cvodes/L-b-qc-r")
    ->Unit(kMs)
    ->Iterations(1);
BENCHMARK_CAPTURE(JointFitStarts, jobs1, 1)
    ->Name("JointFit/pendulum/single-recording-4x9167/ekf-rk4/L-b-qc-r/starts4/jobs1")
    ->Unit(kMs)
    ->Iterations(1)
    ->UseRealTime();
BENCHMARK_CAPTURE(JointFitStarts, jobs2, 2)
    ->Name("JointFit/pendulum/single-recording-4x9167/ekf-rk4/L-b-qc-r/starts4/jobs2")
    ->Unit(kMs)
    ->Iterations(1)
    ->UseRealTime();
BENCHMARK_CAPTURE(Likelihood, rk4_nll, Integrator::kRk4, false)
    ->Name("Likelihood/pendulum/single-recording/ekf-rk4/nll")
    ->Unit(kMs);
BENCHMARK_CAPTURE(Likelihood, rk4_gradient, Integrator::kRk4, true)
    ->Name("Likelihood/pendulum/single-recording/ekf-rk4/gradient-4-params")
    ->Unit(kMs);
BENCHMARK_CAPTURE(Likelihood, cvodes_nll, Integrator::kCvodes, false)
    ->Name("Likelihood/pendulum/single-recording/ekf-cvodes/nll")
    ->Unit(kMs)
    ->Iterations(2);
BENCHMARK_CAPTURE(Likelihood, cvodes_gradient, Integrator::kCvodes, true)
    ->Name("Likelihood/pendulum/single-recording/ekf-cvodes/gradient-4-params")
    ->Unit(kMs)
    ->Iterations(1);

}  // namespace
}  // namespace estlab
