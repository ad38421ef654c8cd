// The estlab subcommands. Each takes the arguments after its name, returns the
// process exit status, and throws InputError for bad input (exit 2).
#ifndef ESTLAB_CLI_COMMANDS_H_
#define ESTLAB_CLI_COMMANDS_H_

#include <ostream>
#include <string>
#include <vector>

#include "src/io/json.h"
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

// A model's description as `estlab list` prints it (list_cmd.cpp).
void PrintModel(const ModelEntry& model, std::ostream& out);
void ModelJson(const ModelEntry& model, JsonWriter* json);
// PrintModel to stdout, or ModelJson when `json`.
void ShowModel(const ModelEntry& model, bool json);

}  // namespace estlab::cli

#endif  // ESTLAB_CLI_COMMANDS_H_
