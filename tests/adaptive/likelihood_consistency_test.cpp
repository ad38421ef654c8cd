// The tuner's innovation likelihood is the filters' own: for every model x
// measurement x Gaussian filter kind in the registry, the NLL the tuner
// computes at fixed Q, R (TuneResult::nll_initial, no parameters) equals
// minus the sum of the log-likelihoods of `estlab filter`'s run
// (FilterSummary::loglik) on the same data, to 1e-10 relative. The data has a
// time-varying input column for the input models (cart-pole, DIPC), and
// measurements with several angle outputs are included (every measurement of
// every model is).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/registry/registry.h"
#include "src/run/filter_spec.h"

namespace estlab::testing {
namespace {

constexpr int kSteps = 120;
constexpr double kDt = 0.01;

std::vector<double> Diagonal(int n, double v) {
  std::vector<double> m(n * n, 0.0);
  for (int i = 0; i < n; ++i) m[i * n + i] = v;
  return m;
}

// RK4 with two substeps; CVODES (BDF) for a stiff model (van der Pol: RK4 at
// dt = 0.01 is unstable), in the simulation and in both filter runs.
TransitionOptions Transition(const ModelEntry& model) {
  TransitionOptions o;
  o.integrator = model.stiff ? Integrator::kCvodes : Integrator::kRk4;
  o.substeps = 2;
  return o;
}

// Measurements of `meas` simulated from the model's defaults, x0 = 0.2 on
// every state (a small swing), process and measurement noise.
FilterData Simulated(const ModelEntry& model, const MeasurementDesc& meas) {
  const int n = int(model.states.size());
  const int m = int(meas.outputs.size());
  SimulationSpec sim;
  sim.params = model.ResolveParams({});
  sim.x0.assign(n, 0.2);
  sim.t_end = kSteps * kDt;
  sim.dt = kDt;
  sim.transition = Transition(model);
  sim.process_noise_var.assign(n, 1e-5);
  sim.measurement = meas.name;
  sim.meas_noise_var.assign(m, 1e-3);
  sim.seed = 7;
  const SimulationResult r = model.simulate(sim);
  FilterData d;
  if (!r.ok || r.rows.size() < 10) {
    ADD_FAILURE() << model.name << ": " << r.error;
    return d;
  }
  d.path = model.name + "/" + meas.name;
  d.m = m;
  for (size_t k = 0; k < r.rows.size(); ++k) {
    d.t.push_back(r.rows[k][0]);
    d.lines.push_back(long(k) + 2);
    for (int j = 0; j < m; ++j) d.z.push_back(r.rows[k][1 + n + j]);
    if (model.has_input()) d.u.push_back(0.3 * std::sin(3.0 * d.t.back()));
  }
  d.nu = model.has_input() ? 1 : 0;
  d.z[5 * m] = std::nan("");  // one missing measurement: no update there
  return d;
}

struct Kind {
  const char* label;
  FilterKind kind;
  int iterations;
  bool redraw;
};
constexpr Kind kKinds[] = {
    {"kf", FilterKind::kKf, 1, true},
    {"ekf", FilterKind::kEkf, 1, true},
    {"iekf", FilterKind::kEkf, 3, true},
    {"ukf", FilterKind::kUkf, 1, true},
    {"ukf-propagate", FilterKind::kUkf, 1, false},
    {"ckf", FilterKind::kCkf, 1, true},
    {"ghkf", FilterKind::kGhkf, 1, true},
};

FilterSpec Spec(const ModelEntry& model, const MeasurementDesc& meas, const Kind& kind) {
  const int n = int(model.states.size());
  const int m = int(meas.outputs.size());
  FilterSpec spec;
  spec.params = model.ResolveParams({});
  spec.measurement = meas.name;
  spec.filter = DefaultFilterOptions(kind.kind);
  if (auto* ekf = std::get_if<EkfOptions>(&spec.filter)) ekf->iterations = kind.iterations;
  if (auto* sigma = std::get_if<SigmaPointOptions>(&spec.filter)) {
    sigma->update =
        kind.redraw ? SigmaPointOptions::Update::kRedraw : SigmaPointOptions::Update::kPropagate;
    sigma->alpha = 0.5;
  }
  spec.transition = Transition(model);
  spec.x0.assign(n, 0.15);
  spec.p0 = Diagonal(n, 0.05);
  spec.q = Diagonal(n, 1e-4);
  spec.r = Diagonal(m, 2e-3);
  return spec;
}

TEST(LikelihoodConsistency, NllEqualsMinusTheFiltersSummedLogLikelihood) {
  TunerOptions options;
  options.q_param = NoiseParam::kFixed;
  options.r_param = NoiseParam::kFixed;
  options.compute_std_errors = false;
  double worst = 0.0;
  int cases = 0, failed = 0;
  for (const ModelEntry* model : AllModels()) {
    for (const MeasurementDesc& meas : model->measurements) {
      const std::vector<FilterData> data = {Simulated(*model, meas)};
      if (data[0].t.empty()) continue;
      for (const Kind& kind : kKinds) {
        const FilterSpec spec = Spec(*model, meas, kind);
        const FilterRunOutput run = model->run_filter(spec, data[0]);
        const std::string label = model->name + " " + meas.name + " " + kind.label;
        const TuneResult tuned = model->tune(spec, options, data);
        if (!run.summary.ok) {
          // The filter fails (the van der Pol KF, linearised once at x0 of a
          // stiff model, loses positive definiteness): so must the likelihood.
          EXPECT_TRUE(std::isinf(tuned.nll_initial)) << label << ": " << run.summary.message;
          ++failed;
          continue;
        }
        ASSERT_TRUE(std::isfinite(tuned.nll_initial)) << label;
        const double rel =
            std::abs(tuned.nll_initial + run.summary.loglik) / std::abs(run.summary.loglik);
        EXPECT_LT(rel, 1e-10) << label << ": NLL " << tuned.nll_initial << ", filter loglik "
                              << run.summary.loglik;
        worst = std::max(worst, rel);
        ++cases;
      }
    }
  }
  std::printf(
      "NLL vs -sum loglik: %d cases, worst relative difference %.3g; %d cases where "
      "both the filter and the likelihood fail\n",
      cases, worst, failed);
  EXPECT_GE(cases, 50);  // 8 measurements x 7 kinds = 56, less the failing ones
  EXPECT_LE(failed, 2);
}

}  // namespace
}  // namespace estlab::testing
