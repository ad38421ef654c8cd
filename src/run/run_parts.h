// Which parts of the filter runner and the simulator a model's code holds
// (issue 38). A built-in model, `estlab model build` and a study compile
// them all (AllRunParts). A model file's first `filter`, `smooth` or
// `simulate` compiles only what that command runs, into a library of its
// own in the model cache (src/registry/model_plugin.cpp): one measurement,
// one filter class, the noise adapter and the smoother only when the
// command uses them. Instantiating the filter templates for the model's
// types is most of a compile (docs/models.md), so that library builds in a
// third of the time of the whole entry, with the same code, hence the same
// numbers.
//
// A parts type has
//   static constexpr const char* kMeasurement;  // nullptr, or a sensor group's
//                                               // name: every measurement
//   static constexpr int kFilter;               // index in FilterKindOptions,
//                                               // -1: every class, -2: none
//   static constexpr bool kAdapt, kSmooth, kSimulate;
// A run that asks for a part its library lacks is refused with a
// std::logic_error (the loader picks the library from the same request).
#ifndef ESTLAB_RUN_RUN_PARTS_H_
#define ESTLAB_RUN_RUN_PARTS_H_

#include <cstddef>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <variant>

#include "src/run/filter_kinds.h"

namespace estlab {

struct AllRunParts {
  static constexpr const char* kMeasurement = nullptr;
  static constexpr int kFilter = -1;
  static constexpr bool kAdapt = true, kSmooth = true, kSimulate = true;
};

// The index of Options in FilterKindOptions.
template <class Options, size_t I = 0>
constexpr int FilterOptionsIndex() {
  if constexpr (I == std::variant_size_v<FilterKindOptions>) {
    return -1;
  } else if constexpr (std::is_same_v<Options, std::variant_alternative_t<I, FilterKindOptions>>) {
    return int(I);
  } else {
    return FilterOptionsIndex<Options, I + 1>();
  }
}

// Whether `name` is one of Model's measurements (not a sensor group's name).
template <class Model, size_t... I>
constexpr bool NamesAMeasurement(std::string_view name, std::index_sequence<I...>) {
  return (
      (std::string_view(std::tuple_element_t<I, typename Model::Measurements>::kName) == name) ||
      ...);
}

// Whether Meas's runner is compiled: every measurement's when kMeasurement
// is null or names none of them (a sensor group).
template <class Parts, class Model, class Meas>
constexpr bool HasMeasurement() {
  if constexpr (Parts::kMeasurement == nullptr) {
    return true;
  } else {
    constexpr size_t kCount = std::tuple_size_v<typename Model::Measurements>;
    return !NamesAMeasurement<Model>(Parts::kMeasurement, std::make_index_sequence<kCount>()) ||
           std::string_view(Parts::kMeasurement) == Meas::kName;
  }
}

template <class Parts, class Options>
constexpr bool HasFilter() {
  return Parts::kFilter == -1 || Parts::kFilter == FilterOptionsIndex<Options>();
}

}  // namespace estlab

#endif  // ESTLAB_RUN_RUN_PARTS_H_
