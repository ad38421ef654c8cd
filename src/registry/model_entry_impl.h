// Builds a model's registry entry from its compile-time description. Include
// only from the generated build/generated/models_inst/<model>.cpp
// (models/model_list.cmake).
#ifndef ESTLAB_REGISTRY_MODEL_ENTRY_IMPL_H_
#define ESTLAB_REGISTRY_MODEL_ENTRY_IMPL_H_

#include "adaptive/tuner.h"
#include "models/model.h"
#include "models/model_traits.h"
#include "src/ode/transition_impl.h"
#include "src/registry/registry.h"
#include "src/run/filter_run_impl.h"
#include "src/sim/simulator_impl.h"

namespace estlab {

// kWithTuner = false leaves `tune` null: a model library compiled at run
// time (model_plugin.cpp) compiles its tuner separately, on first use.
// Parts (src/run/run_parts.h): the filter runner's parts compiled, and
// whether the simulator is (else `simulate` is null; the description is
// always whole).
template <DynamicModel Model, bool kWithTuner = true, class Parts = AllRunParts>
requires kAllMeasurementsOf<Model> ModelEntry MakeModelEntry() {
  ModelEntry e;
  e.name = Model::kName;
  e.description = Model::kDescription;
  for (int i = 0; i < Model::kStateDim; ++i) {
    e.states.push_back(Model::kStateNames[i]);
    e.angle_states.push_back(Model::kAngleStates[i]);
    e.state_units.push_back(Model::kStateUnits[i]);
  }
  const typename Model::Params defaults{};
  for (const auto& spec : Model::kParams)
    e.params.push_back({spec.name, defaults.*(spec.member), spec.description, spec.constraint});
  ForEachMeasurement<Model>([&](auto m) {
    using Meas = decltype(m);
    MeasurementDesc d;
    d.name = Meas::kName;
    for (int j = 0; j < Meas::kDim; ++j) {
      d.outputs.push_back(Meas::kOutputs[j]);
      d.angle_outputs.push_back(Meas::kAngleOutputs[j]);
    }
    for (const OutputGroupSpec& g : MeasurementGroups<Meas>())
      d.groups.push_back({g.name, g.first, g.count});
    e.measurements.push_back(d);
  });
  for (const char* s : Model::kInvariantNames) e.invariants.push_back(s);
  for (int i = 0; i < kInputDim<Model>; ++i) {
    e.inputs.push_back(InputName<Model>(i));
    e.input_units.push_back(InputUnit<Model>(i));
  }
  e.stiff = Model::kStiff;
  e.discrete_time = kDiscreteTime<Model>;
  for (const auto& pair : Model::kPositionRatePairs) e.position_rate_pairs.push_back(pair);
  if constexpr (Parts::kSimulate) e.simulate = &Simulate<Model>;
  if constexpr (kWithTuner) e.tune = &TuneModel<Model>;  // generated tune/tune_<model>.cpp
  if constexpr (Parts::kFilter != -2) e.run_filter = &RunFilter<Model, Parts>;
  return e;
}

}  // namespace estlab

#define ESTLAB_DEFINE_MODEL_ENTRY(Model, EntryFn)                                    \
  template std::unique_ptr<estlab::Transition<Model>> estlab::MakeTransition<Model>( \
      const Model::Params&, const estlab::TransitionOptions&);                       \
  namespace estlab {                                                                 \
  const ModelEntry& EntryFn() {                                                      \
    static const ModelEntry entry = MakeModelEntry<Model>();                         \
    return entry;                                                                    \
  }                                                                                  \
  }

// The entry point of a model library compiled at run time (model_plugin.cpp).
#define ESTLAB_DEFINE_MODEL_PLUGIN(Model)                                           \
  extern "C" const estlab::ModelEntry* estlab_model_entry_v1() {                    \
    static const estlab::ModelEntry entry = estlab::MakeModelEntry<Model, false>(); \
    return &entry;                                                                  \
  }

// The entry point of a model library compiled at run time for one command
// (model_plugin.cpp): only the parts of the runner it needs.
#define ESTLAB_DEFINE_MODEL_PARTS_PLUGIN(Model, Parts)                                     \
  extern "C" const estlab::ModelEntry* estlab_model_entry_v1() {                           \
    static const estlab::ModelEntry entry = estlab::MakeModelEntry<Model, false, Parts>(); \
    return &entry;                                                                         \
  }

#endif  // ESTLAB_REGISTRY_MODEL_ENTRY_IMPL_H_
