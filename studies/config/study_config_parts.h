// The pieces of the study configuration parser (study_config.h), one idea a
// file: scanning the ini text into sections with their lines (study_config_ini.cpp),
// the scenario sections (study_config_scenario.cpp), the filter x noise
// combinations (study_config_combos.cpp) and the [report] section
// (study_config_report.cpp); study_config.cpp puts them together. Internal to
// studies/ and its tests.
#ifndef ESTLAB_STUDIES_CONFIG_STUDY_CONFIG_PARTS_H_
#define ESTLAB_STUDIES_CONFIG_STUDY_CONFIG_PARTS_H_

#include <boost/program_options.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "src/core/types.h"
#include "studies/config/study_config.h"

namespace estlab::study_config {

namespace po = boost::program_options;

// ---------------------------------------------------------------------------
// Pre-scan: sections, keys and their lines (Program_options reports neither).

struct Entry {
  std::string key;
  std::string value;
  int line = 0;
};

struct Section {
  std::string kind;  // study | report | scenario | filter | noise
  std::string name;  // NAME of [kind.NAME]; empty for study and report
  std::string full;  // "scenario.pend"
  int line = 0;
  std::vector<Entry> entries;

  const Entry* Find(const std::string& key) const {
    for (const Entry& e : entries)
      if (e.key == key) return &e;
    return nullptr;
  }
};

class ConfigErrors {
 public:
  explicit ConfigErrors(std::string path) : path_(std::move(path)) {}
  [[noreturn]] void Fail(int line, const std::string& message) const {
    throw InputError(path_ + ":" + std::to_string(line) + ": " + message);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::vector<std::string> Split(const std::string& s, char sep);
bool IsName(const std::string& s);
bool IsLabel(const std::string& s);
// The sections of the text, in order, with their entries and lines.
std::vector<Section> Scan(const std::string& text, const ConfigErrors& err);

// The keys of each section type.
extern const std::vector<std::string> kStudyKeys, kReportKeys, kReportRepeatedKeys, kScenarioKeys,
    kNoiseOwnKeys;
std::vector<std::string> FilterKeys();
// The tuner keys of a [noise.*] section (tune-<key>, q-param, r-param from
// the tuner key table of src/options/tuner_settings.h) and the study's own
// tune-datasets, tune-per-run.
std::vector<std::string> StudyTuneKeys();

// Reads the file with Program_options (unknown or repeated keys are errors
// naming the line).
po::variables_map ParseWithProgramOptions(const std::string& text,
                                          const std::vector<Section>& sections,
                                          const ConfigErrors& err);

// ---------------------------------------------------------------------------
// Typed values with their line, for messages.

struct Value {
  std::string text;
  int line = 0;
  std::string where;  // "[scenario.pend] dt"
};

// Runs `fn`, turning an InputError into "FILE:LINE: [section] key: message".
template <class Fn>
auto Checked(const Value& v, const ConfigErrors& err, Fn&& fn) {
  try {
    return fn(v.text);
  } catch (const InputError& e) {
    std::string msg = e.what();
    // Messages of the shared parsers start with the option name we passed.
    const std::string prefix = v.where.substr(v.where.rfind(' ') + 1) + ": ";
    if (msg.compare(0, prefix.size(), prefix) == 0) msg = msg.substr(prefix.size());
    err.Fail(v.line, v.where + ": " + msg);
  }
}

class SectionValues {
 public:
  SectionValues(const Section& sec, const po::variables_map& vm, const ConfigErrors& err)
      : sec_(sec), err_(err) {
    for (const Entry& e : sec.entries) {
      const std::string full = sec.full + "." + e.key;
      values_[e.key] = {e.value, e.line, "[" + sec.full + "] " + e.key};
      if (vm.count(full) && vm[full].value().type() == typeid(std::string))
        values_[e.key].text = vm[full].as<std::string>();
    }
  }
  bool Has(const std::string& key) const { return values_.count(key) > 0; }
  const Value* Get(const std::string& key) const {
    const auto it = values_.find(key);
    return it == values_.end() ? nullptr : &it->second;
  }
  [[noreturn]] void Fail(const std::string& key, const std::string& message) const {
    const Value* v = Get(key);
    err_.Fail(v ? v->line : sec_.line, "[" + sec_.full + "] " + key + ": " + message);
  }
  [[noreturn]] void FailSection(const std::string& message) const {
    err_.Fail(sec_.line, "[" + sec_.full + "]: " + message);
  }
  // When `key` is given: *out = parse(its text, key, args...), a parse
  // error reported at the key's line as Checked does. Returns whether it
  // was given. v.Read("truth-substeps", &tr.substeps, ParseCount, 1, kMaxSubsteps);
  template <class T, class Parse, class... Args>
  bool Read(const std::string& key, T* out, Parse&& parse, Args&&... args) const {
    const Value* v = Get(key);
    if (v == nullptr) return false;
    *out = Checked(*v, err_, [&](const std::string& text) { return parse(text, key, args...); });
    return true;
  }
  const Section& section() const { return sec_; }
  const ConfigErrors& errors() const { return err_; }

 private:
  const Section& sec_;
  const ConfigErrors& err_;
  std::map<std::string, Value> values_;
};

std::vector<std::string> ParseNameList(const std::string& text, const std::string& what);
std::string JoinDoubles(const std::vector<double>& v);

// '|' alternatives of a scenario key.
struct Alternative {
  std::string label;
  std::string value;
};
std::vector<Alternative> ParseAlternatives(const Entry& e, const ConfigErrors& err,
                                           const std::string& where);

// ---------------------------------------------------------------------------
// The sections.

StudySettings ParseStudy(const SectionValues& v);
ScenarioConfig BuildScenario(const SectionValues& v, const ConfigErrors& err);
// Recorded runs: the simulation keys a scenario with `data` must not have
// and the keys that need `data` (both lists in study_config_ini.cpp), and
// the reading of data, tune-data, column, truth and burn-in into *sc (whose
// model and measurement are set; study_config_data.cpp).
extern const std::vector<std::string> kSimulationKeys, kRecordedKeys;
void ReadRecordedData(const SectionValues& v, ScenarioConfig* sc);
// Expands the '|' alternatives of a scenario section into one Section per
// combination (product in key order; the last key varies fastest).
std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> ExpandScenario(
    const Section& sec, const ConfigErrors& err);
// One filter x noise setting of a scenario: its FilterSpec (through the one
// key table, src/options/filter_settings.h) and its tuner settings.
Combo BuildCombo(const ScenarioConfig& sc, const SectionValues& scen, int fi,
                 const SectionValues& filt, int ni, const SectionValues& noise,
                 const ConfigErrors& err);
std::string NoiseDescription(const SectionValues& noise);
void ParseReport(const Section& sec, const po::variables_map& vm, StudyConfig* c,
                 const ConfigErrors& err);

}  // namespace estlab::study_config

#endif  // ESTLAB_STUDIES_CONFIG_STUDY_CONFIG_PARTS_H_
