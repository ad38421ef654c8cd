#include "studies/study_config.h"

#include <Eigen/Core>

#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/core/white_accel.h"
#include "src/io/output_file.h"
#include "src/options/filter_flags.h"
#include "src/options/filter_settings.h"

namespace po = boost::program_options;

namespace estlab {

uint64_t ConfigHash(const std::string& text) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

namespace {

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
// Keys of each section type.

const std::vector<std::string> kStudyKeys = {
    "name", "description", "seed", "runs", "jobs", "keep-runs", "step-metrics-every"};
const std::vector<std::string> kReportKeys = {"paper", "title", "tables", "overview"};
const std::vector<std::string> kReportRepeatedKeys = {"reference", "claim", "note"};
const std::vector<std::string> kScenarioKeys = {"model",
                                                "params",
                                                "x0",
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
                                                "measurement",
                                                "meas-noise-var",
                                                "meas-noise",
                                                "measure-at-t0",
                                                "prior-x0",
                                                "prior-p0-diag",
                                                "prior-p0",
                                                "input",
                                                "description"};
const std::vector<std::string> kNoiseKeys = {"q",           "q-diag",        "q-white-accel",
                                             "r",           "r-diag",        "scenarios",
                                             "filters",     "description",   "role",
                                             "init-q-diag", "init-q",        "init-q-white-accel",
                                             "init-r-diag", "init-r",        "q-param",
                                             "r-param",     "tune-datasets", "tune-starts",
                                             "tune-burn-in"};

// The keys of a [filter.NAME] section: the filter keys of the one key table
// (src/options/filter_settings.h) that are not about the data, the model or
// the noise (those come from the scenario and noise sections).
std::vector<std::string> FilterKeys() {
  std::vector<std::string> keys = {"kind", "scenarios", "description"};
  for (const FilterKey& k : FilterKeyTable())
    if (!k.data) keys.push_back(k.name);
  return keys;
}

// ---------------------------------------------------------------------------
// Reading the file with Program_options.

po::variables_map ParseWithProgramOptions(const std::string& text,
                                          const std::vector<Section>& sections,
                                          const ConfigErrors& err) {
  po::options_description desc;
  const std::vector<std::string> filter_keys = FilterKeys();
  for (const Section& sec : sections) {
    const std::vector<std::string>* keys = sec.kind == "study"      ? &kStudyKeys
                                           : sec.kind == "report"   ? &kReportKeys
                                           : sec.kind == "scenario" ? &kScenarioKeys
                                           : sec.kind == "filter"   ? &filter_keys
                                                                    : &kNoiseKeys;
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

// ---------------------------------------------------------------------------
// Typed values with their line, for messages.

struct Value {
  std::string text;
  int line = 0;
  std::string where;  // "[scenario.pend] dt"
};

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
  const Section& section() const { return sec_; }
  const ConfigErrors& errors() const { return err_; }

 private:
  const Section& sec_;
  const ConfigErrors& err_;
  std::map<std::string, Value> values_;
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

std::vector<std::string> ParseNameList(const std::string& text, const std::string& what) {
  std::vector<std::string> names;
  for (const auto& part : Split(text, ',')) {
    if (!IsName(part)) throw InputError(what + ": '" + part + "' is not a section name");
    names.push_back(part);
  }
  return names;
}

// ---------------------------------------------------------------------------
// [study]

StudySettings ParseStudy(const SectionValues& v) {
  const ConfigErrors& err = v.errors();
  StudySettings s;
  if (!v.Has("name")) v.FailSection("'name' is required");
  s.name = v.Get("name")->text;
  if (!IsName(s.name)) v.Fail("name", "'" + s.name + "' must be letters, digits, '_' and '-'");
  if (v.Has("description")) s.description = v.Get("description")->text;
  if (v.Has("seed"))
    s.seed = Checked(*v.Get("seed"), err,
                     [](const std::string& t) { return uint64_t(ParseInteger(t, "seed", 0)); });
  if (v.Has("runs"))
    s.runs = Checked(*v.Get("runs"), err,
                     [](const std::string& t) { return int(ParseInteger(t, "runs", 1)); });
  if (v.Has("jobs"))
    s.jobs = Checked(*v.Get("jobs"), err,
                     [](const std::string& t) { return int(ParseInteger(t, "jobs", 1)); });
  if (v.Has("keep-runs")) {
    s.keep_runs = Checked(*v.Get("keep-runs"), err, [](const std::string& t) {
      std::vector<int> runs;
      if (t == "none") return runs;
      for (const auto& part : Split(t, ','))
        runs.push_back(int(ParseInteger(part, "keep-runs", 0)));
      return runs;
    });
  }
  if (v.Has("step-metrics-every"))
    s.step_metrics_every = Checked(*v.Get("step-metrics-every"), err, [](const std::string& t) {
      return int(ParseInteger(t, "step-metrics-every", 1));
    });
  return s;
}

// ---------------------------------------------------------------------------
// [scenario.NAME] with '|' alternatives.

struct Alternative {
  std::string label;
  std::string value;
};

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

}  // namespace

std::vector<double> WhiteAccelCovariance(const ModelEntry& model, double qc, double dt) {
  const int n = int(model.states.size());
  Eigen::MatrixXd Q(n, n);
  FillWhiteAccel(model.position_rate_pairs, qc, dt, &Q);
  std::vector<double> q(n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) q[i * n + j] = Q(i, j);
  return q;
}

namespace {

std::string JoinDoubles(const std::vector<double>& v) {
  std::string s;
  for (double x : v) {
    if (!s.empty()) s += ',';
    s += FormatNumber(x);
  }
  return s;
}

ScenarioConfig BuildScenario(const SectionValues& v, const ConfigErrors& err) {
  ScenarioConfig sc;
  sc.section = v.section().full;
  auto get = [&](const std::string& key) { return v.Get(key); };
  auto text_or = [&](const std::string& key, const std::string& fallback) {
    return v.Has(key) ? v.Get(key)->text : fallback;
  };
  if (!v.Has("model")) v.FailSection("'model' is required (see 'estlab list')");
  sc.model = Checked(*get("model"), err, [](const std::string& t) { return &FindModel(t); });
  const ModelEntry& model = *sc.model;
  const int n = int(model.states.size());
  SimulationSpec& truth = sc.truth;

  if (v.Has("params")) {
    truth.params = Checked(*get("params"), err, [&](const std::string& t) {
      return model.ResolveParams(ParseAssignments({t}, "params"));
    });
  } else {
    truth.params = model.ResolveParams({});
  }
  auto parse_state = [&](const std::string& key) {
    return Checked(*get(key), err, [&](const std::string& t) {
      return model.ResolveState(ParseAssignments({t}, key), key);
    });
  };
  truth.x0 = v.Has("x0") ? parse_state("x0") : std::vector<double>(n, 0.0);
  if (v.Has("truth-x0")) {
    const std::string mode = get("truth-x0")->text;
    if (mode != "fixed" && mode != "sample")
      v.Fail("truth-x0", "expected fixed or sample, got '" + mode + "'");
    sc.sample_x0 = mode == "sample";
  }
  if (!v.Has("dt")) v.FailSection("'dt' is required");
  truth.dt =
      Checked(*get("dt"), err, [](const std::string& t) { return ParseNumber(t, "dt"); });
  if (!(truth.dt > 0)) v.Fail("dt", "must be > 0");
  if (!v.Has("steps")) v.FailSection("'steps' is required");
  sc.steps = Checked(*get("steps"), err,
                     [](const std::string& t) { return int(ParseInteger(t, "steps", 1)); });
  truth.t_end = sc.steps * truth.dt;

  TransitionOptions& tr = truth.transition;
  tr.integrator =
      Checked(Value{text_or("truth-integrator", "cvodes"),
                    v.Has("truth-integrator") ? get("truth-integrator")->line : v.section().line,
                    "[" + sc.section + "] truth-integrator"},
              err, [](const std::string& t) { return ParseIntegrator(t); });
  if (v.Has("truth-method")) {
    const std::string m = get("truth-method")->text;
    if (m == "bdf")
      tr.method = CvodesMethod::kBdf;
    else if (m == "adams")
      tr.method = CvodesMethod::kAdams;
    else if (m != "default")
      v.Fail("truth-method", "expected bdf, adams or default, got '" + m + "'");
  }
  if (v.Has("truth-rtol"))
    tr.rtol = Checked(*get("truth-rtol"), err,
                      [](const std::string& t) { return ParseNumber(t, "truth-rtol"); });
  if (v.Has("truth-atol"))
    tr.atol = Checked(*get("truth-atol"), err,
                      [](const std::string& t) { return ParseNumber(t, "truth-atol"); });
  if (v.Has("truth-substeps"))
    tr.substeps = Checked(*get("truth-substeps"), err, [](const std::string& t) {
      return int(ParseInteger(t, "truth-substeps", 1));
    });
  if (v.Has("truth-max-steps"))
    tr.max_steps = Checked(*get("truth-max-steps"), err, [](const std::string& t) {
      return ParseInteger(t, "truth-max-steps", 1);
    });
  std::string error;
  if (!tr.IsValid(&error)) v.FailSection(error);
  sc.truth_description = IntegratorName(tr.integrator);
  if (tr.integrator == Integrator::kCvodes)
    sc.truth_description += " rtol " + FormatNumber(tr.rtol) + " atol " + FormatNumber(tr.atol);
  else if (tr.substeps > 1)
    sc.truth_description += " x" + std::to_string(tr.substeps) + " substeps";

  // Process noise of the truth, per step of dt.
  sc.oracle_q.assign(n * n, 0.0);
  const std::string pn = text_or("process-noise", "none");
  {
    const auto space = pn.find_first_of(" \t");
    const std::string kind = pn.substr(0, space);
    const std::string arg = space == std::string::npos ? "" : Trim(pn.substr(space));
    const Value val{arg, v.Has("process-noise") ? get("process-noise")->line : 0,
                    "[" + sc.section + "] process-noise"};
    if (kind == "none") {
      sc.truth_description += ", no process noise";
    } else if (kind == "diag") {
      const auto d = Checked(val, err, [&](const std::string& t) {
        auto list = ParseList(t, "process-noise");
        RequireLength(list, n, "process-noise", "one variance per state");
        RequireNonNegative(list, "process-noise");
        return list;
      });
      for (int i = 0; i < n; ++i) sc.oracle_q[i * n + i] = d[i];
      truth.process_noise_var = d;
      sc.truth_description += ", process noise diag " + JoinDoubles(d);
    } else if (kind == "white-accel") {
      sc.oracle_qc = Checked(val, err, [](const std::string& t) {
        const double qc = ParseNumber(t, "process-noise");
        if (qc < 0) throw InputError("process-noise: qc must be >= 0");
        return qc;
      });
      if (model.position_rate_pairs.empty())
        v.Fail("process-noise", "white-accel needs (position, rate) state pairs; model '" +
                                    model.name + "' has none");
      sc.oracle_q_white_accel = true;
      sc.oracle_q = WhiteAccelCovariance(model, sc.oracle_qc, truth.dt);
      truth.process_noise_cov = sc.oracle_q;
      sc.truth_description += ", white-accel qc " + FormatNumber(sc.oracle_qc);
    } else if (kind == "matrix") {
      sc.oracle_q = Checked(val, err, [&](const std::string& t) {
        auto q = ParseMatrix(t, n, "process-noise");
        cli::CheckCovariance(q, n, "process-noise", true);
        return q;
      });
      truth.process_noise_cov = sc.oracle_q;
      sc.truth_description += ", process noise matrix";
    } else {
      v.Fail("process-noise",
             "expected none, diag V1,V2,..., white-accel QC or matrix A,B;C,D, "
             "got '" +
                 pn + "'");
    }
  }

  if (!v.Has("measurement")) v.FailSection("'measurement' is required (see 'estlab list')");
  truth.measurement = get("measurement")->text;
  const MeasurementDesc& meas = *Checked(
      *get("measurement"), err, [&](const std::string& t) { return &model.FindMeasurement(t); });
  const int m = int(meas.outputs.size());
  truth.meas_noise_var.assign(m, 0.0);
  if (v.Has("meas-noise-var")) {
    truth.meas_noise_var = Checked(*get("meas-noise-var"), err, [&](const std::string& t) {
      auto list = ParseList(t, "meas-noise-var");
      RequireLength(list, m, "meas-noise-var", "one per output of '" + meas.name + "'");
      RequireNonNegative(list, "meas-noise-var");
      return list;
    });
  }
  sc.oracle_r.assign(m * m, 0.0);
  for (int j = 0; j < m; ++j) sc.oracle_r[j * m + j] = truth.meas_noise_var[j];
  if (v.Has("meas-noise")) {
    const std::string kind = get("meas-noise")->text;
    if (kind == "poisson") {
      // The counts' variance is lambda, so the oracle R stays diag(lambda);
      // their mean lambda is a bias no filter here models (as in paper 004).
      sc.poisson_meas = true;
      sc.poisson_lambda = truth.meas_noise_var;
      truth.meas_noise_var.assign(m, 0.0);
      sc.truth_description += ", Poisson measurement counts";
    } else if (kind != "gaussian") {
      v.Fail("meas-noise", "expected gaussian or poisson, got '" + kind + "'");
    }
  }
  if (v.Has("measure-at-t0"))
    sc.measure_at_t0 = Checked(*get("measure-at-t0"), err,
                               [](const std::string& t) { return ParseBool(t, "measure-at-t0"); });
  if (v.Has("input")) {
    truth.input = Checked(*get("input"), err,
                          [](const std::string& t) { return ParseNumber(t, "input"); });
    if (truth.input != 0 && !model.has_input)
      v.Fail("input", "model '" + model.name + "' has no input");
  }

  sc.prior_x0 = v.Has("prior-x0") ? parse_state("prior-x0") : truth.x0;
  if (v.Has("prior-p0-diag") && v.Has("prior-p0"))
    v.Fail("prior-p0", "give only one of prior-p0-diag and prior-p0");
  sc.prior_p0.assign(n * n, 0.0);
  if (v.Has("prior-p0-diag")) {
    const auto d = Checked(*get("prior-p0-diag"), err, [&](const std::string& t) {
      auto list = ParseList(t, "prior-p0-diag");
      RequireLength(list, n, "prior-p0-diag", "one per state");
      return list;
    });
    for (int i = 0; i < n; ++i) sc.prior_p0[i * n + i] = d[i];
  } else if (v.Has("prior-p0")) {
    sc.prior_p0 = Checked(*get("prior-p0"), err,
                          [&](const std::string& t) { return ParseMatrix(t, n, "prior-p0"); });
  } else {
    for (int i = 0; i < n; ++i) sc.prior_p0[i * n + i] = 1.0;
  }
  const std::string p0_key = v.Has("prior-p0") ? "prior-p0" : "prior-p0-diag";
  try {
    cli::CheckCovariance(sc.prior_p0, n, "P0", false);
  } catch (const InputError& e) {
    v.Fail(p0_key, e.what());
  }
  return sc;
}

// Expands the '|' alternatives of a scenario section into one Section per
// combination (product in key order; the last key varies fastest).
std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> ExpandScenario(
    const Section& sec, const ConfigErrors& err) {
  std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> out;
  out.push_back({sec, {}});
  out[0].first.entries.clear();
  for (const Entry& e : sec.entries) {
    const auto alts = ParseAlternatives(e, err, "[" + sec.full + "] " + e.key);
    std::vector<std::pair<Section, std::vector<std::pair<std::string, std::string>>>> next;
    for (const auto& [s, choices] : out) {
      for (const auto& a : alts) {
        auto s2 = s;
        s2.entries.push_back({e.key, a.value, e.line});
        auto c2 = choices;
        if (alts.size() > 1) c2.emplace_back(e.key, a.label);
        next.emplace_back(std::move(s2), std::move(c2));
      }
    }
    out = std::move(next);
    if (out.size() > 10000) err.Fail(e.line, "[" + sec.full + "]: more than 10000 combinations");
  }
  return out;
}

// ---------------------------------------------------------------------------
// Filter specs: the scenario's, filter's and noise section's keys fill one
// FilterSettings and BuildFilterSpec (src/options/filter_settings.h) turns
// it into a spec, exactly as for `estlab filter`; an error names the key it
// is about, reported at the line that set it.

Combo BuildCombo(const ScenarioConfig& sc, const SectionValues& scen, int fi,
                 const SectionValues& filt, int ni, const SectionValues& noise,
                 const ConfigErrors& err) {
  FilterSettings settings;
  std::map<std::string, const Value*> origin;  // settings key -> where it was set (null: by us)
  auto add = [&](const std::string& key, const std::string& value, const Value* from) {
    const FilterKey* k = FindFilterKey(key, "");
    if (k != nullptr && k->kind == FilterKey::kRepeatable)
      settings.Add(key, value);
    else
      settings.Set(key, value);
    origin[key] = from;
  };
  const ModelEntry& model = *sc.model;
  const int n = int(model.states.size());
  const int m = int(model.FindMeasurement(sc.truth.measurement).outputs.size());
  add("measure", sc.truth.measurement, scen.Get("measurement"));
  if (scen.Has("params")) add("param", scen.Get("params")->text, scen.Get("params"));
  // Prior from the scenario (already validated): pass as numbers.
  std::string x0;
  for (int i = 0; i < n; ++i) {
    if (i) x0 += ',';
    x0 += model.states[i] + "=" + FormatDouble(sc.prior_x0[i]);
  }
  add("x0", x0, scen.Get(scen.Has("prior-x0") ? "prior-x0" : "x0"));
  std::string p0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (j) p0 += ',';
      p0 += FormatDouble(sc.prior_p0[i * n + j]);
    }
    if (i + 1 < n) p0 += ";";
  }
  add("p0", p0, nullptr);
  add("input", FormatDouble(sc.truth.input), scen.Get("input"));
  const Value* kind = filt.Get("kind");
  add("filter", kind->text, kind);
  for (const Entry& e : filt.section().entries) {
    if (e.key == "kind" || e.key == "scenarios" || e.key == "description") continue;
    add(e.key, filt.Get(e.key)->text, filt.Get(e.key));
  }
  // Q and R: the noise section's keys, or placeholders replaced below.
  // `tuned` starts from the init-q-* / init-r-* key, else from the oracle.
  bool q_oracle = false, r_oracle = false, q_tuned = false, r_tuned = false;
  bool r_oracle_std = false;
  std::string q_shape, r_shape;  // the key that gave the (initial) matrix
  for (const char* key : {"q", "q-diag", "q-white-accel", "r", "r-diag"}) {
    const Value* val = noise.Get(key);
    if (!val) continue;
    const std::string k = key;
    const std::string which = k.substr(0, 1);
    if (val->text == "oracle-std") {
      // Paper 003's sweep: R = diag(std) instead of diag(std^2).
      if (k != "r") noise.Fail(k, "'oracle-std' goes in key r");
      r_oracle = r_oracle_std = true;
      r_shape = "r-diag";
      add("r-diag", JoinDoubles(std::vector<double>(m, 1.0)), val);
      continue;
    }
    if (val->text == "oracle" || val->text == "tuned") {
      if (k != which) noise.Fail(k, "'" + val->text + "' goes in key " + which);
      const bool tuned = val->text == "tuned";
      (which == "q" ? q_tuned : r_tuned) = tuned;
      const Value* init = nullptr;
      for (const std::string& ik :
           which == "q" ? std::vector<std::string>{"init-q-diag", "init-q", "init-q-white-accel"}
                        : std::vector<std::string>{"init-r-diag", "init-r"}) {
        if (!noise.Has(ik)) continue;
        if (!tuned) noise.Fail(ik, "an initial guess needs " + which + " = tuned");
        if (init) noise.Fail(ik, "give only one initial " + which + " (init-" + which + "*)");
        init = noise.Get(ik);
        (which == "q" ? q_shape : r_shape) = ik.substr(5);
        add(ik.substr(5), init->text, init);
      }
      if (!init) {
        (which == "q" ? q_oracle : r_oracle) = true;
        add(which + "-diag",
            which == "q" ? JoinDoubles(std::vector<double>(n, 0.0))
                         : JoinDoubles(std::vector<double>(m, 1.0)),
            val);
      }
      continue;
    }
    (which == "q" ? q_shape : r_shape) = k;
    add(k, val->text, val);
  }
  for (const char* ik : {"init-q-diag", "init-q", "init-q-white-accel", "init-r-diag", "init-r"})
    if (noise.Has(ik) && !(ik[5] == 'q' ? q_tuned : r_tuned))
      noise.Fail(ik, std::string("an initial guess needs ") + ik[5] + " = tuned");

  const std::string context =
      " (for [" + sc.section + "] with [" + noise.section().full + "])";
  Combo combo;
  combo.filter = fi;
  combo.noise = ni;
  try {
    combo.spec = BuildFilterSpec(settings, model);
  } catch (const KeyError& e) {
    const auto it = origin.find(e.key());
    if (it != origin.end() && it->second != nullptr)
      err.Fail(it->second->line, it->second->where + ": " + e.message() + context);
    err.Fail(filt.section().line, "[" + filt.section().full + "] with [" + sc.section +
                                      "] and [" + noise.section().full + "]: " + e.what());
  } catch (const InputError& e) {
    err.Fail(filt.section().line, "[" + filt.section().full + "] with [" + sc.section +
                                      "] and [" + noise.section().full + "]: " + e.what());
  }
  FilterSpec& spec = combo.spec;
  if (q_oracle) {
    spec.q_white_accel = sc.oracle_q_white_accel;
    spec.qc = sc.oracle_qc;
    spec.q = sc.oracle_q;
  }
  if (r_oracle) {
    for (int j = 0; j < m; ++j) {
      if (!(sc.oracle_r[j * m + j] > 0)) {
        noise.Fail("r", "the oracle R of [" + sc.section +
                            "] is singular: its meas-noise-var is 0 for output '" +
                            model.FindMeasurement(sc.truth.measurement).outputs[j] + "'");
      }
    }
    spec.r = sc.oracle_r;
    if (r_oracle_std)
      for (double& x : spec.r) x = std::sqrt(x);
  }
  spec.has_t0 = !sc.measure_at_t0;
  spec.t0 = 0.0;
  if (q_tuned || r_tuned) {
    combo.tune = true;
    TunerOptions& t = combo.tuner;
    auto param = [&](bool tuned, const std::string& which, const std::string& shape) {
      if (!tuned) {
        if (noise.Has(which + "-param"))
          noise.Fail(which + "-param", "needs " + which + " = tuned");
        return NoiseParam::kFixed;
      }
      if (noise.Has(which + "-param")) {
        return Checked(*noise.Get(which + "-param"), err, [&](const std::string& t) {
          const NoiseParam p = ParseNoiseParam(t, which + "-param");
          if (p == NoiseParam::kFixed) throw InputError(which + "-param: fixed contradicts tuned");
          return p;
        });
      }
      if (shape == which + "-white-accel") return NoiseParam::kWhiteAccel;
      if (shape == which) return NoiseParam::kFull;
      if (shape.empty() && which == "q" && sc.oracle_q_white_accel) return NoiseParam::kWhiteAccel;
      if (shape.empty() && which == "q") {
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j)
            if (i != j && sc.oracle_q[i * n + j] != 0.0) return NoiseParam::kFull;
      }
      return NoiseParam::kDiag;
    };
    t.q_param = param(q_tuned, "q", q_shape);
    t.r_param = param(r_tuned, "r", r_shape);
    auto integer = [&](const std::string& key, long fallback, long min_value) {
      if (!noise.Has(key)) return fallback;
      return Checked(*noise.Get(key), err,
                     [&](const std::string& t) { return ParseInteger(t, key, min_value); });
    };
    combo.tune_datasets = int(integer("tune-datasets", 3, 1));
    t.starts = int(integer("tune-starts", 1, 1));
    t.burn_in = int(integer("tune-burn-in", 0, 0));
    t.compute_std_errors = true;
    std::string error;
    if (!t.IsValid(&error)) noise.FailSection(error);
    if (!IsTunable(spec, t, n, &error))
      err.Fail(filt.section().line, "[" + filt.section().full + "] with [" + sc.section +
                                        "] and [" + noise.section().full + "]: " + error);
  } else {
    for (const char* key : {"q-param", "r-param", "tune-datasets", "tune-starts", "tune-burn-in"})
      if (noise.Has(key)) noise.Fail(key, "applies only with q = tuned or r = tuned");
  }
  return combo;
}

std::string NoiseDescription(const SectionValues& noise) {
  auto describe = [&](const std::string& which, std::vector<std::string> keys) {
    for (const auto& key : keys) {
      if (!noise.Has(key)) continue;
      const std::string& v = noise.Get(key)->text;
      if (v == "oracle") return std::string("oracle");
      if (v == "oracle-std") return std::string("diag(sqrt(oracle variance)) (paper 003's R)");
      if (v != "tuned") return key + " " + v;
      std::string out = "tuned";
      if (noise.Has(which + "-param")) out += " (" + noise.Get(which + "-param")->text + ")";
      for (const auto& ik :
           {"init-" + which + "-diag", "init-" + which, "init-" + which + "-white-accel"})
        if (noise.Has(ik)) return out + " from " + ik.substr(5) + " " + noise.Get(ik)->text;
      return out + " from the oracle";
    }
    return std::string("?");
  };
  std::string d = "Q " + describe("q", {"q", "q-diag", "q-white-accel"}) + ", R " +
                  describe("r", {"r", "r-diag"});
  if (noise.Has("tune-datasets") || noise.Has("tune-starts"))
    d += " (" + (noise.Has("tune-datasets") ? noise.Get("tune-datasets")->text : "3") +
         " tuning trajectories, " +
         (noise.Has("tune-starts") ? noise.Get("tune-starts")->text : "1") + " start(s))";
  return d;
}

// ---------------------------------------------------------------------------
// [report]

const std::set<std::string> kReferenceStats = {"mean", "var", "std", "median"};

bool MetricExists(const StudyConfig& c, const std::string& metric) {
  if (metric == "mean_nees" || metric == "mean_nis" || metric == "loglik") return true;
  // mse_STATE is derived in the report (the square of each run's RMSE).
  for (const auto& s : c.state_columns)
    if (metric == "rmse_" + s || metric == "mae_" + s || metric == "mse_" + s) return true;
  return false;
}

bool FilterRefExists(const StudyConfig& c, const std::string& ref) {
  const auto slash = ref.find('/');
  const std::string f = ref.substr(0, slash);
  bool found = false;
  for (const auto& fc : c.filters) found |= fc.name == f;
  if (!found) return false;
  if (slash == std::string::npos) return true;
  for (const auto& nc : c.noises)
    if (nc.name == ref.substr(slash + 1)) return true;
  return false;
}

void ParseReport(const Section& sec, const po::variables_map& vm, StudyConfig* c,
                 const ConfigErrors& err) {
  auto line_of = [&](const std::string& key, const std::string& value) {
    for (const Entry& e : sec.entries)
      if (e.key == key && e.value == value) return e.line;
    return sec.line;
  };
  const SectionValues v(sec, vm, err);
  if (v.Has("paper")) c->paper = v.Get("paper")->text;
  if (v.Has("title")) c->title = v.Get("title")->text;
  if (v.Has("tables")) {
    c->tables = Checked(*v.Get("tables"), err, [](const std::string& t) {
      std::vector<std::string> out;
      for (const auto& part : Split(t, ',')) {
        const std::string k = Trim(part);
        if (k != "rmse" && k != "mse" && k != "mae")
          throw InputError("tables: expected rmse, mse or mae, got '" + k + "'");
        out.push_back(k);
      }
      return out;
    });
  }
  if (v.Has("overview") && Trim(v.Get("overview")->text) == "none") {
    c->overview = {"none"};  // no overview table
  } else if (v.Has("overview")) {
    for (const auto& part : Split(v.Get("overview")->text, ',')) {
      const std::string metric = Trim(part);
      if (metric != "us_per_step" && !MetricExists(*c, metric))
        v.Fail("overview", "unknown metric '" + metric +
                               "' (rmse_STATE, mse_STATE, mae_STATE, "
                               "mean_nees, mean_nis, loglik)");
      c->overview.push_back(metric);
    }
  }
  auto repeated = [&](const std::string& key) {
    const std::string full = sec.full + "." + key;
    return vm.count(full) ? vm[full].as<std::vector<std::string>>() : std::vector<std::string>{};
  };
  c->notes = repeated("note");
  for (const std::string& text : repeated("reference")) {
    const int line = line_of("reference", text);
    const auto parts = Split(text, '|');
    std::istringstream in(parts[0]);
    std::string group, metric, stat;
    in >> group >> metric;
    ReferenceValue r;
    const auto g = Split(group, '/');
    if (g.size() != 3)
      err.Fail(line,
               "[report] reference: expected SCENARIO/FILTER/NOISE METRIC stat=value..., "
               "got '" +
                   text + "'");
    r.scenario = g[0];
    r.filter = g[1];
    r.noise = g[2];
    r.metric = metric;
    if (!MetricExists(*c, metric))
      err.Fail(line, "[report] reference: unknown metric '" + metric +
                         "' (rmse_STATE, mae_STATE, mean_nees, mean_nis, loglik)");
    bool scen_ok = r.scenario == "*", filt_ok = r.filter == "*", noise_ok = r.noise == "*";
    for (const auto& s : c->scenarios)
      scen_ok |= s.name == r.scenario || s.section == "scenario." + r.scenario;
    for (const auto& f : c->filters) filt_ok |= f.name == r.filter;
    for (const auto& nc : c->noises) noise_ok |= nc.name == r.noise;
    if (!scen_ok || !filt_ok || !noise_ok)
      err.Fail(line, "[report] reference: '" + group +
                         "' names no scenario/filter/noise of "
                         "this study");
    while (in >> stat) {
      const auto eq = stat.find('=');
      const std::string name = stat.substr(0, eq);
      if (eq == std::string::npos || !kReferenceStats.count(name))
        err.Fail(line,
                 "[report] reference: expected mean=, var=, std= or median=, got '" + stat + "'");
      try {
        r.stats.emplace_back(name, ParseNumber(stat.substr(eq + 1), name));
      } catch (const InputError& e) {
        err.Fail(line, std::string("[report] reference: ") + e.what());
      }
    }
    if (r.stats.empty()) err.Fail(line, "[report] reference: no values in '" + text + "'");
    if (parts.size() > 1) r.source = parts[1];
    c->references.push_back(r);
  }
  for (const std::string& text : repeated("claim")) {
    const int line = line_of("claim", text);
    const auto parts = Split(text, '|');
    const auto colon = parts[0].find(':');
    Claim cl;
    std::istringstream in(colon == std::string::npos ? "" : parts[0].substr(colon + 1));
    std::string extra;
    if (colon == std::string::npos || !(in >> cl.a >> cl.op >> cl.b) || (in >> extra))
      err.Fail(line, "[report] claim: expected 'METRIC: FILTER[/NOISE] OP FILTER[/NOISE]', got '" +
                         text + "'");
    cl.metric = Trim(parts[0].substr(0, colon));
    if (!MetricExists(*c, cl.metric))
      err.Fail(line, "[report] claim: unknown metric '" + cl.metric + "'");
    if (cl.op != "<" && cl.op != "<=" && cl.op != ">" && cl.op != ">=")
      err.Fail(line, "[report] claim: operator must be <, <=, > or >=, got '" + cl.op + "'");
    for (const auto* ref : {&cl.a, &cl.b})
      if (!FilterRefExists(*c, *ref))
        err.Fail(line,
                 "[report] claim: '" + *ref + "' is not FILTER or FILTER/NOISE of this study");
    cl.text = parts.size() > 1 ? parts[1] : "";
    c->claims.push_back(cl);
  }
}

}  // namespace

StudyConfig ParseStudyConfig(const std::string& text, const std::string& path) {
  const ConfigErrors err(path);
  const std::vector<Section> sections = Scan(text, err);
  const po::variables_map vm = ParseWithProgramOptions(text, sections, err);

  StudyConfig c;
  c.path = path;
  c.text = text;
  const Section* study = nullptr;
  const Section* report = nullptr;
  std::vector<const Section*> scenario_secs, filter_secs, noise_secs;
  for (const Section& s : sections) {
    if (s.kind == "study") study = &s;
    if (s.kind == "report") report = &s;
    if (s.kind == "scenario") scenario_secs.push_back(&s);
    if (s.kind == "filter") filter_secs.push_back(&s);
    if (s.kind == "noise") noise_secs.push_back(&s);
  }
  if (!study) err.Fail(1, "no [study] section");
  if (scenario_secs.empty()) err.Fail(study->line, "no [scenario.NAME] section");
  if (filter_secs.empty()) err.Fail(study->line, "no [filter.NAME] section");
  if (noise_secs.empty()) err.Fail(study->line, "no [noise.NAME] section");
  c.study = ParseStudy(SectionValues(*study, vm, err));

  // Filters and noise settings.
  std::vector<SectionValues> filter_values, noise_values;
  for (const Section* s : filter_secs) {
    filter_values.emplace_back(*s, vm, err);
    const SectionValues& v = filter_values.back();
    FilterConfig f;
    f.name = s->name;
    if (!v.Has("kind")) v.FailSection("'kind' is required (kf, ekf, iekf, ukf, ckf, ghkf, pf)");
    f.kind = v.Get("kind")->text;
    Checked(*v.Get("kind"), err, [](const std::string& t) { return ParseFilterKind(t); });
    f.description = f.kind;
    for (const Entry& e : s->entries) {
      if (e.key == "kind" || e.key == "scenarios") continue;
      if (e.key == "description") {
        f.description = e.value;
        break;
      }
      f.description += " " + e.key + "=" + e.value;
    }
    if (v.Has("scenarios"))
      f.scenarios = Checked(*v.Get("scenarios"), err,
                            [](const std::string& t) { return ParseNameList(t, "scenarios"); });
    c.filters.push_back(f);
  }
  for (const Section* s : noise_secs) {
    noise_values.emplace_back(*s, vm, err);
    const SectionValues& v = noise_values.back();
    NoiseConfig nc;
    nc.name = s->name;
    const int nq = int(v.Has("q")) + int(v.Has("q-diag")) + int(v.Has("q-white-accel"));
    const int nr = int(v.Has("r")) + int(v.Has("r-diag"));
    if (nq != 1)
      v.FailSection(
          "give exactly one of q, q-diag, q-white-accel (q = oracle: the truth's process "
          "noise; q = tuned: the likelihood tuner)");
    if (nr != 1) v.FailSection("give exactly one of r, r-diag (r = oracle: the truth's noise)");
    nc.description = v.Has("description") ? v.Get("description")->text : NoiseDescription(v);
    auto text_of = [&](const char* key) { return v.Has(key) ? v.Get(key)->text : std::string(); };
    nc.role = text_of("q") == "tuned" || text_of("r") == "tuned"     ? "tuned"
              : text_of("q") == "oracle" && text_of("r") == "oracle" ? "oracle"
                                                                     : "hand";
    if (v.Has("role")) {
      nc.role = v.Get("role")->text;
      if (nc.role != "hand" && nc.role != "tuned" && nc.role != "oracle" && nc.role != "other")
        v.Fail("role", "expected hand, tuned, oracle or other, got '" + nc.role + "'");
    }
    if (v.Has("scenarios"))
      nc.scenarios = Checked(*v.Get("scenarios"), err,
                             [](const std::string& t) { return ParseNameList(t, "scenarios"); });
    if (v.Has("filters")) {
      nc.filters = Checked(*v.Get("filters"), err,
                           [](const std::string& t) { return ParseNameList(t, "filters"); });
      for (const auto& name : nc.filters) {
        bool found = false;
        for (const auto& f : c.filters) found |= f.name == name;
        if (!found) v.Fail("filters", "no [filter." + name + "]");
      }
    }
    c.noises.push_back(nc);
  }
  for (size_t i = 0; i < filter_secs.size(); ++i)
    for (const auto& name : c.filters[i].scenarios) {
      bool found = false;
      for (const Section* s : scenario_secs) found |= s->name == name;
      if (!found) filter_values[i].Fail("scenarios", "no [scenario." + name + "]");
    }
  for (size_t i = 0; i < noise_secs.size(); ++i)
    for (const auto& name : c.noises[i].scenarios) {
      bool found = false;
      for (const Section* s : scenario_secs) found |= s->name == name;
      if (!found) noise_values[i].Fail("scenarios", "no [scenario." + name + "]");
    }

  // Scenarios, expanded, each with its filter x noise combinations.
  std::set<std::string> names;
  std::vector<std::unique_ptr<Section>> expanded_storage;
  for (const Section* s : scenario_secs) {
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
      ScenarioConfig sc = BuildScenario(v, err);
      sc.choices = choices;
      sc.name = s->name;
      for (const auto& ch : choices) sc.name += "." + ch.second;
      if (!names.insert(sc.name).second)
        err.Fail(s->line, "scenario name '" + sc.name + "' occurs twice");
      for (const auto& st : sc.model->states)
        if (std::find(c.state_columns.begin(), c.state_columns.end(), st) == c.state_columns.end())
          c.state_columns.push_back(st);
      for (size_t fi = 0; fi < c.filters.size(); ++fi) {
        const auto& fs = c.filters[fi].scenarios;
        if (!fs.empty() && std::find(fs.begin(), fs.end(), s->name) == fs.end()) continue;
        for (size_t ni = 0; ni < c.noises.size(); ++ni) {
          const auto& ns = c.noises[ni].scenarios;
          if (!ns.empty() && std::find(ns.begin(), ns.end(), s->name) == ns.end()) continue;
          const auto& nf = c.noises[ni].filters;
          if (!nf.empty() && std::find(nf.begin(), nf.end(), c.filters[fi].name) == nf.end())
            continue;
          sc.combos.push_back(
              BuildCombo(sc, v, int(fi), filter_values[fi], int(ni), noise_values[ni], err));
        }
      }
      if (sc.combos.empty())
        err.Fail(s->line, "[" + s->full + "]: no filter and noise setting applies to it");
      if (sc.model->run_filter == nullptr)
        err.Fail(s->line, "model '" + sc.model->name + "' has no filter runner in this build");
      c.scenarios.push_back(std::move(sc));
    }
  }
  if (report) ParseReport(*report, vm, &c, err);
  for (int k : c.study.keep_runs)
    if (k >= c.study.runs && study->Find("keep-runs"))
      err.Fail(study->Find("keep-runs")->line, "[study] keep-runs: run " + std::to_string(k) +
                                                   " >= runs (" + std::to_string(c.study.runs) +
                                                   "); runs are numbered from 0");
  return c;
}

StudyConfig LoadStudyConfig(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot read study config '" + path + "'");
  std::ostringstream s;
  s << in.rdbuf();
  return ParseStudyConfig(s.str(), path);
}

}  // namespace estlab
