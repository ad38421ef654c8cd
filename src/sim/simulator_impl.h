// Truth simulation: integrate a model from x0 over [0, t_end] with output
// every dt, optionally adding process noise to the state after each output
// step and measurement noise to the chosen measurement.
//
//   x_{k+1} = Phi(x_k; t_k, t_{k+1}) + w_k,  w_k ~ N(0, diag(process_noise_var))
//   z_k     = h(x_k) + v_k,                  v_k ~ N(0, diag(meas_noise_var))
//
// Noise is drawn from one Rng(seed): first the measurement noise of row 0,
// then for each step the process noise and the measurement noise of the new
// row, so the same seed always gives the same file.
#ifndef ESTLAB_SIM_SIMULATOR_IMPL_H_
#define ESTLAB_SIM_SIMULATOR_IMPL_H_

#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "models/model_traits.h"
#include "src/core/random.h"
#include "src/ode/transition.h"
#include "src/sim/simulation.h"

namespace estlab {

template <class Model>
SimulationResult Simulate(const SimulationSpec& spec) {
  constexpr int N = Model::kStateDim;
  using State = Vec<double, N>;
  const auto start = std::chrono::steady_clock::now();
  const typename Model::Params params = ParamsFromVector<Model>(spec.params);

  SimulationResult result;
  result.columns.push_back("t");
  for (const char* s : Model::kStateNames) result.columns.push_back(s);

  // Type-erased measurement with noise.
  std::vector<double> (*measure)(const State&, const typename Model::Params&) = nullptr;
  VisitMeasurement<Model>(spec.measurement, [&](auto m) {
    using Meas = decltype(m);
    for (const char* o : Meas::kOutputs) result.columns.push_back(std::string("z_") + o);
    measure = [](const State& x, const typename Model::Params& p) {
      const Vec<double, Meas::kDim> z = Meas::template Eval<double>(x, p);
      return std::vector<double>(z.data(), z.data() + Meas::kDim);
    };
  });

  Rng rng(spec.seed);
  auto make_row = [&](double t, const State& x) {
    std::vector<double> row;
    row.push_back(t);
    for (int i = 0; i < N; ++i) row.push_back(x(i));
    if (measure != nullptr) {
      std::vector<double> z = measure(x, params);
      for (size_t j = 0; j < z.size(); ++j) {
        if (!spec.meas_noise_var.empty()) z[j] += std::sqrt(spec.meas_noise_var[j]) * rng.Normal();
        row.push_back(z[j]);
      }
    }
    return row;
  };

  // Process noise w = L n with L L^T = Q (diagonal variances or a full PSD
  // covariance; the symmetric square root handles semi-definite Q).
  Mat<N, N> noise_factor = Mat<N, N>::Zero();
  bool has_process_noise = false;
  if (!spec.process_noise_cov.empty()) {
    Mat<N, N> Q;
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) Q(i, j) = spec.process_noise_cov[i * N + j];
    Eigen::SelfAdjointEigenSolver<Mat<N, N>> eig(0.5 * (Q + Q.transpose()));
    noise_factor = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() *
                   eig.eigenvectors().transpose();
    has_process_noise = true;
  } else if (!spec.process_noise_var.empty()) {
    for (int i = 0; i < N; ++i) noise_factor(i, i) = std::sqrt(spec.process_noise_var[i]);
    has_process_noise = true;
  }
  const bool track_invariants = Model::kInvariantNames.size() > 0 &&
                                Model::InvariantsHold(params, spec.input) && !has_process_noise;
  auto transition = MakeTransition<Model>(params, spec.transition);
  transition->SetInput(spec.input);

  State x = ToVec<N>(spec.x0);
  const auto inv0 = Model::Invariants(x, params);
  std::vector<double> drift(Model::kInvariantNames.size(), 0.0);

  // Output times t_k = k dt, the last one clipped to t_end.
  const long steps = std::max(0L, long(std::ceil(spec.t_end / spec.dt - 1e-9)));
  result.rows.reserve(steps + 1);
  result.rows.push_back(make_row(0.0, x));
  for (long k = 0; k < steps; ++k) {
    const double t0 = k * spec.dt;
    const double t1 = std::min(spec.t_end, (k + 1) * spec.dt);
    try {
      x = transition->Step(x, t0, t1);
    } catch (const NumericalError& e) {
      result.ok = false;
      result.error = e.what();
      break;
    }
    if (!x.allFinite()) {
      result.ok = false;
      result.error = "state became non-finite at t = " + std::to_string(t1);
      break;
    }
    if (has_process_noise) {
      Vec<double, N> n;
      for (int i = 0; i < N; ++i) n(i) = rng.Normal();
      x += noise_factor * n;
    }
    if (track_invariants) {
      const auto inv = Model::Invariants(x, params);
      for (int j = 0; j < inv.size(); ++j) {
        const double scale = std::abs(inv0(j)) > 0 ? std::abs(inv0(j)) : 1.0;
        drift[j] = std::max(drift[j], std::abs(inv(j) - inv0(j)) / scale);
      }
    }
    result.rows.push_back(make_row(t1, x));
    ++result.steps;
  }
  if (track_invariants) {
    for (size_t j = 0; j < Model::kInvariantNames.size(); ++j) {
      result.invariant_names.push_back(Model::kInvariantNames[j]);
      result.invariant_initial.push_back(inv0(j));
      result.invariant_drift.push_back(drift[j]);
    }
  }
  result.stats = transition->stats();
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace estlab

#endif  // ESTLAB_SIM_SIMULATOR_IMPL_H_
