// The filter settings of one run as text by key, the one table of those
// keys, and the one function that turns them into a FilterSpec.
//
// The keys are the option names without "--" (alpha, q-diag, x0, ...). The
// command line (filter_flags.h: program_options generated from the table),
// --config files and the studies' [filter.*] / [noise.*] sections all fill a
// FilterSettings; BuildFilterSpec parses and checks it once, and every error
// is a KeyError naming the key as the user wrote it, so each front end
// reports it in its own form:
//   estlab: error: --alpha: must be > 0 and finite, got -1
//   paper002.ini:31: [filter.ukf] alpha: must be > 0 and finite, got -1
//
// Usage:
//   FilterSettings s;
//   s.Set("measure", "sin");
//   s.Set("filter", "ukf");
//   s.Set("q-diag", "1e-4,1e-3");
//   s.Set("r-diag", "0.01");
//   const FilterSpec spec = BuildFilterSpec(s, FindModel("pendulum"));  // throws KeyError
#ifndef ESTLAB_OPTIONS_FILTER_SETTINGS_H_
#define ESTLAB_OPTIONS_FILTER_SETTINGS_H_

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "src/core/types.h"
#include "src/registry/registry.h"
#include "src/run/filter_spec.h"

namespace estlab {

// One filter option key.
struct FilterKey {
  enum Kind { kValue, kRepeatable, kFlag };
  const char* name;          // as the user writes it, without "--"
  const char* default_text;  // nullptr: none
  const char* help;
  Kind kind = kValue;
  // Noise keys (q-diag, ...) take the tuner's "init-" prefix; data keys
  // describe the data, the model or the noise (set by a study's scenario and
  // noise sections, not by [filter.NAME]).
  bool noise = false;
  bool data = false;
};
// Every filter option, in help order.
const std::vector<FilterKey>& FilterKeyTable();
// The entry for `key` (with the noise prefix, e.g. "init-q-diag"), or null.
const FilterKey* FindFilterKey(const std::string& key, const std::string& noise_prefix);

// An error in the value of one key. what() is "--KEY: message".
class KeyError : public InputError {
 public:
  KeyError(const std::string& key, const std::string& message)
      : InputError("--" + key + ": " + message), key_(key), message_(message) {}
  const std::string& key() const { return key_; }
  const std::string& message() const { return message_; }

 private:
  std::string key_, message_;
};

class FilterSettings {
 public:
  // noise_prefix: "" for --q-diag etc., "init-" for the tuner's initial Q, R.
  explicit FilterSettings(std::string noise_prefix = "") : prefix_(std::move(noise_prefix)) {}
  const std::string& noise_prefix() const { return prefix_; }

  void Set(const std::string& key, const std::string& text) { values_[key] = {text}; }
  void Add(const std::string& key, const std::string& text) { values_[key].push_back(text); }
  void Erase(const std::string& key) { values_.erase(key); }
  // Given by the user (not a default of the table).
  bool Given(const std::string& key) const { return values_.count(key) > 0; }
  // The value given, else the table's default; throws KeyError when neither.
  std::string Get(const std::string& key) const;
  // Every value of a repeatable key (empty when not given).
  std::vector<std::string> GetAll(const std::string& key) const;
  const std::map<std::string, std::vector<std::string>>& values() const { return values_; }

 private:
  std::string prefix_;
  std::map<std::string, std::vector<std::string>> values_;
};

// Parses and checks the settings (the filter's own IsValid: filter_options.h
// of src/run); throws KeyError naming the key.
FilterSpec BuildFilterSpec(const FilterSettings& settings, const ModelEntry& model);
// What one run of these settings needs of a model file's code (RunNeeds,
// registry.h): its measurement, its filter class, the noise adapter when
// --adapt is given, the smoother for `smooth`. A value that does not parse
// asks for every class (BuildFilterSpec then names it).
RunNeeds RunNeedsOf(const FilterSettings& settings, bool smooth);
// The "seed" key: a non-negative 64-bit integer (the particle filter's and
// the tuner's random draws); throws KeyError.
uint64_t SeedOf(const FilterSettings& settings);

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_FILTER_SETTINGS_H_
