// Helpers of the plugin tests that run estlab on example model files: the
// shared model cache beside the binary, a run with it, and a number from
// the --json output.
#ifndef ESTLAB_TESTS_PLUGIN_PLUGIN_TEST_UTIL_H_
#define ESTLAB_TESTS_PLUGIN_PLUGIN_TEST_UTIL_H_

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "cli/cli_test_util.h"

namespace estlab::testing {

// The model cache the plugin tests share (compiled models survive a run).
inline std::string PluginCache() {
  return (std::filesystem::path(ESTLAB_BINARY).parent_path() / "test-model-cache").string();
}
inline RunResult EstCached(const std::string& args, const std::string& cwd) {
  return RunEstlab("--model-cache '" + PluginCache() + "' " + args, cwd);
}

// The number after "key": inside the object that follows "section": (the
// first "key" when section is empty); NaN when absent.
inline double JsonNumber(const std::string& json, const std::string& section,
                         const std::string& key) {
  size_t at = section.empty() ? 0 : json.find("\"" + section + "\": ");
  if (at == std::string::npos) return std::nan("");
  at = json.find("\"" + key + "\": ", at);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + at + key.size() + 4, nullptr);
}

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_PLUGIN_PLUGIN_TEST_UTIL_H_
