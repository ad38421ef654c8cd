// The estlab subcommands. Each takes the arguments after its name, returns the
// process exit status, and throws InputError for bad input (exit 2).
#ifndef ESTLAB_CLI_COMMANDS_H_
#define ESTLAB_CLI_COMMANDS_H_

#include <boost/program_options/options_description.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "src/io/json.h"
#include "src/options/filter_settings.h"
#include "src/options/truth_flags.h"
#include "src/registry/registry.h"

namespace estlab::cli {

int RunSimulate(const std::vector<std::string>& args);
int RunList(const std::vector<std::string>& args);
int RunFilterCommand(const std::vector<std::string>& args);
int RunSmoothCommand(const std::vector<std::string>& args);
int RunStudyCommand(const std::vector<std::string>& args);
int RunMerge(const std::vector<std::string>& args);
int RunFigures(const std::vector<std::string>& args);
int RunTune(const std::vector<std::string>& args);
int RunModel(const std::vector<std::string>& args);

// The commands' cores for the Python module (src/python): the same options
// (as on the command line, "--key", "value", ...), the same checks and the
// same numbers, with the results in memory instead of files and stdout. Data
// files may be tables in memory (src/io/memory_files.h). Bad input throws
// InputError (or a program_options error), as the commands do.

// One `estlab filter` (smooth: `estlab smooth`) request, its options read:
// the key table's (FilterSettings, --column maps among them), the data
// file's name, and the command's own options. FilterRequestFromArgs reads them from arguments as
// the command line gives them (--config files merged); the Python module also fills one directly,
// with no option parsing.
struct FilterRequest {
  std::string model;                 // --model
  FilterSettings settings;           // the filter key table's options
  std::string data;                  // --data (a file, or a table in memory)
  std::optional<std::string> truth;  // --truth
  bool no_truth = false;             // --no-truth
  bool smooth = false;
  int smoother_trajectories = 100;  // --smoother-trajectories (smooth)
  bool smoother_trajectories_given = false;
  bool allow_degenerate = false;  // --allow-degenerate
};
FilterRequest FilterRequestFromArgs(const std::vector<std::string>& args, bool smooth);

// What the command computed and would write.
struct FilterOutcome {
  FilterRunOutput run;  // the rows of --out and the summary
  TruthChoice truth;
  bool has_truth = false;
  int status = 0;                   // the exit status: 0, or 1 (numerical failure, degenerate)
  std::string error;                // with status 1, what follows "estlab: error: "
  std::string warning;              // "estlab: warning: " (a degenerate run allowed)
  std::string SummaryJson() const;  // what --json prints
};
FilterOutcome ComputeFilter(const FilterRequest& request);

// What `estlab simulate` computed (no --out needed).
struct SimulateOutcome {
  SimulationResult result;   // the rows (so far, when not ok)
  std::string sidecar_json;  // OUT.json: the settings, the truth's states
  std::string summary_json;  // what --json prints ("out": "")
  int status = 0;            // 0, or 1: a numerical failure
  std::string error;
};
SimulateOutcome ComputeSimulation(const std::vector<std::string>& args);

// The options of a command: filter, smooth, simulate or tune (the keys the
// Python module accepts, and suggests from).
const boost::program_options::options_description& CommandOptions(const std::string& command);
const boost::program_options::options_description& SimulateDescription();
const boost::program_options::options_description& TuneDescription();

// A model's description as `estlab list` prints it (list_cmd.cpp).
void PrintModel(const ModelEntry& model, std::ostream& out);
void ModelJson(const ModelEntry& model, JsonWriter* json);
// PrintModel to stdout, or ModelJson when `json`.
void ShowModel(const ModelEntry& model, bool json);

}  // namespace estlab::cli

#endif  // ESTLAB_CLI_COMMANDS_H_
