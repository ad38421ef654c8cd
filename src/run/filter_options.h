// FilterSpec -> the options struct of its filter kind, in one place: the
// filter runs (filter_run_impl.h) and the tuner's likelihood
// (adaptive/likelihood.h) build their filters' options here, and the
// options' own IsValid is the only check of them, so a setting the filter
// rejects is rejected everywhere with the same message.
//
// Usage:
//   std::string error;
//   if (!IsValidFilterOptions(spec, n, &error)) throw InputError(error);
//   const EkfOptions o = EkfOptionsOf(spec);
#ifndef ESTLAB_RUN_FILTER_OPTIONS_H_
#define ESTLAB_RUN_FILTER_OPTIONS_H_

#include <string>

#include "src/filters/filter_options.h"
#include "src/run/filter_spec.h"

namespace estlab {

KfOptions KfOptionsOf(const FilterSpec& spec);
EkfOptions EkfOptionsOf(const FilterSpec& spec);
// For kUkf, kCkf, kGhkf (the rule follows the kind).
SigmaPointOptions SigmaPointOptionsOf(const FilterSpec& spec);
ParticleOptions ParticleOptionsOf(const FilterSpec& spec);  // throws InputError (resample name)

// The IsValid of the options of spec.kind for a model with `state_dim`
// states, and of the transition options (with *error set when false). Every
// message starts with the option key it is about ("alpha: must be > 0 ...").
bool IsValidFilterOptions(const FilterSpec& spec, int state_dim, std::string* error);
// IsValidFilterOptions, and the IsValid of every other kind's options as
// well: a bad value of an option the chosen filter does not use is still an
// error (the user may think it applies). What the user-facing front ends
// check (BuildFilterSpec).
bool AllFilterOptionsValid(const FilterSpec& spec, int state_dim, std::string* error);

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_OPTIONS_H_
