// estlab list: models, measurements, parameters, integrators.
#include <boost/program_options.hpp>
#include <iostream>

#include "src/cli/commands.h"
#include "src/io/json.h"
#include "src/registry/registry.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {
const std::vector<std::string> kIntegrators = {"cvodes", "rk4", "euler", "semi-implicit-euler",
                                               "discrete"};

// The "[unit]" that ends a parameter description ("length [m]" -> "[m]"),
// empty when it has none.
std::string UnitOf(const std::string& description) {
  const size_t open = description.rfind('[');
  if (open == std::string::npos || description.back() != ']') return "";
  return description.substr(open);
}
}  // namespace

void ModelJson(const ModelEntry& model, JsonWriter* json) {
  JsonWriter& j = *json;
  const ModelEntry* m = &model;
  j.BeginObject();
  j.Key("name").Value(m->name).Key("description").Value(m->description);
  j.Key("states").Value(m->states).Key("state_units").Value(m->state_units);
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
    j.BeginObject().Key("name").Value(meas.name).Key("outputs").Value(meas.outputs);
    if (!meas.groups.empty()) {  // sensor groups: name -> its outputs
      j.Key("groups").BeginObject();
      for (const OutputGroup& g : meas.groups) {
        j.Key(g.name).Value(std::vector<std::string>(meas.outputs.begin() + g.first,
                                                     meas.outputs.begin() + g.first + g.count));
      }
      j.EndObject();
    }
    j.EndObject();
  }
  j.EndArray();
  j.Key("has_input").Value(m->has_input()).Key("inputs").Value(m->inputs);
  j.Key("input_units").Value(m->input_units);
  j.Key("stiff").Value(m->stiff);
  j.Key("discrete_time").Value(m->discrete_time);
  j.Key("invariants").Value(m->invariants);
  j.EndObject();
}

void PrintModel(const ModelEntry& model, std::ostream& out) {
  const ModelEntry* m = &model;
  out << "\n  " << m->name << "  -  " << m->description << "\n    states:       ";
  for (size_t i = 0; i < m->states.size(); ++i)
    out << (i ? ", " : "") << m->states[i] << (m->angle_states[i] ? " (angle)" : "");
  out << "\n    parameters:   ";
  for (size_t i = 0; i < m->params.size(); ++i) {
    const std::string unit = UnitOf(m->params[i].description);
    out << (i ? ", " : "") << m->params[i].name << "=" << m->params[i].default_value
        << (unit.empty() ? "" : " " + unit);
  }
  out << "\n    measurements: ";
  for (size_t i = 0; i < m->measurements.size(); ++i) {
    out << (i ? "; " : "") << m->measurements[i].name << " -> ";
    for (size_t k = 0; k < m->measurements[i].outputs.size(); ++k)
      out << (k ? "," : "") << m->measurements[i].outputs[k];
    for (size_t g = 0; g < m->measurements[i].groups.size(); ++g) {  // (position: x, ...)
      const OutputGroup& group = m->measurements[i].groups[g];
      out << (g ? ", " : " (sensor groups ") << group.name << ":";
      for (int k = 0; k < group.count; ++k)
        out << (k ? "," : " ") << m->measurements[i].outputs[size_t(group.first + k)];
      if (g + 1 == m->measurements[i].groups.size()) out << ")";
    }
  }
  if (m->inputs.size() == 1)
    out << "\n    input:        " << m->inputs[0] << " (data column '" << m->inputs[0]
        << (m->inputs[0] == "u" ? "'" : "' or 'u'")
        << ", held between samples; or a constant --input)";
  if (m->inputs.size() > 1) {
    out << "\n    inputs:       ";
    for (size_t i = 0; i < m->inputs.size(); ++i)
      out << (i ? ", " : "") << m->inputs[i]
          << (m->input_units[i].empty() ? "" : " [" + m->input_units[i] + "]");
    out << " (data columns of these names, held between samples; or --input a,b,...)";
  }
  if (m->discrete_time) out << "\n    time:         discrete (a step map; --integrator discrete)";
  if (!m->invariants.empty()) {
    out << "\n    invariants:   ";
    for (size_t i = 0; i < m->invariants.size(); ++i) out << (i ? ", " : "") << m->invariants[i];
  }
  out << "\n";
}

void ShowModel(const ModelEntry& model, bool json) {
  if (!json) {
    PrintModel(model, std::cout);
    return;
  }
  JsonWriter j;
  ModelJson(model, &j);
  std::cout << j.str() << "\n";
}

int RunList(const std::vector<std::string>& args) {
  po::options_description desc("estlab list: models, measurements, parameters, integrators");
  desc.add_options()("help,h", "this text")("json", "machine-readable output")(
      "model", po::value<std::string>(), "one model: a name, or a .model / .h file");
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).run(), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << desc
              << "\nExamples:\n  estlab list\n  estlab list --json\n"
                 "  estlab list --model examples/models/pendulum.model\n";
    return 0;
  }
  if (vm.count("model")) {
    // The description alone: a model file not yet in the cache compiles no
    // filter and no simulator for it (run-all-none.so).
    const ModelEntry& m = FindModel(vm["model"].as<std::string>(), {.run = RunNeeds{.filter = -2}});
    ShowModel(m, vm.count("json") > 0);
    return 0;
  }
  if (vm.count("json")) {
    JsonWriter j;
    j.BeginObject().Key("models").BeginArray();
    for (const ModelEntry* m : AllModels()) {
      ModelJson(*m, &j);
    }
    j.EndArray().Key("integrators").Value(kIntegrators).EndObject();
    std::cout << j.str() << "\n";
    return 0;
  }
  std::cout << "Models\n";
  for (const ModelEntry* m : AllModels()) {
    PrintModel(*m, std::cout);
  }
  std::cout << "\nIntegrators\n  cvodes (default; BDF for stiff models, Adams otherwise; --method "
               "bdf|adams)\n"
            << "  rk4, euler, semi-implicit-euler (fixed step, --substeps N)\n"
            << "  discrete (a discrete-time model's own map: its default and only choice)\n";
  return 0;
}

}  // namespace estlab::cli
