// The C++ text a model file compiles into: the model header and the
// translation units of its entry and its tuner. One generator for the two
// ways a model file is built:
//   kPlugin  at run time into entry.so / tune.so (model_plugin.cpp), loaded
//            with dlopen: each unit exports one extern "C" entry point;
//   kLinked  into a program by the CMake function estlab_add_model (through
//            `estlab model source FILE --out DIR`): the entry registers the
//            model at static initialisation (RegisterLinkedModel, linked_models.h),
//            so `FindModel("<name>")` finds it like a built-in model
//            (linked_models.h).
//
// Usage:
//   const ModelSource s = ReadModelSource("examples/models/pendulum.model");
//   // s.contents is the generated header; write it to DIR/model.h, then
//   std::string entry = ModelEntryUnit(s, "model.h", ModelLinkage::kLinked, false);
//   // or all at once, as `estlab model source` does:
//   WriteModelSources("examples/models/pendulum.model", "out", /*with_tuner=*/true);
//
// WARNING: a linked entry's registration is a static object in entry.cpp; a
// linker drops an unreferenced object file of a static library, and the
// model with it. estlab_add_model therefore makes an OBJECT library.
#ifndef ESTLAB_REGISTRY_MODEL_SOURCE_H_
#define ESTLAB_REGISTRY_MODEL_SOURCE_H_

#include <string>

#include "src/registry/registry.h"

namespace estlab {

// What one model file compiles into.
struct ModelSource {
  std::string path;      // absolute
  std::string name;      // the model's name (a .h: the file's stem until built)
  std::string header;    // a .h: its path; a .model: "" (the header is `contents`)
  std::string contents;  // the header's text (generated for a .model file)
  std::string type;      // the C++ type; "" = the header defines ESTLAB_MODEL_TYPE
};

// The text of a file (a model file, a compiler log); throws InputError.
std::string ReadModelText(const std::string& path);

// Reads and, for a .model file, parses, checks and translates `path`.
// Throws InputError (a model file's problems as FILE:LINE:COL lines).
ModelSource ReadModelSource(const std::string& path);

enum class ModelLinkage { kPlugin, kLinked };

// The entry's translation unit, including `header`. `with_tuner` (kLinked
// only) fills ModelEntry::tune from the tuner unit linked beside it; a
// plugin's tuner is loaded separately (tune.so).
std::string ModelEntryUnit(const ModelSource& s, const std::string& header, ModelLinkage linkage,
                           bool with_tuner);
// The tuner's translation unit (TuneModel<Model> instantiated), including `header`.
std::string ModelTunerUnit(const ModelSource& s, const std::string& header, ModelLinkage linkage);

// One command's parts of a plugin (src/run/run_parts.h): the library's
// name in the cache folder, "run-<measurement>-<filter>[-adapt][-smooth][-sim]"
// ("all" for every measurement or class, "none" for no filter), and its
// translation unit. A measurement name that is not a C identifier (sensor
// groups, "imu,gps") stands for every measurement: only identifiers enter the
// generated code.
std::string PartsLibraryName(const RunNeeds& needs);
std::string ModelPartsUnit(const ModelSource& s, const std::string& header, const RunNeeds& needs);

// What `estlab model source FILE --out DIR` writes, for static linking:
// DIR/model.h (the generated header, or for a .h one line including it),
// DIR/entry.cpp and with `with_tuner` DIR/tune.cpp, always rewritten (a
// build rule's outputs must end newer than the model file, or make reruns
// it and recompiles every time). Returns the model's name. Throws InputError.
std::string WriteModelSources(const std::string& path, const std::string& dir, bool with_tuner);

}  // namespace estlab

#endif  // ESTLAB_REGISTRY_MODEL_SOURCE_H_
