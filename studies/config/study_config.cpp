#include "studies/config/study_config.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "adaptive/estimators.h"
#include "src/core/hash.h"
#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/io/output_file.h"
#include "studies/config/study_config_parts.h"

namespace estlab {

namespace {
constexpr std::pair<NoiseRole, const char*> kNoiseRoles[] = {{NoiseRole::kHand, "hand"},
                                                             {NoiseRole::kTuned, "tuned"},
                                                             {NoiseRole::kOracle, "oracle"},
                                                             {NoiseRole::kOther, "other"}};
}  // namespace

const char* NoiseRoleName(NoiseRole role) {
  for (const auto& [r, name] : kNoiseRoles)
    if (r == role) return name;
  return "other";
}

bool ParseNoiseRole(const std::string& text, NoiseRole* role) {
  for (const auto& [r, name] : kNoiseRoles)
    if (text == name) return *role = r, true;
  return false;
}

uint64_t ConfigHash(const std::string& text) { return Fnv1a64(text); }

namespace study_config {

// ---------------------------------------------------------------------------
// [study]

StudySettings ParseStudy(const SectionValues& v) {
  const ConfigErrors& err = v.errors();
  StudySettings s;
  if (!v.Has("name")) v.FailSection("'name' is required");
  s.name = v.Get("name")->text;
  if (!IsName(s.name)) v.Fail("name", "'" + s.name + "' must be letters, digits, '_' and '-'");
  if (v.Has("description")) s.description = v.Get("description")->text;
  v.Read("seed", &s.seed, ParseInteger, 0);
  v.Read("runs", &s.runs, ParseCount, 1, kMaxRuns);
  v.Read("jobs", &s.jobs, ParseCount, 1, 1024);
  if (v.Has("keep-runs")) {
    s.keep_runs = Checked(*v.Get("keep-runs"), err, [](const std::string& t) {
      std::vector<int> runs;
      if (t == "none") return runs;
      for (const auto& part : Split(t, ','))
        runs.push_back(ParseCount(part, "keep-runs", 0, kMaxRuns - 1));
      return runs;
    });
  }
  v.Read("step-metrics-every", &s.step_metrics_every, ParseCount, 1, kMaxSteps);
  return s;
}

namespace {

// The sections of a study by kind, and the values of its filter and noise
// sections (kept for the combinations).
struct ConfigParts {
  const Section* study = nullptr;
  const Section* report = nullptr;
  std::vector<const Section*> scenario_secs, filter_secs, noise_secs;
  std::vector<SectionValues> filter_values, noise_values;
};

// Sorts the sections by kind; a study needs a [study] section and at least
// one scenario, filter and noise section.
ConfigParts GroupSections(const std::vector<Section>& sections, const ConfigErrors& err) {
  ConfigParts p;
  for (const Section& s : sections) {
    if (s.kind == "study") p.study = &s;
    if (s.kind == "report") p.report = &s;
    if (s.kind == "scenario") p.scenario_secs.push_back(&s);
    if (s.kind == "filter") p.filter_secs.push_back(&s);
    if (s.kind == "noise") p.noise_secs.push_back(&s);
  }
  if (!p.study) err.Fail(1, "no [study] section");
  if (p.scenario_secs.empty()) err.Fail(p.study->line, "no [scenario.NAME] section");
  if (p.filter_secs.empty()) err.Fail(p.study->line, "no [filter.NAME] section");
  if (p.noise_secs.empty()) err.Fail(p.study->line, "no [noise.NAME] section");
  return p;
}

// One [filter.NAME] section: its kind (required), its description (by
// default the kind and its keys) and the scenarios it applies to.
FilterConfig ParseFilter(const SectionValues& v) {
  const ConfigErrors& err = v.errors();
  FilterConfig f;
  f.name = v.section().name;
  if (!v.Has("kind"))
    v.FailSection(
        "'kind' is required (kf, ekf, iekf, ukf, ckf, ghkf, pf, or a smoother: rts, erts, "
        "iekf-rts, urts, ckf-rts, ghkf-rts, pf-bs)");
  f.kind = v.Get("kind")->text;
  Checked(*v.Get("kind"), err, [](const std::string& t) {
    const std::string filter = FilterOfSmoother(t);
    return ParseFilterKind(filter.empty() ? t : filter);
  });
  f.description = f.kind;
  for (const Entry& e : v.section().entries) {
    if (e.key == "kind" || e.key == "scenarios") continue;
    if (e.key == "description") {
      f.description = e.value;
      break;
    }
    f.description += " " + e.key + "=" + e.value;
  }
  v.Read("scenarios", &f.scenarios, ParseNameList);
  return f;
}

// The role of a [noise.NAME] section: tuned, oracle or hand from its q and
// r, unless its `role` key names one (or other).
NoiseRole RoleOf(const SectionValues& v) {
  auto text_of = [&](const char* key) { return v.Has(key) ? v.Get(key)->text : std::string(); };
  NoiseRole role = text_of("q") == "tuned" || text_of("r") == "tuned" || v.Has("params")
                       ? NoiseRole::kTuned
                   : text_of("q") == "oracle" && text_of("r") == "oracle" ? NoiseRole::kOracle
                                                                          : NoiseRole::kHand;
  if (v.Has("role") && !ParseNoiseRole(v.Get("role")->text, &role))
    v.Fail("role", "expected hand, tuned, oracle or other, got '" + v.Get("role")->text + "'");
  return role;
}

// One [noise.NAME] section: exactly one Q and one R key, its description,
// role, tuner settings, and the scenarios and filters (of `filters`) it
// applies to.
NoiseConfig ParseNoise(const SectionValues& v, const std::vector<FilterConfig>& filters) {
  const ConfigErrors& err = v.errors();
  NoiseConfig nc;
  nc.name = v.section().name;
  const int nq = int(v.Has("q")) + int(v.Has("q-diag")) + int(v.Has("q-white-accel"));
  const int nr = int(v.Has("r")) + int(v.Has("r-diag"));
  if (nq != 1)
    v.FailSection(
        "give exactly one of q, q-diag, q-white-accel (q = oracle: the truth's process "
        "noise; q = tuned: the likelihood tuner)");
  if (nr != 1) v.FailSection("give exactly one of r, r-diag (r = oracle: the truth's noise)");
  nc.description = v.Has("description") ? v.Get("description")->text : NoiseDescription(v);
  nc.role = RoleOf(v);
  if (v.Has("tune-estimator")) {
    nc.estimator = v.Get("tune-estimator")->text;  // the estimator table's name
    Checked(*v.Get("tune-estimator"), err, [](const std::string& t) {
      return ParseEstimator(t, "tune-estimator", /*studies_only=*/true);
    });
  }
  nc.init_scale = v.Has("init-scale") ? v.Get("init-scale")->text : std::string();
  v.Read("tune-per-run", &nc.per_run, ParseBool);
  v.Read("scenarios", &nc.scenarios, ParseNameList);
  if (v.Has("filters")) {
    nc.filters = Checked(*v.Get("filters"), err,
                         [](const std::string& t) { return ParseNameList(t, "filters"); });
    for (const auto& name : nc.filters) {
      bool found = false;
      for (const auto& f : filters) found |= f.name == name;
      if (!found) v.Fail("filters", "no [filter." + name + "]");
    }
  }
  return nc;
}

// Fails at the `scenarios` key of `v` unless each of `names` has a
// [scenario.NAME] section.
void CheckScenariosExist(const std::vector<std::string>& names,
                         const std::vector<const Section*>& scenario_secs, const SectionValues& v) {
  for (const auto& name : names) {
    bool found = false;
    for (const Section* s : scenario_secs) found |= s->name == name;
    if (!found) v.Fail("scenarios", "no [scenario." + name + "]");
  }
}

// Filters and noise settings, into c->filters and c->noises, with their
// values kept in *p; then the scenarios they name are checked.
void ParseFiltersAndNoises(const po::variables_map& vm, const ConfigErrors& err, ConfigParts* p,
                           StudyConfig* c) {
  for (const Section* s : p->filter_secs) {
    p->filter_values.emplace_back(*s, vm, err);
    c->filters.push_back(ParseFilter(p->filter_values.back()));
  }
  for (const Section* s : p->noise_secs) {
    p->noise_values.emplace_back(*s, vm, err);
    c->noises.push_back(ParseNoise(p->noise_values.back(), c->filters));
  }
  for (size_t i = 0; i < p->filter_secs.size(); ++i)
    CheckScenariosExist(c->filters[i].scenarios, p->scenario_secs, p->filter_values[i]);
  for (size_t i = 0; i < p->noise_secs.size(); ++i)
    CheckScenariosExist(c->noises[i].scenarios, p->scenario_secs, p->noise_values[i]);
}

// Appends `name` to `names` unless it is there.
void AddUnique(const std::string& name, std::vector<std::string>* names) {
  if (std::find(names->begin(), names->end(), name) == names->end()) names->push_back(name);
}

// The filter x noise combinations that apply to the scenario `base` (its
// section's NAME), into sc->combos; a combination tuned per run makes the
// study an identification, with the scenario's outputs.
void AddCombos(const std::string& base, const SectionValues& v, const ConfigParts& p,
               const ConfigErrors& err, ScenarioConfig* sc, StudyConfig* c) {
  for (size_t fi = 0; fi < c->filters.size(); ++fi) {
    const auto& fs = c->filters[fi].scenarios;
    if (!fs.empty() && std::find(fs.begin(), fs.end(), base) == fs.end()) continue;
    for (size_t ni = 0; ni < c->noises.size(); ++ni) {
      const auto& ns = c->noises[ni].scenarios;
      if (!ns.empty() && std::find(ns.begin(), ns.end(), base) == ns.end()) continue;
      const auto& nf = c->noises[ni].filters;
      if (!nf.empty() && std::find(nf.begin(), nf.end(), c->filters[fi].name) == nf.end()) continue;
      sc->combos.push_back(
          BuildCombo(*sc, v, int(fi), p.filter_values[fi], int(ni), p.noise_values[ni], err));
      if (sc->combos.back().tune_per_run) {
        c->identification = true;
        for (const auto& o : sc->model->FindMeasurement(sc->truth.measurement).outputs)
          AddUnique(o, &c->identification_outputs);
      }
    }
  }
}

// One expanded scenario of [scenario.NAME] `s` with its '|' `choices`,
// named NAME.LABEL..., its columns and combinations added to *c.
void AddScenario(const Section& s, const SectionValues& v,
                 const std::vector<std::pair<std::string, std::string>>& choices,
                 const ConfigParts& p, const ConfigErrors& err, std::set<std::string>* names,
                 StudyConfig* c) {
  ScenarioConfig sc = BuildScenario(v, err);
  sc.choices = choices;
  sc.name = s.name;
  for (const auto& ch : choices) sc.name += "." + ch.second;
  if (!names->insert(sc.name).second)
    err.Fail(s.line, "scenario name '" + sc.name + "' occurs twice");
  for (const auto& st : sc.model->states) AddUnique(st, &c->state_columns);
  if (sc.recorded)
    for (const auto& o : sc.model->FindMeasurement(sc.truth.measurement).outputs)
      AddUnique(o, &c->output_columns);
  AddCombos(s.name, v, p, err, &sc, c);
  if (sc.combos.empty())
    err.Fail(s.line, "[" + s.full + "]: no filter and noise setting applies to it");
  if (sc.model->run_filter == nullptr)
    err.Fail(s.line, "model '" + sc.model->name + "' has no filter runner in this build");
  c->scenarios.push_back(std::move(sc));
}

// Scenarios, expanded, each with its filter x noise combinations.
void ParseScenarios(const po::variables_map& vm, const ConfigErrors& err, const ConfigParts& p,
                    StudyConfig* c) {
  std::set<std::string> names;
  std::vector<std::unique_ptr<Section>> expanded_storage;
  for (const Section* s : p.scenario_secs) {
    // Values come from Program_options for the plain keys; '|' lists are
    // expanded from the same text.
    Section merged = *s;
    for (Entry& e : merged.entries) {
      const std::string full = s->full + "." + e.key;
      if (vm.count(full)) e.value = vm[full].as<std::string>();
    }
    for (auto& [sec, choices] : ExpandScenario(merged, err)) {
      expanded_storage.push_back(std::make_unique<Section>(sec));
      const Section& es = *expanded_storage.back();
      const SectionValues v(es, po::variables_map(), err);
      AddScenario(*s, v, choices, p, err, &names, c);
    }
  }
}

// Each run that keep-runs names must be < runs.
void CheckKeepRuns(const StudyConfig& c, const Section& study, const ConfigErrors& err) {
  for (int k : c.study.keep_runs)
    if (k >= c.study.runs && study.Find("keep-runs"))
      err.Fail(study.Find("keep-runs")->line, "[study] keep-runs: run " + std::to_string(k) +
                                                  " >= runs (" + std::to_string(c.study.runs) +
                                                  "); runs are numbered from 0");
}

}  // namespace

}  // namespace study_config

using namespace study_config;

StudyConfig ParseStudyConfig(const std::string& text, const std::string& path) {
  const ConfigErrors err(path);
  const std::vector<Section> sections = Scan(text, err);
  const po::variables_map vm = ParseWithProgramOptions(text, sections, err);

  StudyConfig c;
  c.path = path;
  c.text = text;
  ConfigParts p = GroupSections(sections, err);
  c.study = ParseStudy(SectionValues(*p.study, vm, err));
  ParseFiltersAndNoises(vm, err, &p, &c);
  ParseScenarios(vm, err, p, &c);
  if (p.report) ParseReport(*p.report, vm, &c, err);
  CheckKeepRuns(c, *p.study, err);
  return c;
}

namespace {

// `text` without a leading UTF-8 BOM and with CRLF and lone CR (old Mac)
// line ends turned into LF, so editors' variants of a file read the same.
std::string WithUnixLineEnds(const std::string& text) {
  const size_t start = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  std::string out;
  out.reserve(text.size());
  for (size_t i = start; i < text.size(); ++i) {
    if (text[i] != '\r') {
      out += text[i];
    } else if (i + 1 == text.size() || text[i + 1] != '\n') {
      out += '\n';
    }
  }
  return out;
}

}  // namespace

StudyConfig LoadStudyConfig(const std::string& path) {
  if (std::filesystem::is_directory(path))
    throw InputError("study config '" + path + "' is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot read study config '" + path + "'");
  std::ostringstream s;
  s << in.rdbuf();
  return ParseStudyConfig(WithUnixLineEnds(s.str()), path);
}

}  // namespace estlab
