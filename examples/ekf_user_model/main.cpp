// Runs an EKF on a model that estlab_add_model built into this program
// (damped_pendulum.model, CMakeLists.txt), through estlab's library API:
//
//   1. FindModel("damped-pendulum"): the model registered itself (its
//      generated entry.cpp), so it is found by name like a built-in model;
//   2. simulate 10 s of truth with process noise and noisy measurements of
//      the bob's horizontal position x = L sin(theta) (sigma 2 cm);
//   3. run the EKF (RK4 transitions, AD Jacobians) from a wrong initial guess;
//   4. print the RMSE of each state against the truth, and of the angle read
//      off each measurement alone (theta = asin(x / L)).
//
// Exit status 0 when the EKF's angle RMSE is below half that of the
// measurements alone and below 0.01 rad (a filter that ignored the
// measurements, or whose Jacobian was wrong, does not get there), else 1.
#include <cmath>
#include <cstdio>
#include <exception>
#include <vector>

#include "src/registry/registry.h"

namespace {

constexpr double kMeasSigma = 0.02;  // [m]

estlab::SimulationResult SimulateTruth(const estlab::ModelEntry& model) {
  estlab::SimulationSpec sim;
  sim.params = model.ResolveParams({});
  sim.x0 = model.ResolveState({{"theta", 1.0}}, "x0");
  sim.t_end = 10.0;
  sim.dt = 0.01;
  sim.transition.integrator = estlab::Integrator::kRk4;
  sim.process_noise_var = {1e-8, 1e-5};
  sim.measurement = "x";
  sim.meas_noise_var = {kMeasSigma * kMeasSigma};
  sim.seed = 2024;
  return model.simulate(sim);
}

// The simulation's rows (t, theta, omega, z_x) as filter data with truth.
estlab::FilterData ToFilterData(const estlab::SimulationResult& s) {
  estlab::FilterData d;
  d.m = 1;
  d.has_truth = true;
  for (const std::vector<double>& row : s.rows) {
    d.t.push_back(row[0]);
    d.lines.push_back(long(d.t.size()) + 1);
    d.truth.insert(d.truth.end(), {row[1], row[2]});
    d.z.push_back(row[3]);
  }
  return d;
}

estlab::FilterSpec EkfSpec(const estlab::ModelEntry& model) {
  estlab::FilterSpec spec;
  spec.params = model.ResolveParams({});
  spec.measurement = "x";
  spec.filter = estlab::EkfOptions{};
  spec.transition.integrator = estlab::Integrator::kRk4;
  spec.x0 = {0.7, 0.5};  // truth: 1.0, 0
  spec.p0 = {0.1, 0.0, 0.0, 0.5};
  spec.q = {1e-8, 0.0, 0.0, 1e-5};
  spec.r = {kMeasSigma * kMeasSigma};
  return spec;
}

// RMSE of theta = asin(z / L) against the true theta.
double MeasurementOnlyRmse(const estlab::FilterData& d, double length) {
  double sum = 0.0;
  for (size_t k = 0; k < d.t.size(); ++k) {
    const double e = std::asin(std::fmax(-1.0, std::fmin(1.0, d.z[k] / length))) - d.truth[2 * k];
    sum += e * e;
  }
  return std::sqrt(sum / double(d.t.size()));
}

}  // namespace

int main() {
  try {
    const estlab::ModelEntry& model = estlab::FindModel("damped-pendulum");
    const estlab::SimulationResult truth = SimulateTruth(model);
    if (!truth.ok) {
      std::fprintf(stderr, "ekf_user_model: simulation failed: %s\n", truth.error.c_str());
      return 1;
    }
    const estlab::FilterData data = ToFilterData(truth);
    const estlab::FilterRunOutput out = model.run_filter(EkfSpec(model), data);
    const estlab::FilterSummary& s = out.summary;
    if (!s.ok) {
      std::fprintf(stderr, "ekf_user_model: filter failed: %s\n", s.message.c_str());
      return 1;
    }
    const double length = model.ResolveParams({})[1];  // L
    const double raw = MeasurementOnlyRmse(data, length);
    std::printf("model %s (%s), %ld steps, %s\n", model.name.c_str(), model.description.c_str(),
                s.steps, s.filter.c_str());
    for (size_t i = 0; i < s.states.size(); ++i)
      std::printf("  RMSE %-6s %.5f\n", s.states[i].c_str(), s.rmse[i]);
    std::printf("  RMSE theta from the measurements alone %.5f\n", raw);
    const bool pass = s.rmse[0] < 0.5 * raw && s.rmse[0] < 0.01;
    std::printf("%s: EKF theta RMSE %s 0.5 x measurements-alone and 0.01 rad\n",
                pass ? "ok" : "FAILED", pass ? "below" : "not below");
    return pass ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ekf_user_model: error: %s\n", e.what());
    return 2;
  }
}
