// The report of `estlab tune --estimator output-error` (studies/run/output_error.h):
// text and JSON, in the shape of the prediction-error report so that scripts
// read both alike ("tuned": {"params": ...}, "std_errors", "validation").
#ifndef ESTLAB_SRC_CLI_TUNE_OUTPUT_ERROR_H_
#define ESTLAB_SRC_CLI_TUNE_OUTPUT_ERROR_H_

#include <string>
#include <vector>

#include "src/cli/tune_validate.h"
#include "src/cli/tune_x0.h"
#include "src/registry/registry.h"
#include "studies/run/output_error.h"

namespace estlab::cli {

// `runs` are the --data files (their paths name the per-file x0).
void PrintOutputError(const ModelEntry& model, const FilterSpec& spec, const OutputErrorResult& r,
                      const std::vector<FilterData>& runs, double horizon,
                      const std::vector<Validation>& validations, const std::string& out_path);

// "tuned": {"params": {...}, "x0": {STATE: value, ...}} (the shared x0), and
// "x0_per_file": [{"data": PATH, "x0": {...}, "std_errors": {...}}, ...].
// The fit's estimated initial states, for the report and tuned.ini.
X0Report FitX0(const ModelEntry& model, const FilterSpec& spec, const OutputErrorResult& r,
               const std::vector<FilterData>& runs);

std::string OutputErrorJson(const ModelEntry& model, const FilterSpec& spec,
                            const OutputErrorResult& r, const std::vector<FilterData>& runs,
                            double horizon, const std::vector<Validation>& validations,
                            const std::string& out_path);

}  // namespace estlab::cli

#endif  // ESTLAB_SRC_CLI_TUNE_OUTPUT_ERROR_H_
