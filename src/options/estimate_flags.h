// The physical parameters of `estlab tune --estimate-param` (and a study's
// `params = tuned ...`): the names, their bounds and priors as TunerOptions
// takes them (adaptive/tuner.h).
//
// Usage:
//   std::vector<EstimatedParam> e = ParseEstimatedParams(
//       "L,b", "b=0:10", "L=normal:0.15:0.05");
//
// Grammar (comma-separated lists, blanks ignored):
//   --estimate-param  NAME[,NAME...]
//   --param-bounds    NAME=LO:HI[,...]   natural scale; either side may be
//                                        empty (its default: see tuner.h)
//   --param-prior     NAME=normal:MEAN:SD[,...]
//   --estimate-x0     STATE[,STATE...]
// A bound or prior for a name not in --estimate-param is an error, so is a
// repeated name.
#ifndef ESTLAB_OPTIONS_ESTIMATE_FLAGS_H_
#define ESTLAB_OPTIONS_ESTIMATE_FLAGS_H_

#include <string>
#include <vector>

#include "adaptive/tuner.h"

namespace estlab {

// Throws InputError naming the option and the offending text.
std::vector<EstimatedParam> ParseEstimatedParams(const std::string& names,
                                                 const std::string& bounds,
                                                 const std::string& priors);

// --estimate-x0 NAME[,NAME...]: the state names as written (checked against
// the model by ResolveInitialStates, adaptive/initial_states.h); "" gives
// none. Throws InputError for an empty name.
std::vector<std::string> ParseEstimatedStates(const std::string& names);

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_ESTIMATE_FLAGS_H_
