// FilterSpec -> the options struct of its filter kind, in one place: the
// filter runs (filter_run_impl.h) and the tuner's likelihood
// (adaptive/likelihood.h) build their filters' options here, and the
// options' own IsValid is the only check of them, so a setting the filter
// rejects is rejected everywhere with the same message.
//
// Usage:
//   std::string error;
//   if (!IsValidFilterOptions(spec, &error)) throw InputError(error);
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

// The IsValid of the options of spec.kind (with *error set when false).
bool IsValidFilterOptions(const FilterSpec& spec, std::string* error);

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_OPTIONS_H_
