// Compile-time helpers over a model's measurement list and parameter table.
#ifndef ESTLAB_MODELS_MODEL_TRAITS_H_
#define ESTLAB_MODELS_MODEL_TRAITS_H_

#include <string>
#include <tuple>
#include <vector>

#include "src/core/types.h"

namespace estlab {

// Calls fn(Meas{}) for every measurement type of Model.
template <class Model, class Fn>
void ForEachMeasurement(Fn&& fn) {
  std::apply([&](auto... m) { (fn(m), ...); }, typename Model::Measurements{});
}

// Calls fn(Meas{}) for the measurement named `name`; returns false if none.
template <class Model, class Fn>
bool VisitMeasurement(const std::string& name, Fn&& fn) {
  bool found = false;
  ForEachMeasurement<Model>([&](auto m) {
    if (!found && name == decltype(m)::kName) {
      found = true;
      fn(m);
    }
  });
  return found;
}

template <class Model>
typename Model::Params ParamsFromVector(const std::vector<double>& values) {
  typename Model::Params p;
  for (size_t i = 0; i < Model::kParams.size() && i < values.size(); ++i)
    p.*(Model::kParams[i].member) = values[i];
  return p;
}

template <int N>
Vec<double, N> ToVec(const std::vector<double>& v) {
  Vec<double, N> x;
  for (int i = 0; i < N; ++i) x(i) = v[i];
  return x;
}

}  // namespace estlab

#endif  // ESTLAB_MODELS_MODEL_TRAITS_H_
