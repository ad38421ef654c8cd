// Models linked into a program rather than built in or loaded at run time:
// the CMake function estlab_add_model (cmake/estlab_add_model.cmake) compiles
// the entry.cpp that `estlab model source` writes (model_source.h), whose
// last lines are ESTLAB_DEFINE_LINKED_MODEL. Its static initialiser calls
// RegisterLinkedModel, and from then on AllModels() lists the model after
// the built-in ones and FindModel(name) returns it (registry.h).
//
// Usage (what the generated entry.cpp holds):
//   #include "model.h"
//   #include "src/registry/model_entry_impl.h"
//   #include "src/registry/linked_models.h"
//   ESTLAB_DEFINE_LINKED_MODEL(estlab::user_models::Pendulum, false)
//
// WARNING: a name given twice (a linked model named like a built-in one or
// like another linked model) makes FindModel throw for that name; a model
// linked without its tuner (kWithTuner false) makes FindModel(name,
// {.tuner = true}) throw. ESTLAB_DEFINE_LINKED_MODEL needs
// model_entry_impl.h included before it.
#ifndef ESTLAB_REGISTRY_LINKED_MODELS_H_
#define ESTLAB_REGISTRY_LINKED_MODELS_H_

#include "src/registry/registry.h"

namespace estlab {

// Adds a model linked into the program; called during static initialisation.
// `entry` is called on the first AllModels() or FindModel() after it.
// Returns true.
bool RegisterLinkedModel(const ModelEntry& (*entry)());

}  // namespace estlab

// The entry (MakeModelEntry, model_entry_impl.h) and its registration.
// kWithTuner: TuneModel<Model> is instantiated in a unit linked beside it
// (ModelTunerUnit, kLinked).
#define ESTLAB_DEFINE_LINKED_MODEL(Model, kWithTuner)                                    \
  namespace {                                                                            \
  const estlab::ModelEntry& LinkedModelEntry() {                                         \
    static const estlab::ModelEntry entry = estlab::MakeModelEntry<Model, kWithTuner>(); \
    return entry;                                                                        \
  }                                                                                      \
  [[maybe_unused]] const bool kLinkedModelRegistered =                                   \
      estlab::RegisterLinkedModel(&LinkedModelEntry);                                    \
  }

#endif  // ESTLAB_REGISTRY_LINKED_MODELS_H_
