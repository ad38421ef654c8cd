// The [report] section: paper, tables, references and claims, each checked
// against the study's filters, noises and metrics (study_config_parts.h).
#include <set>

#include "src/core/parse.h"
#include "studies/config/study_config_parts.h"

namespace estlab::study_config {

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

namespace {

// tables = rmse, mse, mae: the error tables of the report.
std::vector<std::string> ParseTables(const Value& v, const ConfigErrors& err) {
  return Checked(v, err, [](const std::string& t) {
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

// overview = METRIC,... (or none): the columns of the overview table.
void ParseOverview(const SectionValues& v, StudyConfig* c) {
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
}

// The stat=value words of a reference (mean, var, std, median) into r.
void ParseReferenceStats(std::istream& in, int line, const ConfigErrors& err, ReferenceValue* r) {
  std::string stat;
  while (in >> stat) {
    const auto eq = stat.find('=');
    const std::string name = stat.substr(0, eq);
    if (eq == std::string::npos || !kReferenceStats.count(name))
      err.Fail(line,
               "[report] reference: expected mean=, var=, std= or median=, got '" + stat + "'");
    try {
      r->stats.emplace_back(name, ParseNumber(stat.substr(eq + 1), name));
    } catch (const InputError& e) {
      err.Fail(line, std::string("[report] reference: ") + e.what());
    }
  }
}

// reference = SCENARIO/FILTER/NOISE METRIC stat=value... [| source], each
// name one of the study's (or *), at its line.
ReferenceValue ParseReference(const std::string& text, int line, const StudyConfig& c,
                              const ConfigErrors& err) {
  const auto parts = Split(text, '|');
  std::istringstream in(parts[0]);
  std::string group, metric;
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
  if (!MetricExists(c, metric))
    err.Fail(line, "[report] reference: unknown metric '" + metric +
                       "' (rmse_STATE, mae_STATE, mean_nees, mean_nis, loglik)");
  bool scen_ok = r.scenario == "*", filt_ok = r.filter == "*", noise_ok = r.noise == "*";
  for (const auto& s : c.scenarios)
    scen_ok |= s.name == r.scenario || s.section == "scenario." + r.scenario;
  for (const auto& f : c.filters) filt_ok |= f.name == r.filter;
  for (const auto& nc : c.noises) noise_ok |= nc.name == r.noise;
  if (!scen_ok || !filt_ok || !noise_ok)
    err.Fail(line, "[report] reference: '" + group +
                       "' names no scenario/filter/noise of "
                       "this study");
  ParseReferenceStats(in, line, err, &r);
  if (r.stats.empty()) err.Fail(line, "[report] reference: no values in '" + text + "'");
  if (parts.size() > 1) r.source = parts[1];
  return r;
}

// claim = METRIC: FILTER[/NOISE] OP FILTER[/NOISE] [| text], at its line.
Claim ParseClaim(const std::string& text, int line, const StudyConfig& c, const ConfigErrors& err) {
  const auto parts = Split(text, '|');
  const auto colon = parts[0].find(':');
  Claim cl;
  std::istringstream in(colon == std::string::npos ? "" : parts[0].substr(colon + 1));
  std::string extra;
  if (colon == std::string::npos || !(in >> cl.a >> cl.op >> cl.b) || (in >> extra))
    err.Fail(line, "[report] claim: expected 'METRIC: FILTER[/NOISE] OP FILTER[/NOISE]', got '" +
                       text + "'");
  cl.metric = Trim(parts[0].substr(0, colon));
  if (!MetricExists(c, cl.metric))
    err.Fail(line, "[report] claim: unknown metric '" + cl.metric + "'");
  if (cl.op != "<" && cl.op != "<=" && cl.op != ">" && cl.op != ">=")
    err.Fail(line, "[report] claim: operator must be <, <=, > or >=, got '" + cl.op + "'");
  for (const auto* ref : {&cl.a, &cl.b})
    if (!FilterRefExists(c, *ref))
      err.Fail(line, "[report] claim: '" + *ref + "' is not FILTER or FILTER/NOISE of this study");
  cl.text = parts.size() > 1 ? parts[1] : "";
  return cl;
}

}  // namespace

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
  if (v.Has("tables")) c->tables = ParseTables(*v.Get("tables"), err);
  ParseOverview(v, c);
  auto repeated = [&](const std::string& key) {
    const std::string full = sec.full + "." + key;
    return vm.count(full) ? vm[full].as<std::vector<std::string>>() : std::vector<std::string>{};
  };
  c->notes = repeated("note");
  for (const std::string& text : repeated("reference"))
    c->references.push_back(ParseReference(text, line_of("reference", text), *c, err));
  for (const std::string& text : repeated("claim"))
    c->claims.push_back(ParseClaim(text, line_of("claim", text), *c, err));
}

}  // namespace estlab::study_config
