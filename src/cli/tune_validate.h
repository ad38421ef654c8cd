// `estlab tune --validate FILE...`: the filter run on held-out files with the
// initial, the tuned and (when known) the true noise and parameters. Per file
// and setting, over the updates after the tuner's --burn-in:
//
//   nll_per_step, mean_nis with its 95 % bounds   (studies/report/study_metrics.h)
//   pred_rmse_<output>   one-step-ahead prediction RMSE of each output
//   rmse, mean_nees      when the file has truth columns
//   free_rmse_<output>   the free simulation over `horizon` s windows from
//                        the recorded states (output_error.h), ditto
//   whole_rmse_<output>  the free simulation over the whole file from the
//                        run's prior mean x0 (--x0, or the tuned.ini's x0),
//                        driven by the file's input (zero-order hold)
//
// The true noise comes from --true-q-diag / --true-r-diag, else from the
// FILE.json that `estlab simulate` writes beside its CSV.
#ifndef ESTLAB_SRC_CLI_TUNE_VALIDATE_H_
#define ESTLAB_SRC_CLI_TUNE_VALIDATE_H_

#include <boost/program_options.hpp>
#include <optional>
#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/io/json.h"
#include "src/registry/registry.h"
#include "studies/report/study_metrics.h"

namespace estlab::cli {

struct ValidationRun {
  FilterSummary summary;   // the whole run (status, truth metrics)
  NoTruthMetrics metrics;  // after the burn-in
  // Free-simulation RMSE per output over windows of `horizon` s from the
  // recorded states (studies/run/output_error.h); empty without state columns.
  std::vector<double> free_rmse;
  // Free-simulation RMSE per output over the whole file from the run's prior
  // mean (summary.x0), the file's input held between samples.
  std::vector<double> whole_rmse;
};

struct Validation {
  std::string path;
  // The prior mean of the tuned run on this file (x0 = first-sample: its
  // own first measurements), by state.
  std::vector<std::string> states;
  std::vector<double> x0;
  ValidationRun initial, tuned;
  std::optional<ValidationRun> oracle;
  std::string oracle_source;
};

// Loads every --validate file (with the training files' --column maps; with
// x0 = first-sample each file gets its own prior mean) and runs the filter.
// Throws InputError for bad files or options.
std::vector<Validation> ValidateAll(const boost::program_options::variables_map& vm,
                                    const ModelEntry& model, const FilterSpec& spec,
                                    const FilterSpec& tuned, int burn_in, double horizon);

void PrintValidation(const Validation& v, const std::vector<std::string>& outputs, double horizon);
void WriteValidationJson(JsonWriter* j, const Validation& v,
                         const std::vector<std::string>& outputs);

}  // namespace estlab::cli

#endif  // ESTLAB_SRC_CLI_TUNE_VALIDATE_H_
