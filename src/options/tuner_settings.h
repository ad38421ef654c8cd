// The tuner's settings as text by key, the one table of those keys, and the
// one function that turns them into TunerOptions (adaptive/tuner.h), as
// filter_settings.h does for the filter.
//
// The keys are the option names without "--" (estimator, solver, starts,
// ...). The command line (`estlab tune`, options generated from the table),
// --config files and a study's [noise.*] sections (as tune-<key>, and
// q-param / r-param as they are) all fill a TunerSettings;
// BuildTunerOptions parses and checks it once, and every error is a KeyError
// naming the key, so each front end reports it in its own form:
//   estlab: error: --lags: applies to the als estimator only (the estimator is em)
//   s.ini:12: [noise.em] tune-lags: applies to the als estimator only (...)
// Which estimator a key applies to comes from the estimator table
// (adaptive/estimators.h): a key of another estimator is an error, never
// silently ignored.
//
// Usage:
//   TunerSettings s;
//   s.Set("estimator", "em");
//   s.Set("tolerance", "1e-7");
//   TunerOptions o = BuildTunerOptions(s, "q-diag", "r-diag");  // throws KeyError
#ifndef ESTLAB_OPTIONS_TUNER_SETTINGS_H_
#define ESTLAB_OPTIONS_TUNER_SETTINGS_H_

#include <map>
#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/options/filter_settings.h"

namespace estlab {

// One tuner option key.
struct TunerKey {
  const char* name;          // as the user writes it, without "--"
  const char* default_text;  // nullptr: none (or the estimator's default)
  const char* help;
  // Whether the key applies to an estimator (nullptr: to every one), and
  // to which in words ("the ml estimator").
  bool (*applies)(const EstimatorInfo& estimator) = nullptr;
  const char* applies_to = "";
  bool in_studies = true;  // a study's [noise.*] key (tune-<name>)
};
// Every tuner option, in help order.
const std::vector<TunerKey>& TunerKeyTable();
// The key's name in a study's [noise.*] section: tune-<name>, or q-param /
// r-param as they are.
std::string StudyTunerKey(const TunerKey& key);

class TunerSettings {
 public:
  void Set(const std::string& key, const std::string& text) { values_[key] = text; }
  bool Given(const std::string& key) const { return values_.count(key) > 0; }
  // The value given, else the table's default ("" when none).
  std::string Get(const std::string& key) const;
  const std::map<std::string, std::string>& values() const { return values_; }

 private:
  std::map<std::string, std::string> values_;
};

// The parameterisation a guess implies when q-param / r-param is not given:
// the guess's key (without "init-") ending in -white-accel -> white-accel,
// -scalar -> scalar, -diag -> diag, the full matrix (q, r) -> full; no
// guess ("") -> diag.
NoiseParam NoiseParamOfGuess(const std::string& guess_key);

// Parses and checks the settings (TunerOptions::IsValid included); throws
// KeyError naming the key. q_guess, r_guess: the keys the initial Q and R
// came from (NoiseParamOfGuess). The seed and the estimated parameters are
// not tuner keys (the filter's seed, estimate_flags.h).
TunerOptions BuildTunerOptions(const TunerSettings& settings, const std::string& q_guess,
                               const std::string& r_guess);

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_TUNER_SETTINGS_H_
