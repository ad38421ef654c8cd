// estlab model check | build | show | source FILE: a model file (.model or
// C++ header) validated, compiled ahead of time, described, or written out as
// the C++ sources a program links (estlab_add_model, docs/models.md).
#include <boost/program_options.hpp>
#include <iostream>

#include "src/cli/commands.h"
#include "src/core/types.h"
#include "src/io/json.h"
#include "src/registry/model_plugin.h"
#include "src/registry/model_source.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {

constexpr const char* kExamples = R"(Examples:
  estlab model check examples/models/pendulum.model
  estlab model show examples/models/multiarm_double_pendulum.model
  estlab model build examples/models/pendulum.model --tuner      # e.g. on a login node
  estlab filter --model examples/models/pendulum.model ...      # compiled on first use
  estlab model source examples/models/pendulum.model --out gen --tuner

A .model file is checked and described without compiling. `build` compiles
the filters and simulator (and with --tuner the Q/R tuner) into the model
cache (--model-cache DIR, ESTLAB_MODEL_CACHE, else $XDG_CACHE_HOME/estlab or
~/.cache/estlab); every later command loads them in well under a second.
`source` writes what a program compiles to link the model into itself:
DIR/model.h (the generated header; for a .h, a line including it),
DIR/entry.cpp (registers the model, so estlab::FindModel finds it by name)
and with --tuner DIR/tune.cpp. The CMake function estlab_add_model runs it.
See docs/models.md.
)";

void PrintBuild(const ModelEntry& m, bool json) {
  const ModelBuildReport& r = LastModelBuild();
  if (json) {
    JsonWriter j;
    j.BeginObject().Key("model").Value(m.name).Key("entry_library").Value(r.entry_library);
    j.Key("compiled_entry").Value(r.compiled_entry).Key("entry_seconds").Value(r.entry_seconds);
    if (!r.tuner_library.empty()) {
      j.Key("tuner_library").Value(r.tuner_library).Key("compiled_tuner").Value(r.compiled_tuner);
      j.Key("tuner_seconds").Value(r.tuner_seconds);
    }
    j.EndObject();
    std::cout << j.str() << "\n";
    return;
  }
  std::cout << "model " << m.name << ": " << r.entry_library
            << (r.compiled_entry ? " (compiled now)" : " (cached)") << "\n";
  if (!r.tuner_library.empty())
    std::cout << "tuner: " << r.tuner_library
              << (r.compiled_tuner ? " (compiled now)" : " (cached)") << "\n";
}

// `estlab model source FILE --out DIR [--tuner]`.
int WriteSources(const std::string& path, const po::variables_map& vm) {
  if (!vm.count("out")) throw InputError("model source: give --out DIR");
  const std::string dir = vm["out"].as<std::string>();
  const bool tuner = vm.count("tuner") > 0;
  const std::string name = WriteModelSources(path, dir, tuner);
  std::cout << "model " << name << ": wrote " << dir << "/model.h, entry.cpp"
            << (tuner ? ", tune.cpp" : "") << "\n";
  return 0;
}

}  // namespace

int RunModel(const std::vector<std::string>& args) {
  po::options_description desc("estlab model check|build|show|source FILE");
  desc.add_options()("help,h", "this text")("json", "machine-readable output")(
      "tuner", "build: compile the Q/R tuner as well; source: write tune.cpp as well")(
      "out", po::value<std::string>(), "source: the folder to write into")(
      "action", po::value<std::string>(), "check | build | show | source")(
      "file", po::value<std::string>(), "a .model file or a C++ model header");
  po::positional_options_description pos;
  pos.add("action", 1).add("file", 1);
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).positional(pos).run(), vm);
  po::notify(vm);
  if (vm.count("help") || !vm.count("action")) {
    std::cout << desc << "\n" << kExamples;
    return vm.count("help") ? 0 : 2;
  }
  const std::string action = vm["action"].as<std::string>();
  if (action != "check" && action != "build" && action != "show" && action != "source")
    throw InputError("model: unknown action '" + action + "' (check, build, show or source)");
  if (!vm.count("file")) throw InputError("model " + action + ": give a .model or .h file");
  const std::string file = vm["file"].as<std::string>();
  const std::string path = ResolveModelPath(file);
  if (path.empty()) throw InputError("model file '" + file + "' not found");
  const bool json = vm.count("json") > 0;
  if (action == "source") return WriteSources(path, vm);
  const bool is_model_file = path.size() > 6 && path.substr(path.size() - 6) == ".model";
  if (action == "build" || !is_model_file) {
    const ModelEntry& m = LoadModelFile(path, {.tuner = vm.count("tuner") > 0});
    if (action == "build") {
      PrintBuild(m, json);
    } else if (action == "show") {
      ShowModel(m, json);
    } else {
      std::cout << path << ": ok (model " << m.name << ", compiled)\n";
    }
    return 0;
  }
  const ModelEntry m = DescribeModelFile(path);  // throws FILE:LINE:COL lines
  if (action == "check") {
    std::cout << path << ": ok (model " << m.name << ": " << m.states.size() << " states, "
              << m.params.size() << " parameters, " << m.measurements.size() << " measurements)\n";
  } else {
    ShowModel(m, json);
  }
  return 0;
}

}  // namespace estlab::cli
