// Truth simulation: integrate a model from x0 over [0, t_end] with output
// every dt (or over a recorded schedule of times and held inputs),
// optionally adding process noise to the state after each output
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

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "models/model_traits.h"
#include "src/core/random.h"
#include "src/filters/symmetric_eigen.h"
#include "src/ode/transition.h"
#include "src/sim/simulation.h"

namespace estlab {

// The output times: spec.times when given, else t_k = k dt up to t_end (the
// last one clipped to t_end).
inline std::vector<double> OutputTimes(const SimulationSpec& spec) {
  if (!spec.times.empty()) return spec.times;
  const long steps = std::max(0L, long(std::ceil(spec.t_end / spec.dt - 1e-9)));
  std::vector<double> times(size_t(steps) + 1);
  for (long k = 0; k <= steps; ++k) times[k] = std::min(spec.t_end, k * spec.dt);
  return times;
}

// The nu input values held over [times[k], times[k+1]) (null: the zero
// input).
inline const double* InputAt(const SimulationSpec& spec, size_t k, int nu) {
  if (nu > 0 && spec.inputs.size() >= size_t(nu)) {
    const size_t rows = spec.inputs.size() / size_t(nu);
    return &spec.inputs[std::min(k, rows - 1) * size_t(nu)];
  }
  return spec.input.size() == size_t(nu) && nu > 0 ? spec.input.data() : nullptr;
}

// Process noise w = L n with L L^T = Q (diagonal variances or a full PSD
// covariance; the symmetric square root handles semi-definite Q); false
// when the spec has none.
template <int N>
bool ProcessNoiseFactor(const SimulationSpec& spec, Mat<N, N>* factor) {
  factor->setZero();
  if (!spec.process_noise_cov.empty()) {
    Mat<N, N> Q;
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) Q(i, j) = spec.process_noise_cov[i * N + j];
    const Mat<N, N> sym = 0.5 * (Q + Q.transpose());
    Vec<double, N> values;
    Mat<N, N> vectors;
    SymmetricEigen<N>(sym, &values, &vectors);
    *factor = vectors * values.cwiseMax(0.0).cwiseSqrt().asDiagonal() * vectors.transpose();
    return true;
  }
  if (spec.process_noise_var.empty()) return false;
  for (int i = 0; i < N; ++i) (*factor)(i, i) = std::sqrt(spec.process_noise_var[i]);
  return true;
}

template <class Model>
SimulationResult Simulate(const SimulationSpec& spec) {
  constexpr int N = Model::kStateDim;
  using State = Vec<double, N>;
  const auto start = std::chrono::steady_clock::now();
  const typename Model::Params params = ParamsFromVector<Model>(spec.params);
  const std::vector<double> times = OutputTimes(spec);

  SimulationResult result;
  result.columns.push_back("t");
  for (const char* s : Model::kStateNames) result.columns.push_back(s);
  for (const std::string& name : spec.input_columns) result.columns.push_back(name);
  constexpr int nu = kInputDim<Model>;
  if (!spec.input.empty() && spec.input.size() != size_t(nu))
    throw InputError("input: " + std::to_string(spec.input.size()) + " values for model " +
                     Model::kName + " with " + std::to_string(nu) + " inputs");
  if (nu == 0 ? !spec.inputs.empty() : spec.inputs.size() % size_t(nu) != 0)
    throw InputError("the recorded inputs do not come in rows of " + std::to_string(nu));

  // Type-erased measurement.
  std::vector<double> (*measure)(double, const State&, const InputOf<Model>&,
                                 const typename Model::Params&) = nullptr;
  VisitMeasurement<Model>(spec.measurement, [&](auto m) {
    using Meas = decltype(m);
    if (!spec.output_every.empty() &&
        (spec.output_every.size() != size_t(Meas::kDim) ||
         *std::min_element(spec.output_every.begin(), spec.output_every.end()) < 1))
      throw InputError("sensor rates: one period >= 1 row per output of '" +
                       std::string(Meas::kName) + "'");
    for (const char* o : Meas::kOutputs) result.columns.push_back(std::string("z_") + o);
    if (spec.noise_free_outputs)
      for (const char* o : Meas::kOutputs) result.columns.push_back(std::string("y_") + o);
    measure = [](double t, const State& x, const InputOf<Model>& u,
                 const typename Model::Params& p) {
      const Vec<double, Meas::kDim> z = EvalMeasurement<Model, Meas, double>(t, x, u, p);
      return std::vector<double>(z.data(), z.data() + Meas::kDim);
    };
  });

  Rng rng(spec.seed);
  auto make_row = [&](size_t k, const State& x) {
    std::vector<double> row;
    row.push_back(times[k]);
    for (int i = 0; i < N; ++i) row.push_back(x(i));
    const InputOf<Model> u = InputFrom<Model>(InputAt(spec, k, nu));
    if (!spec.input_columns.empty())
      for (int i = 0; i < nu; ++i) row.push_back(InputComponent<Model>(u, i));
    if (measure != nullptr) {
      const std::vector<double> y = measure(times[k], x, u, params);
      for (size_t j = 0; j < y.size(); ++j) {
        double z = y[j];
        if (!spec.meas_noise_var.empty()) z += std::sqrt(spec.meas_noise_var[j]) * rng.Normal();
        if (!spec.output_every.empty() && k % size_t(spec.output_every[j]) != 0)
          z = std::numeric_limits<double>::quiet_NaN();  // not sampled in this row
        row.push_back(z);
      }
      if (spec.noise_free_outputs) row.insert(row.end(), y.begin(), y.end());
    }
    return row;
  };

  Mat<N, N> noise_factor;
  const bool has_process_noise = ProcessNoiseFactor<N>(spec, &noise_factor);
  const InputOf<Model> u0 = InputFrom<Model>(InputAt(spec, 0, nu));
  const bool track_invariants = Model::kInvariantNames.size() > 0 && spec.inputs.empty() &&
                                Model::InvariantsHold(params, u0) && !has_process_noise;
  auto transition = MakeTransition<Model>(params, spec.transition);
  transition->SetInput(u0);

  State x = ToVec<N>(spec.x0);
  const auto inv0 = Model::Invariants(x, params);
  std::vector<double> drift(Model::kInvariantNames.size(), 0.0);

  result.rows.reserve(times.size());
  result.rows.push_back(make_row(0, x));
  for (size_t k = 0; k + 1 < times.size(); ++k) {
    const double t0 = times[k], t1 = times[k + 1];
    try {
      // u_k held over [t_k, t_k+1), or the line to u_k+1 (linear hold).
      const InputOf<Model> u_k = InputFrom<Model>(InputAt(spec, k, nu));
      transition->SetInput(u_k, spec.transition.input_hold == InputHold::kLinear
                                    ? InputFrom<Model>(InputAt(spec, k + 1, nu))
                                    : u_k);
      if (t1 > t0) x = transition->Step(x, t0, t1);
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
    if (has_process_noise && t1 > t0) {
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
    result.rows.push_back(make_row(k + 1, x));
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
