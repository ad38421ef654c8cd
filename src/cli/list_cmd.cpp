// estlab list: models, measurements, parameters, integrators.
#include <boost/program_options.hpp>
#include <iostream>

#include "src/cli/commands.h"
#include "src/io/json.h"
#include "src/registry/registry.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {
const std::vector<std::string> kIntegrators = {"cvodes", "rk4", "euler", "semi-implicit-euler"};
}

int RunList(const std::vector<std::string>& args) {
  po::options_description desc("estlab list: models, measurements, parameters, integrators");
  desc.add_options()("help,h", "this text")("json", "machine-readable output");
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).run(), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << desc << "\nExamples:\n  estlab list\n  estlab list --json\n";
    return 0;
  }
  if (vm.count("json")) {
    JsonWriter j;
    j.BeginObject().Key("models").BeginArray();
    for (const ModelEntry* m : AllModels()) {
      j.BeginObject().Key("name").Value(m->name).Key("description").Value(m->description);
      j.Key("states").Value(m->states);
      j.Key("angle_states").BeginArray();
      for (bool a : m->angle_states) j.Value(a);
      j.EndArray();
      j.Key("params").BeginArray();
      for (const auto& p : m->params) {
        j.BeginObject().Key("name").Value(p.name).Key("default").Value(p.default_value);
        j.Key("description").Value(p.description).Key("constraint").Value(ConstraintText(p.constraint));
        j.EndObject();
      }
      j.EndArray().Key("measurements").BeginArray();
      for (const auto& meas : m->measurements) {
        j.BeginObject().Key("name").Value(meas.name).Key("outputs").Value(meas.outputs).EndObject();
      }
      j.EndArray();
      j.Key("has_input").Value(m->has_input).Key("stiff").Value(m->stiff);
      j.Key("invariants").Value(m->invariants);
      j.EndObject();
    }
    j.EndArray().Key("integrators").Value(kIntegrators).EndObject();
    std::cout << j.str() << "\n";
    return 0;
  }
  std::cout << "Models\n";
  for (const ModelEntry* m : AllModels()) {
    std::cout << "\n  " << m->name << "  -  " << m->description << "\n    states:       ";
    for (size_t i = 0; i < m->states.size(); ++i)
      std::cout << (i ? ", " : "") << m->states[i] << (m->angle_states[i] ? " (angle)" : "");
    std::cout << "\n    parameters:   ";
    for (size_t i = 0; i < m->params.size(); ++i)
      std::cout << (i ? ", " : "") << m->params[i].name << "=" << m->params[i].default_value;
    std::cout << "\n    measurements: ";
    for (size_t i = 0; i < m->measurements.size(); ++i) {
      std::cout << (i ? "; " : "") << m->measurements[i].name << " -> ";
      for (size_t k = 0; k < m->measurements[i].outputs.size(); ++k)
        std::cout << (k ? "," : "") << m->measurements[i].outputs[k];
    }
    if (m->has_input) std::cout << "\n    input:        yes (--input or a 'u' column)";
    if (!m->invariants.empty()) {
      std::cout << "\n    invariants:   ";
      for (size_t i = 0; i < m->invariants.size(); ++i) std::cout << (i ? ", " : "") << m->invariants[i];
    }
    std::cout << "\n";
  }
  std::cout << "\nIntegrators\n  cvodes (default; BDF for stiff models, Adams otherwise; --method bdf|adams)\n"
            << "  rk4, euler, semi-implicit-euler (fixed step, --substeps N)\n";
  return 0;
}

}  // namespace estlab::cli
