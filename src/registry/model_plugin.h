// Models from files: a `.model` file (src/modelfile) or a C++ model header
// written by the user, compiled once into a shared library in the model cache
// and loaded with dlopen. `FindModel` (registry.h) calls this for any name
// that is a path or is found on ESTLAB_MODEL_PATH.
//
//   compile   <cache>/<name>-<key>/entry.so   metadata, transitions, simulator,
//                                             every filter (`model build`, a
//                                             study, `list`, Python)
//             <cache>/<name>-<key>/run-*.so   metadata and one command's parts
//                                             (src/run/run_parts.h): the first
//                                             `filter`, `smooth`, `simulate`,
//                                             `tune` while entry.so is not there
//             <cache>/<name>-<key>/tune.so    the Q/R tuner (first tune or study
//                                             with tuned noise; the heavier one)
//   key       FNV-1a of the header text, estlab's version, commit and binary
//             (path, size, mtime), the compiler and its flags: an edited model
//             or a rebuilt estlab compiles anew, a stale library is never loaded.
//   cache     --model-cache DIR, else $ESTLAB_MODEL_CACHE, else
//             $XDG_CACHE_HOME/estlab, else ~/.cache/estlab.
//
// A library is compiled to a name unique to the process and renamed into
// place, so two processes compiling the same model at once both succeed and a
// failed compile leaves nothing a later run would load. A C++ header must
// `#define ESTLAB_MODEL_TYPE <its model type>` (docs/models.md).
//
// Usage:
//   const ModelEntry& m = LoadModelFile("examples/models/pendulum.model", {});
//   const ModelEntry& t = LoadModelFile(path, {.tuner = true});   // m.tune set
//   const ModelEntry& f = LoadModelFile(path, {.run = RunNeeds{.measurement = "sin",
//                                                               .filter = 2}});
//
// WARNING: the libraries resolve estlab's own functions against the running
// estlab binary (linked with its symbols exported); a program that links
// estlab as a library builds its models into itself instead
// (estlab_add_model, docs/models.md).
#ifndef ESTLAB_REGISTRY_MODEL_PLUGIN_H_
#define ESTLAB_REGISTRY_MODEL_PLUGIN_H_

#include <string>

#include "src/registry/registry.h"

namespace estlab {

// True for a name that names a model file: ends in .model or .h, or
// contains a '/'.
bool IsModelPath(const std::string& name);
// `name` as a file: itself when it exists, else <dir>/<name>.model or
// <dir>/<name>.h for each dir of ESTLAB_MODEL_PATH; "" when none.
std::string ResolveModelPath(const std::string& name);

// Sets the cache folder for this process (the --model-cache option).
void SetModelCacheDir(const std::string& dir);
std::string ModelCacheDir();

// The entry of the model in `path` (.model or .h), compiled if needed.
// Throws InputError: a model file's problems as FILE:LINE:COL lines, a
// header's compiler errors (first lines), an unreadable file.
const ModelEntry& LoadModelFile(const std::string& path, ModelNeeds needs);

// A .model file's description (name, states, parameters, measurements,
// invariants) without compiling it: no entry points. Throws InputError.
ModelEntry DescribeModelFile(const std::string& path);

// What `estlab model build` reports: the library paths and whether each was
// compiled now (false = found in the cache), with the compile time.
struct ModelBuildReport {
  std::string entry_library, tuner_library;
  bool compiled_entry = false, compiled_tuner = false;
  double entry_seconds = 0.0, tuner_seconds = 0.0;
};
const ModelBuildReport& LastModelBuild();

}  // namespace estlab

#endif  // ESTLAB_REGISTRY_MODEL_PLUGIN_H_
