#include "src/options/truth_flags.h"

#include <algorithm>
#include <sstream>

#include "src/core/parse.h"
#include "src/io/csv_reader.h"
#include "src/io/memory_files.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {

std::string Join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// Whether PATH.json is a simulate sidecar: an object with "estlab_version"
// and the list of "states" the simulation wrote.
bool SimulateSidecar(const std::string& path) {
  const std::optional<std::string> text = ReadSidecar(path);
  if (!text) return false;
  const std::string& s = *text;
  return s.find("\"estlab_version\"") != std::string::npos &&
         s.find("\"states\"") != std::string::npos;
}

}  // namespace

std::string TruthChoice::Describe(bool has_truth) const {
  if (has_truth) return Join(names) + " (" + source + ")";
  if (!source.empty()) return "none (" + source + ")";
  return "none";
}

void AddTruthOptions(po::options_description* desc) {
  desc->add_options()("truth", po::value<std::string>(),
                      "the state-named columns are the truth: every state, e.g. theta,omega "
                      "(default: only when FILE.json from 'estlab simulate' says so)")(
      "no-truth", "never read truth columns (no errors, RMSE or NEES)");
}

TruthChoice ResolveTruth(const po::variables_map& vm, const std::string& path,
                         const ModelEntry& model) {
  return ResolveTruth(
      vm.count("truth") ? std::optional<std::string>(vm["truth"].as<std::string>()) : std::nullopt,
      vm.count("no-truth") > 0, path, model);
}

TruthChoice ResolveTruth(const std::optional<std::string>& truth, bool no_truth,
                         const std::string& path, const ModelEntry& model) {
  TruthChoice c;
  c.names = model.states;
  if (no_truth) {
    if (truth) throw InputError("--truth and --no-truth contradict each other");
    c.source = "--no-truth";
    return c;
  }
  if (truth) {
    std::vector<std::string> named;
    std::stringstream list(*truth);
    for (std::string name; std::getline(list, name, ',');) {
      if (model.StateIndex(name) < 0)
        throw InputError("--truth: '" + name + "' is not a state of model '" + model.name +
                         "' (states: " + Join(model.states) + ")");
      named.push_back(name);
    }
    for (const auto& s : model.states)
      if (std::find(named.begin(), named.end(), s) == named.end())
        throw InputError("--truth must name every state of model '" + model.name + "' (" +
                         Join(model.states) + "); '" + s + "' is missing");
    c.read = true;
    c.source = "--truth";
    return c;
  }
  if (SimulateSidecar(path)) {
    c.read = true;
    c.source = path + ".json, written by estlab simulate";
    return c;
  }
  std::string list;
  for (const auto& s : model.states) list += (list.empty() ? "" : ",") + s;
  c.source = "no " + path + ".json from estlab simulate; --truth " + list +
             " reads the columns of those names as truth";
  return c;
}

}  // namespace estlab::cli
