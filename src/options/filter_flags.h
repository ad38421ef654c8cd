// The command-line side of the filter options shared by `estlab filter`,
// `estlab tune` and the studies: program_options generated from the key
// table (filter_settings.h), --config files, data files.
#ifndef ESTLAB_OPTIONS_FILTER_FLAGS_H_
#define ESTLAB_OPTIONS_FILTER_FLAGS_H_

#include <boost/program_options.hpp>
#include <string>
#include <vector>

#include "src/options/column_map.h"
#include "src/options/filter_settings.h"
#include "src/options/tuner_settings.h"
#include "src/registry/registry.h"
#include "src/run/filter_spec.h"

namespace estlab::cli {

// Adds every filter option. `noise_prefix` is "" for --q-diag etc. and
// "init-" for the tuner's --init-q-diag. The tuner gets only the options that
// apply to it: not those of the kinds it cannot tune ("pf: ..." keys,
// filter_kinds.h), nor --full-cov, and --filter lists the tunable kinds.
void AddFilterOptions(boost::program_options::options_description* desc,
                      const std::string& noise_prefix = "");

// Adds every tuner option of the key table (tuner_settings.h) and --form,
// the old name of --solver (`estlab tune`).
void AddTunerOptions(boost::program_options::options_description* desc);
// The tuner options given on the command line or in a --config file (--form
// as solver; defaults left to the key table).
TunerSettings TunerSettingsFromVariablesMap(const boost::program_options::variables_map& vm);

// Adds --config FILE (repeatable): filter options as 'key = value' lines,
// e.g. the tuned.ini that 'estlab tune --out' writes.
void AddConfigOption(boost::program_options::options_description* desc);

// Merges the --config files named in *vm into *vm. Keys are the option names
// of 'estlab filter' (q-diag, r-diag, filter, x0, ...); with noise_prefix
// "init-" the noise keys become the tuner's initial values (q-diag ->
// init-q-diag). What the command line gives wins: an option given there is
// kept, and a Q (or R) option on the command line replaces every Q (R)
// option of the file. Earlier files win over later ones. Throws InputError
// naming the file for an unreadable file, an unknown key or a bad value.
// For the tuner (noise_prefix "init-") the file may also hold tuner keys
// (estimator = em, starts = 4, ...).
void MergeConfigFiles(boost::program_options::variables_map* vm,
                      const std::string& noise_prefix = "");

// The filter options given on the command line (defaults left to the key
// table, filter_settings.h).
FilterSettings SettingsFromVariablesMap(const boost::program_options::variables_map& vm,
                                        const std::string& noise_prefix = "");

// Builds and validates the spec (throws KeyError naming the option).
FilterSpec BuildFilterSpec(const boost::program_options::variables_map& vm, const ModelEntry& model,
                           const std::string& noise_prefix = "");

// Reads a data CSV for `model` and measurement `meas`: column t, the
// z_<output> columns, truth columns named like the states (optional, all or
// none), and 'u' for models with an input. `columns` maps any of them from
// another column, ours = a * theirs + b (column_map.h); missing measurements
// stay missing. With read_truth false the state-named columns are not read
// (data whose state-like columns are derived, not measured truth). A model
// with an input needs the 'u' column unless constant_input (the user gave
// --input); a missing or non-finite input is an error naming FILE:LINE.
FilterData LoadFilterData(const std::string& path, const ModelEntry& model,
                          const MeasurementDesc& meas, const std::vector<ColumnMap>& columns,
                          bool read_truth = true, bool constant_input = false);

// Whether the command line (or a --config file) holds the input at one
// value (--input): data without a 'u' column are then allowed.
bool ConstantInputGiven(const boost::program_options::variables_map& vm);

// The times and (for a model with an input) the input column of a CSV, as
// `estlab simulate --data` replays them: t, lines, nu and u of the
// result are set, m = 0. Errors as LoadFilterData's.
FilterData LoadInputRecord(const std::string& path, const ModelEntry& model,
                           const std::vector<ColumnMap>& columns);

// Throws InputError when spec's --t0 is later than the first row of `data`
// (the filter cannot run back to it; it used to be ignored silently). The
// message names the first row (FILE:LINE) and its time.
void CheckPriorTime(const FilterSpec& spec, const FilterData& data);

// The file names given to the options `keys` (each a string or a repeatable
// string option), in order, then each one's sidecar FILE.json (read for
// truth columns and noise); absent options add nothing. For
// RefuseOutputOverInput.
std::vector<std::string> InputFiles(const boost::program_options::variables_map& vm,
                                    const std::vector<std::string>& keys);

// The --column maps of the command line (ParseColumnMaps).
std::vector<ColumnMap> ParseColumnRenames(const boost::program_options::variables_map& vm);

// Checks that the row-major n x n matrix is symmetric and positive definite
// (or semi-definite when allow_semidefinite); throws InputError naming it.
void CheckCovariance(const std::vector<double>& a, int n, const std::string& what,
                     bool allow_semidefinite);

}  // namespace estlab::cli

#endif  // ESTLAB_OPTIONS_FILTER_FLAGS_H_
