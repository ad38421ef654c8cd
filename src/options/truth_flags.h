// Which columns of a data file are the truth. Columns named like the states
// are not taken as truth because of their names alone: a recording often
// has a derived, noisy velocity column called omega, and NEES against it
// would be reported as if it meant something. They are the truth when
//   --truth theta,omega   names them (every state of the model), or
//   FILE.json             the sidecar `estlab simulate` writes says so
//                         (it lists the simulation's states);
// --no-truth turns both off.
//
// Usage (estlab filter, smooth, tune --data/--validate):
//   AddTruthOptions(&desc);
//   const TruthChoice truth = ResolveTruth(vm, path, model);
//   FilterData data = LoadFilterData(path, model, meas, maps, truth.read);
//   std::cout << "truth  " << truth.Describe(data.has_truth) << "\n";
#ifndef ESTLAB_OPTIONS_TRUTH_FLAGS_H_
#define ESTLAB_OPTIONS_TRUTH_FLAGS_H_

#include <boost/program_options.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/registry/registry.h"

namespace estlab::cli {

struct TruthChoice {
  bool read = false;               // read the state-named columns as truth
  std::string source;              // "--truth", "d.csv.json (estlab simulate)"
  std::vector<std::string> names;  // the state-named columns the file has (for messages)
  // "theta, omega (from d.csv.json, written by estlab simulate)", or why
  // there is none.
  std::string Describe(bool has_truth) const;
};

void AddTruthOptions(boost::program_options::options_description* desc);

// Throws InputError for --truth naming an unknown state or not every state,
// or given with --no-truth.
TruthChoice ResolveTruth(const boost::program_options::variables_map& vm, const std::string& path,
                         const ModelEntry& model);
// The same from the values: `truth` (--truth's list; nullopt when not
// given) and `no_truth`.
TruthChoice ResolveTruth(const std::optional<std::string>& truth, bool no_truth,
                         const std::string& path, const ModelEntry& model);

}  // namespace estlab::cli

#endif  // ESTLAB_OPTIONS_TRUTH_FLAGS_H_
