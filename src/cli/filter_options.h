// The options shared by `estlab filter`, `estlab tune` and the studies:
// model, measurement, filter and its settings, prior, Q and R, data columns.
#ifndef ESTLAB_CLI_FILTER_OPTIONS_H_
#define ESTLAB_CLI_FILTER_OPTIONS_H_

#include <boost/program_options.hpp>
#include <string>
#include <vector>

#include "src/registry/registry.h"
#include "src/run/filter_spec.h"

namespace estlab::cli {

// Adds every filter option. `noise_prefix` is "" for --q-diag etc. and
// "init-" for the tuner's --init-q-diag.
void AddFilterOptions(boost::program_options::options_description* desc,
                      const std::string& noise_prefix = "");

// Builds and validates the spec (throws InputError naming the option).
FilterSpec BuildFilterSpec(const boost::program_options::variables_map& vm,
                           const ModelEntry& model, const std::string& noise_prefix = "");

// Reads a data CSV for `model` and measurement `meas`: column t, the
// z_<output> columns (renamed by --column ours=theirs), truth columns named
// like the states (optional, all or none), and 'u' for models with an input.
FilterData LoadFilterData(const std::string& path, const ModelEntry& model,
                          const MeasurementDesc& meas,
                          const std::vector<std::pair<std::string, std::string>>& renames);

std::vector<std::pair<std::string, std::string>> ParseColumnRenames(
    const boost::program_options::variables_map& vm);

// Checks that the row-major n x n matrix is symmetric and positive definite
// (or semi-definite when allow_semidefinite); throws InputError naming it.
void CheckCovariance(const std::vector<double>& a, int n, const std::string& what,
                     bool allow_semidefinite);

}  // namespace estlab::cli

#endif  // ESTLAB_CLI_FILTER_OPTIONS_H_
