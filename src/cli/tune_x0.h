// The estimated initial states in `estlab tune`'s report, one shape for
// every estimator that fits them (ml: the filter's prior mean; output-error:
// the simulation's start): the text table, the JSON keys and the tuned.ini
// lines.
//
//   text   "initial state [of PATH]" then  NAME  initial  estimate  SE
//   JSON   "tuned": {..., "x0": {NAME: v}}, "x0_std_errors": {NAME: se}
//          (one x0 shared), or "x0_per_file": [{"data": PATH, "x0": {...},
//          "std_errors": {...}}, ...] (one per --data file)
//   ini    "x0 = s1=v,s2=v" (the whole x0; per file, "# PATH: x0 = ...")
#ifndef ESTLAB_SRC_CLI_TUNE_X0_H_
#define ESTLAB_SRC_CLI_TUNE_X0_H_

#include <string>
#include <vector>

#include "src/io/json.h"
#include "src/run/filter_spec.h"

namespace estlab::cli {

struct X0Report {
  std::vector<std::string> states;  // the model's, in order
  std::vector<std::string> names;   // the estimated ones
  // Per row (one shared, or one per --data file): the whole x0 at the
  // start and at the estimate, and the SEs (NaN where not estimated).
  std::vector<std::vector<double>> initial, x0, std_errors;
  std::vector<std::string> paths;  // the --data files
  bool empty() const { return x0.empty(); }
};

// The report of a fit's rows; the paths from the --data files.
X0Report MakeX0Report(const std::vector<std::string>& states, const std::vector<std::string>& names,
                      const std::vector<std::vector<double>>& initial,
                      const std::vector<std::vector<double>>& x0,
                      const std::vector<std::vector<double>>& std_errors,
                      const std::vector<FilterData>& runs);

void PrintX0(const X0Report& r);
// Inside "tuned": the shared x0 (nothing per file).
void WriteTunedX0Json(JsonWriter* j, const X0Report& r);
// After "tuned": x0_std_errors, or x0_per_file.
void WriteX0DetailJson(JsonWriter* j, const X0Report& r);
std::string X0IniLines(const X0Report& r);

}  // namespace estlab::cli

#endif  // ESTLAB_SRC_CLI_TUNE_X0_H_
