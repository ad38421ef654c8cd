#include "src/registry/registry.h"

#include <cmath>

#include "src/core/parse.h"
#include "src/registry/linked_models.h"
#include "src/registry/model_plugin.h"

namespace estlab {

// The entries of the model list (models/model_list.cmake), each defined in
// its generated translation unit (ESTLAB_DEFINE_MODEL_ENTRY).
#define ESTLAB_MODEL(Type, stem) const ModelEntry& Type##Entry();
#include "estlab_model_list.inc"
#undef ESTLAB_MODEL

namespace {

// Filled during static initialisation (a function-local static, so the
// order of the translation units' initialisers does not matter).
std::vector<const ModelEntry& (*)()>& LinkedEntries() {
  static std::vector<const ModelEntry& (*)()> entries;
  return entries;
}

std::string Join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

bool RegisterLinkedModel(const ModelEntry& (*entry)()) {
  LinkedEntries().push_back(entry);
  return true;
}

const std::vector<const ModelEntry*>& AllModels() {
  static std::vector<const ModelEntry*> models = {
#define ESTLAB_MODEL(Type, stem) &Type##Entry(),
#include "estlab_model_list.inc"
#undef ESTLAB_MODEL
  };
  static size_t linked = 0;  // the linked entries appended so far
  for (; linked < LinkedEntries().size(); ++linked) models.push_back(&LinkedEntries()[linked]());
  return models;
}

const ModelEntry& FindModel(const std::string& name, ModelNeeds needs) {
  std::vector<std::string> names;
  const ModelEntry* found = nullptr;
  for (const ModelEntry* m : AllModels()) {
    if (m->name == name && found != nullptr)
      throw InputError("model '" + name + "' is defined twice (a linked model named like " +
                       "another; rename one in its file)");
    if (m->name == name) found = m;
    names.push_back(m->name);
  }
  if (found != nullptr && needs.tuner && found->tune == nullptr)
    throw InputError("model '" + name + "' was linked without its tuner (estlab_add_model(" +
                     "... TUNER), docs/models.md)");
  if (found != nullptr) return *found;
  if (const std::string path = ResolveModelPath(name); !path.empty())
    return LoadModelFile(path, needs);
  if (IsModelPath(name)) throw InputError("model file '" + name + "' not found");
  throw InputError("unknown model '" + name + "' (known: " + Join(names) +
                   "; or a .model / .h file, see docs/models.md)");
}

std::vector<double> ModelEntry::ResolveParams(
    const std::vector<std::pair<std::string, double>>& overrides) const {
  std::vector<double> values;
  for (const auto& p : params) values.push_back(p.default_value);
  for (const auto& [key, value] : overrides) {
    bool found = false;
    for (size_t i = 0; i < params.size(); ++i) {
      if (params[i].name == key) {
        CheckConstraint(name, key.c_str(), value, params[i].constraint);
        values[i] = value;
        found = true;
      }
    }
    if (!found) {
      std::vector<std::string> names;
      for (const auto& p : params) names.push_back(p.name);
      throw InputError("unknown parameter '" + key + "' for model '" + name +
                       "' (known: " + Join(names) + ")");
    }
  }
  return values;
}

int ModelEntry::StateIndex(const std::string& state) const {
  for (size_t i = 0; i < states.size(); ++i)
    if (states[i] == state) return int(i);
  return -1;
}

std::vector<double> ModelEntry::ResolveState(
    const std::vector<std::pair<std::string, double>>& values, const std::string& option) const {
  std::vector<double> x(states.size(), 0.0);
  for (const auto& [key, value] : values) {
    const int i = StateIndex(key);
    if (i < 0) {
      throw InputError("unknown state '" + key + "' in " + option + " for model '" + name +
                       "' (states: " + Join(states) + ")");
    }
    if (!std::isfinite(value)) throw InputError(option + ": value of '" + key + "' is not finite");
    x[i] = value;
  }
  return x;
}

std::string ModelEntry::CheckIntegrator(Integrator integrator) const {
  const std::string error = CheckIntegratorForModel(integrator, discrete_time, name);
  if (!error.empty() || integrator != Integrator::kSemiImplicitEuler) return error;
  std::vector<std::string> unpaired;
  for (size_t i = 0; i < states.size(); ++i) {
    bool paired = false;
    for (const auto& [pos, rate] : position_rate_pairs)
      paired = paired || pos == int(i) || rate == int(i);
    if (!paired) unpaired.push_back(states[i]);
  }
  if (unpaired.empty()) return "";
  return "integrator 'semi-implicit-euler' advances only the states in a (position, rate) pair; "
         "model '" +
         name + "' has " + Join(unpaired) +
         " in none (they would stay frozen): use rk4, euler or cvodes";
}

const OutputGroup* MeasurementDesc::FindGroup(const std::string& group) const {
  for (const OutputGroup& g : groups)
    if (g.name == group) return &g;
  return nullptr;
}

namespace {

// "a, b" of the group names of `m`.
std::string GroupNames(const MeasurementDesc& m) {
  std::vector<std::string> names;
  for (const OutputGroup& g : m.groups) names.push_back(g.name);
  return Join(names);
}

}  // namespace

const MeasurementDesc& ModelEntry::FindMeasurement(const std::string& meas) const {
  const std::string want = Trim(meas);
  std::vector<std::string> names, groups;
  for (const auto& m : measurements) {
    if (m.name == want) return m;
    names.push_back(m.name);
    for (const OutputGroup& g : m.groups) groups.push_back(g.name);
  }
  const std::string known =
      " (known: " + Join(names) + (groups.empty() ? "" : "; sensor groups: " + Join(groups)) + ")";
  if (groups.empty() || want.find(',') == std::string::npos) {
    bool group = false;  // one group's name alone
    for (const std::string& g : groups) group = group || g == want;
    if (!group)
      throw InputError("unknown measurement '" + want + "' for model '" + name + "'" + known);
  }
  // A list of sensor groups: all of one measurement's, each once.
  const MeasurementDesc* found = nullptr;
  std::vector<std::string> given;
  for (const std::string& g : SplitTrimmed(want, ',')) {
    const MeasurementDesc* owner = nullptr;
    for (const auto& m : measurements) {
      if (m.name == g)
        throw InputError("'" + g + "' in '" + want +
                         "' is a measurement, not a sensor group: give one measurement, or "
                         "sensor groups of one");
      if (m.FindGroup(g) != nullptr) owner = &m;
    }
    if (owner == nullptr)
      throw InputError("unknown sensor group '" + g + "' in '" + want + "' for model '" + name +
                       "'" + known);
    for (const std::string& earlier : given)
      if (earlier == g)
        throw InputError("sensor group '" + g + "' is named twice in '" + want + "'");
    if (found != nullptr && found != owner)
      throw InputError("sensor groups '" + given.front() + "' and '" + g +
                       "' belong to different measurements ('" + found->name + "', '" +
                       owner->name + "')");
    found = owner;
    given.push_back(g);
  }
  if (given.size() != found->groups.size())
    throw InputError("'" + want + "' names " + std::to_string(given.size()) + " of the " +
                     std::to_string(found->groups.size()) + " sensor groups of measurement '" +
                     found->name + "' (" + GroupNames(*found) +
                     "): name them all, or the measurement");
  return *found;
}

}  // namespace estlab
