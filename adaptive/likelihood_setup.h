// What InnovationLikelihood (likelihood.h) checks and derives before it
// runs: the spec and the datasets (CheckSpec: the tuner's own conditions,
// IsTunable, then sizes and measurement coverage), the reference step of the
// data, and the initial Q and R in the form of noise_param.h.
#ifndef ESTLAB_ADAPTIVE_LIKELIHOOD_SETUP_H_
#define ESTLAB_ADAPTIVE_LIKELIHOOD_SETUP_H_

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/noise_param.h"
#include "adaptive/tuner.h"
#include "models/model.h"
#include "src/core/types.h"
#include "src/run/filter_spec.h"
#include "src/run/step_loop.h"

namespace estlab {

namespace likelihood_internal {

// Median of the positive time steps of a dataset (0 when it has none).
inline double MedianStep(const FilterData& data) {
  std::vector<double> steps;
  for (size_t k = 1; k < data.t.size(); ++k)
    if (data.t[k] > data.t[k - 1]) steps.push_back(data.t[k] - data.t[k - 1]);
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

template <class Model>
std::vector<std::pair<int, int>> Pairs() {
  std::vector<std::pair<int, int>> out;
  for (const auto& p : Model::kPositionRatePairs) out.push_back(p);
  return out;
}

template <int D>
InitialCovariance<D> InitialFromVector(const std::vector<double>& v, const std::string& what) {
  if (v.size() != size_t(D) * D) {
    throw InputError("the initial " + what + " has " + std::to_string(v.size()) +
                     " entries, expected " + std::to_string(D) + " x " + std::to_string(D));
  }
  InitialCovariance<D> c;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) c.matrix(i, j) = v[i * D + j];
  return c;
}

template <class Model>
InitialCovariance<Model::kStateDim> InitialQ(const FilterSpec& spec) {
  if (spec.q_white_accel) {
    InitialCovariance<Model::kStateDim> c;
    if (!(spec.qc >= 0 && std::isfinite(spec.qc)))
      throw InputError("the initial qc must be finite and >= 0, got " + FormatNumber(spec.qc));
    c.white_accel = true;
    c.qc = spec.qc;
    return c;
  }
  return InitialFromVector<Model::kStateDim>(spec.q, "Q");
}

template <class Model>
std::vector<std::string> StateNames() {
  std::vector<std::string> out;
  for (const char* s : Model::kStateNames) out.push_back(s);
  return out;
}
template <class Meas>
std::vector<std::string> OutputNames() {
  std::vector<std::string> out;
  for (const char* s : Meas::kOutputs) out.push_back(s);
  return out;
}

// R's blocks for options.r_param_groups (one per sensor group of Meas, in
// output order), or none; throws InputError naming an unknown, repeated or
// missing group.
template <class Meas>
std::vector<CovarianceBlock> RBlocks(const TunerOptions& options) {
  if (options.r_param_groups.empty()) return {};
  std::string known;
  for (const OutputGroupSpec& g : MeasurementGroups<Meas>())
    known += (known.empty() ? "" : ", ") + std::string(g.name);
  if (known.empty()) {
    throw InputError(std::string("--r-param: measurement '") + Meas::kName +
                     "' has no sensor groups: give one kind for all of R");
  }
  for (const auto& [name, kind] : options.r_param_groups) {
    bool found = false;
    for (const OutputGroupSpec& g : MeasurementGroups<Meas>()) found = found || name == g.name;
    if (!found)
      throw InputError("--r-param: unknown sensor group '" + name + "' (groups of " + Meas::kName +
                       ": " + known + ")");
  }
  std::vector<CovarianceBlock> blocks;
  for (const OutputGroupSpec& g : MeasurementGroups<Meas>()) {
    const NoiseParam* kind = nullptr;
    for (const auto& [name, k] : options.r_param_groups)
      if (name == g.name) kind = &k;
    if (kind == nullptr)
      throw InputError(std::string("--r-param: no kind for sensor group '") + g.name +
                       "' (give every group of " + Meas::kName + ": " + known + ")");
    blocks.push_back({*kind, g.first, g.count, g.name});
  }
  return blocks;
}

// Checks the spec before anything is built from it.
template <class Model, class Meas>
const FilterSpec& CheckSpec(const FilterSpec& spec, const TunerOptions& options,
                            const std::vector<FilterData>& datasets) {
  std::string error;
  if (!IsTunable(spec, options, Model::kStateDim, &error)) throw InputError(error);
  error = CheckIntegratorForModel(spec.transition.integrator, kDiscreteTime<Model>, Model::kName);
  if (!error.empty()) throw InputError(error);
  if (spec.x0.size() != size_t(Model::kStateDim))
    throw InputError("x0 has " + std::to_string(spec.x0.size()) + " entries, expected " +
                     std::to_string(Model::kStateDim));
  if (spec.p0.size() != size_t(Model::kStateDim) * Model::kStateDim)
    throw InputError("P0 has the wrong size");
  if (datasets.empty()) throw InputError("the tuner needs at least one dataset");
  for (const FilterData& d : datasets) {
    const std::string name = d.path.empty() ? "a dataset" : d.path;
    if (d.m != Meas::kDim || d.z.size() != d.t.size() * size_t(Meas::kDim))
      throw InputError(name + ": measurement columns do not match '" + std::string(Meas::kName) +
                       "'");
    if (const std::string why = CheckInputWidths(spec, d, kInputDim<Model>); !why.empty())
      throw InputError(why);
    long updates = 0;
    std::vector<long> finite(Meas::kDim, 0);
    for (size_t k = 0; k < d.t.size(); ++k) {
      for (int j = 0; j < Meas::kDim; ++j) finite[j] += std::isfinite(d.z[k * Meas::kDim + j]);
      updates += RowUpdates(d, k);  // the observed components of a partial row update
    }
    for (int j = 0; j < Meas::kDim; ++j) {
      if (finite[j] == 0)
        throw InputError(name + ": measurement column z_" + std::string(Meas::kOutputs[j]) +
                         " has no value (all missing)");
    }
    if (updates <= options.burn_in) {
      throw InputError(name + ": " + std::to_string(updates) +
                       " measurement updates, not more than the burn-in of " +
                       std::to_string(options.burn_in));
    }
  }
  return spec;
}

}  // namespace likelihood_internal

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_LIKELIHOOD_SETUP_H_
