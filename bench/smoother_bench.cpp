// Benchmarks of the RTS smoother (src/filters/rts_smoother.h) against the
// forward filter it smooths (issue 13: RTS at most 1.5x the forward filter):
// the pendulum (angle measured, RK4, dt 0.01) over 2000 steps,
//
//   Forward/<kind>/...     the filter alone over the 2000 steps
//   ForwardRts/<kind>/...  the same filter, recording its moments, plus the
//                          backward pass
//
//   build/bench/estlab_bench --benchmark_filter='Forward'
//       --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//       --benchmark_report_aggregates_only=true
// ForwardRts / Forward of the same kind is the smoother's cost.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>
#include <string>

#include "models/pendulum.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/rts_smoother.h"
#include "src/filters/sigma_point.h"
#include "src/ode/transition_impl.h"

namespace estlab {
namespace {

using P = models::Pendulum;
constexpr int kSteps = 2000;
constexpr double kDt = 0.01;

std::unique_ptr<Filter<P, P::Angle>> Make(const std::string& kind, Transition<P>* tr) {
  const P::Params params;
  if (kind == "kf") {
    KfOptions o;
    o.operating_point = {0.0, 0.0};
    return std::make_unique<LinearizedKf<P, P::Angle>>(params, o);
  }
  if (kind == "ekf") return std::make_unique<Ekf<P, P::Angle>>(tr, params, EkfOptions{});
  SigmaPointOptions o;
  o.rule = kind == "ukf" ? SigmaRule::kUnscented : SigmaRule::kCubature;
  o.alpha = 0.5;
  return std::make_unique<SigmaPointFilter<P, P::Angle>>(tr, params, o);
}

void Run(benchmark::State& state, const std::string& kind, bool smooth) {
  TransitionOptions topt;
  topt.integrator = Integrator::kRk4;
  auto transition = MakeTransition<P>(P::Params{}, topt);
  auto filter = Make(kind, transition.get());
  const Mat<2, 2> Q = 1e-4 * Mat<2, 2>::Identity();
  const Mat<1, 1> R = Mat<1, 1>::Constant(1e-2);
  RtsSmoother<2> rts;
  rts.Reserve(kSteps);
  for (auto _ : state) {
    rts.Clear();
    filter->Initialize(Vec<double, 2>(0.5, 0.0), 0.01 * Mat<2, 2>::Identity());
    for (int k = 0; k < kSteps; ++k) {
      if (k > 0) {
        filter->Predict((k - 1) * kDt, k * kDt, Q);
        if (smooth) {
          Mat<2, 2> C = Mat<2, 2>::Zero();
          filter->PredictCrossCov(&C);
          rts.AddPredicted(filter->mean(), filter->cov(), C);
        }
      }
      const Vec<double, 1> z(0.5 * std::cos(3.13 * k * kDt));
      benchmark::DoNotOptimize(filter->Update(z, R).log_likelihood);
      if (smooth) rts.AddFiltered(filter->mean(), filter->cov());
    }
    if (smooth) {
      std::string why;
      if (!rts.Smooth(&why)) {
        state.SkipWithError(why.c_str());
        return;
      }
      benchmark::DoNotOptimize(rts.mean(0));
    }
  }
  state.SetItemsProcessed(state.iterations() * kSteps);
}

void RegisterSmootherBenchmarks() {
  for (const char* kind : {"kf", "ekf", "ukf", "ckf"}) {
    const std::string suffix = std::string(kind) + "/pendulum/n2m1/rk4/2000-steps";
    benchmark::RegisterBenchmark(("Forward/" + suffix).c_str(), [kind](benchmark::State& s) {
      Run(s, kind, false);
    })->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("ForwardRts/" + suffix).c_str(), [kind](benchmark::State& s) {
      Run(s, kind, true);
    })->Unit(benchmark::kMicrosecond);
  }
}
const bool kRegistered = (RegisterSmootherBenchmarks(), true);

}  // namespace
}  // namespace estlab
