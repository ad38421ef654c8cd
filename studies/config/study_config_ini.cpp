// Scanning a study's ini text: sections, entries and their lines; the keys
// of each section type; Program_options over the whole file (unknown and
// repeated keys); typed values (study_config_parts.h).
#include <algorithm>
#include <set>
#include <sstream>

#include "src/core/parse.h"
#include "src/options/filter_settings.h"
#include "studies/config/study_config_parts.h"

namespace estlab::study_config {

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t pos = s.find(sep, start);
    parts.push_back(
        Trim(s.substr(start, pos == std::string::npos ? std::string::npos : pos - start)));
    if (pos == std::string::npos) break;
    start = pos + 1;
  }
  return parts;
}

bool IsName(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

// Labels of '|' alternatives may also hold '.' and '+' ("s0.01", "1e+2").
bool IsLabel(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' ||
          c == '+'))
      return false;
  return true;
}

std::vector<Section> Scan(const std::string& text, const ConfigErrors& err) {
  std::vector<Section> sections;
  std::set<std::string> seen;
  std::istringstream in(text);
  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const auto hash = raw.find('#');  // Program_options: '#' starts a comment anywhere
    const std::string s = Trim(hash == std::string::npos ? raw : raw.substr(0, hash));
    if (s.empty()) continue;
    if (s.front() == '[') {
      if (s.back() != ']') err.Fail(line, "expected '[section]', got '" + s + "'");
      Section sec;
      sec.full = Trim(s.substr(1, s.size() - 2));
      sec.line = line;
      const auto dot = sec.full.find('.');
      sec.kind = sec.full.substr(0, dot);
      sec.name = dot == std::string::npos ? "" : sec.full.substr(dot + 1);
      const bool named = sec.kind == "scenario" || sec.kind == "filter" || sec.kind == "noise";
      const bool single = sec.kind == "study" || sec.kind == "report";
      if (!(named && IsName(sec.name)) && !(single && dot == std::string::npos)) {
        err.Fail(line, "unknown section [" + sec.full +
                           "] (expected [study], [report], [scenario.NAME], [filter.NAME] or "
                           "[noise.NAME] with NAME of letters, digits, '_' and '-')");
      }
      if (!seen.insert(sec.full).second) err.Fail(line, "section [" + sec.full + "] given twice");
      sections.push_back(sec);
      continue;
    }
    const auto eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      err.Fail(line, "expected 'key = value' or '[section]', got '" + s + "'");
    if (sections.empty())
      err.Fail(line, "key '" + Trim(s.substr(0, eq)) + "' before the first [section]");
    sections.back().entries.push_back({Trim(s.substr(0, eq)), Trim(s.substr(eq + 1)), line});
  }
  return sections;
}
// ---------------------------------------------------------------------------
// Pre-scan: sections, keys and their lines (Program_options reports neither).

// ---------------------------------------------------------------------------
// Keys of each section type.

const std::vector<std::string> kStudyKeys = {
    "name", "description", "seed", "runs", "jobs", "keep-runs", "step-metrics-every"};
const std::vector<std::string> kReportKeys = {"paper", "title", "tables", "overview"};
const std::vector<std::string> kReportRepeatedKeys = {"reference", "claim", "note"};
// Scenario keys: the simulation's, those of recorded runs (study_config_data.cpp
// uses both lists to reject the other kind), and the common ones.
const std::vector<std::string> kSimulationKeys = {"x0",
                                                  "truth-x0",
                                                  "dt",
                                                  "steps",
                                                  "truth-integrator",
                                                  "truth-method",
                                                  "truth-rtol",
                                                  "truth-atol",
                                                  "truth-substeps",
                                                  "truth-max-steps",
                                                  "process-noise",
                                                  "meas-noise-var",
                                                  "meas-noise",
                                                  "measure-at-t0",
                                                  "sensor-rate",
                                                  "sensor-every"};
const std::vector<std::string> kRecordedKeys = {"tune-data", "column", "truth", "burn-in"};
const std::vector<std::string> kScenarioKeys = [] {
  std::vector<std::string> keys = {"model",         "params",   "measurement", "prior-x0",
                                   "prior-p0-diag", "prior-p0", "input",       "input-hold",
                                   "description",   "data"};
  keys.insert(keys.end(), kSimulationKeys.begin(), kSimulationKeys.end());
  keys.insert(keys.end(), kRecordedKeys.begin(), kRecordedKeys.end());
  return keys;
}();
// The [noise.*] keys; the tuner's (tune-<key>, q-param, r-param) come from
// the tuner key table (StudyTuneKeys).
const std::vector<std::string> kNoiseOwnKeys = {"q",           "q-diag",       "q-white-accel",
                                                "r",           "r-diag",       "scenarios",
                                                "filters",     "description",  "role",
                                                "init-q-diag", "init-q",       "init-q-white-accel",
                                                "init-r-diag", "init-r",       "init-scale",
                                                "params",      "param-bounds", "param-prior"};

// ---------------------------------------------------------------------------
// Reading the file with Program_options.

// ---------------------------------------------------------------------------
// Typed values with their line, for messages.

// The keys of a [filter.NAME] section: the filter keys of the one key table
// (src/options/filter_settings.h) that are not about the data, the model or
// the noise (those come from the scenario and noise sections).
std::vector<std::string> FilterKeys() {
  std::vector<std::string> keys = {"kind", "scenarios", "description"};
  for (const FilterKey& k : FilterKeyTable())
    if (!k.data) keys.push_back(k.name);
  return keys;
}

po::variables_map ParseWithProgramOptions(const std::string& text,
                                          const std::vector<Section>& sections,
                                          const ConfigErrors& err) {
  po::options_description desc;
  const std::vector<std::string> filter_keys = FilterKeys();
  std::vector<std::string> noise_keys = kNoiseOwnKeys;
  for (const std::string& key : StudyTuneKeys()) noise_keys.push_back(key);
  for (const Section& sec : sections) {
    const std::vector<std::string>* keys = sec.kind == "study"      ? &kStudyKeys
                                           : sec.kind == "report"   ? &kReportKeys
                                           : sec.kind == "scenario" ? &kScenarioKeys
                                           : sec.kind == "filter"   ? &filter_keys
                                                                    : &noise_keys;
    for (const auto& key : *keys)
      desc.add_options()((sec.full + "." + key).c_str(), po::value<std::string>());
    if (sec.kind == "report") {
      for (const auto& key : kReportRepeatedKeys)
        desc.add_options()((sec.full + "." + key).c_str(),
                           po::value<std::vector<std::string>>()->composing());
    }
  }
  auto line_of = [&](const std::string& full_key, bool last) {
    int found = 0;
    for (const Section& sec : sections)
      for (const Entry& e : sec.entries)
        if (sec.full + "." + e.key == full_key && (found == 0 || last)) found = e.line;
    return found;
  };
  auto split_key = [](const std::string& full_key) {
    const auto dot = full_key.rfind('.');
    return std::make_pair(full_key.substr(0, dot), full_key.substr(dot + 1));
  };
  po::variables_map vm;
  std::istringstream in(text);
  try {
    po::store(po::parse_config_file(in, desc, /*allow_unregistered=*/false), vm);
    po::notify(vm);
  } catch (const po::unknown_option& e) {
    const std::string name = e.get_option_name();
    const auto [section, key] = split_key(name);
    std::string known;
    for (const auto& opt : desc.options()) {
      const std::string& n = opt->long_name();
      if (n.compare(0, section.size() + 1, section + ".") == 0)
        known += (known.empty() ? "" : ", ") + n.substr(section.size() + 1);
    }
    err.Fail(line_of(name, false),
             "unknown key '" + key + "' in [" + section + "] (known: " + known + ")");
  } catch (const po::multiple_occurrences& e) {
    const std::string name = e.get_option_name();
    const auto [section, key] = split_key(name);
    err.Fail(line_of(name, true), "key '" + key + "' given twice in [" + section + "]");
  } catch (const po::error& e) {
    err.Fail(1, e.what());
  }
  return vm;
}

std::vector<std::string> ParseNameList(const std::string& text, const std::string& what) {
  std::vector<std::string> names;
  for (const auto& part : Split(text, ',')) {
    if (!IsName(part)) throw InputError(what + ": '" + part + "' is not a section name");
    names.push_back(part);
  }
  return names;
}

std::string JoinDoubles(const std::vector<double>& v) {
  std::string s;
  for (double x : v) {
    if (!s.empty()) s += ',';
    s += FormatNumber(x);
  }
  return s;
}

std::vector<Alternative> ParseAlternatives(const Entry& e, const ConfigErrors& err,
                                           const std::string& where) {
  std::vector<Alternative> alts;
  const auto parts = Split(e.value, '|');
  for (size_t i = 0; i < parts.size(); ++i) {
    Alternative a;
    a.value = parts[i];
    const auto colon = parts[i].find(':');
    if (colon != std::string::npos && IsLabel(Trim(parts[i].substr(0, colon)))) {
      a.label = Trim(parts[i].substr(0, colon));
      a.value = Trim(parts[i].substr(colon + 1));
    } else if (parts.size() > 1) {
      a.label = IsLabel(a.value) ? a.value : e.key + std::to_string(i + 1);
    }
    if (a.value.empty() && parts.size() > 1) err.Fail(e.line, where + ": empty alternative");
    alts.push_back(a);
  }
  std::set<std::string> labels;
  for (const auto& a : alts)
    if (alts.size() > 1 && !labels.insert(a.label).second)
      err.Fail(e.line, where + ": label '" + a.label + "' used twice");
  return alts;
}

}  // namespace estlab::study_config
