// The model registry: every model's metadata (states, parameters,
// measurements) and its per-model entry points, so the CLI can pick a model by
// name without including any model template.
//
// Usage:
//   const ModelEntry& m = FindModel("double-pendulum");   // throws InputError
//   const ModelEntry& f = FindModel("examples/models/pendulum.model", {.tuner = true});
//   std::vector<double> p = m.ResolveParams({{"L1", 2.0}});
//
// Adding a model: one header in models/ (satisfying DynamicModel,
// models/model.h) and one line in models/model_list.cmake; CMake generates
// its entry (MakeModelEntry<Model>()) and its tuner translation units.
#ifndef ESTLAB_REGISTRY_REGISTRY_H_
#define ESTLAB_REGISTRY_REGISTRY_H_

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/tuner.h"
#include "src/core/params.h"
#include "src/ode/transition.h"
#include "src/run/filter_spec.h"
#include "src/sim/simulation.h"

namespace estlab {

struct ParamDesc {
  std::string name;
  double default_value;
  std::string description;
  Constraint constraint;
};

// A sensor group: outputs [first, first + count) of its measurement.
struct OutputGroup {
  std::string name;
  int first = 0;
  int count = 0;
};

struct MeasurementDesc {
  std::string name;
  std::vector<std::string> outputs;
  std::vector<bool> angle_outputs;
  // Its sensor groups (models/model.h, kGroups); empty: one sensor.
  std::vector<OutputGroup> groups;
  // The group of a name, or null.
  const OutputGroup* FindGroup(const std::string& group) const;
};

struct ModelEntry {
  std::string name;
  std::string description;
  std::vector<std::string> states;
  std::vector<bool> angle_states;
  std::vector<std::string> state_units;                  // "" = dimensionless
  std::vector<std::pair<int, int>> position_rate_pairs;  // (position, rate) state indices
  std::vector<ParamDesc> params;
  std::vector<MeasurementDesc> measurements;
  std::vector<std::string> invariants;
  // The inputs (empty: none): their names, which are their data columns
  // (a single input may also be read from a column "u"), and units.
  std::vector<std::string> inputs;
  std::vector<std::string> input_units;
  bool has_input() const { return !inputs.empty(); }
  bool stiff = false;
  bool discrete_time = false;  // a step map x(t + dt) (Integrator::kDiscrete only)

  SimulationResult (*simulate)(const SimulationSpec&) = nullptr;
  FilterRunOutput (*run_filter)(const FilterSpec&, const FilterData&) = nullptr;
  // Q/R tuning by maximum innovation likelihood (adaptive/tuner.h).
  TuneResult (*tune)(const FilterSpec&, const TunerOptions&,
                     const std::vector<FilterData>&) = nullptr;

  // Defaults with "name=value" overrides applied and validated; throws
  // InputError naming an unknown or invalid parameter.
  std::vector<double> ResolveParams(
      const std::vector<std::pair<std::string, double>>& overrides) const;
  // Full state from "name=value" pairs (unnamed states are 0).
  std::vector<double> ResolveState(const std::vector<std::pair<std::string, double>>& values,
                                   const std::string& option) const;
  // A measurement by its name, or by its sensor groups' names, comma-
  // separated in any order ("imu,gps" for a measurement with the groups
  // gps and imu); throws InputError naming what is unknown, repeated or
  // missing.
  const MeasurementDesc& FindMeasurement(const std::string& name) const;
  // "" when `integrator` can run this model, else why not: discrete-time
  // models and integrators (CheckIntegratorForModel), and semi-implicit
  // Euler for a model with a state in no (position, rate) pair (it would
  // leave that state frozen).
  std::string CheckIntegrator(Integrator integrator) const;
  int StateIndex(const std::string& name) const;  // -1 when unknown
};

// The built-in models (models/model_list.cmake), then linked ones (linked_models.h).
const std::vector<const ModelEntry*>& AllModels();

// One command's share of a model file's code (src/run/run_parts.h): a
// `filter`, `smooth` or `simulate` of a model file whose whole entry is not
// in the cache compiles only these parts, into a library of their own.
struct RunNeeds {
  std::string measurement = "";  // its name; "": every measurement
  int filter = -1;               // index in FilterKindOptions; -1: every class, -2: none
  bool adapt = false, smooth = false, simulate = false;
};

// What a command needs of a model compiled from a file (model_plugin.h).
struct ModelNeeds {
  bool tuner = false;  // the Q/R tuner as well (compiled on its first use)
  // Unset: the whole entry (every filter, the simulator).
  std::optional<RunNeeds> run = std::nullopt;
};
// A built-in model by name, or a model file: a path to a .model or .h file,
// or a name found on ESTLAB_MODEL_PATH (compiled on first use, cached).
// Throws InputError naming the known models (and see linked_models.h).
const ModelEntry& FindModel(const std::string& name, ModelNeeds needs = {});

}  // namespace estlab

#endif  // ESTLAB_REGISTRY_REGISTRY_H_
