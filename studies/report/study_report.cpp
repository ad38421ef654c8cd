#include "studies/report/study_report.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>

#include "src/core/types.h"
#include "studies/report/study_report_parts.h"

namespace estlab {

namespace study_report {

std::vector<double> Values(const GroupValues* g, const std::string& metric) {
  if (!g) return {};
  // mse_STATE: each run's mean squared error, the square of its RMSE (paper
  // 001 reports MSE; runs.csv keeps the RMSE only).
  if (metric.compare(0, 4, "mse_") == 0) {
    std::vector<double> v = Values(g, "rmse_" + metric.substr(4));
    for (double& x : v) x *= x;
    return v;
  }
  const auto it = g->values.find(metric);
  return it == g->values.end() ? std::vector<double>{} : it->second;
}

std::string MeanCell(const MetricStats& s) {
  if (s.n == 0) return "–";
  return Sig(s.mean) + " ± " + Sig(s.std, 2) + " [" + Sig(s.ci95_lo) + ", " + Sig(s.ci95_hi) + "]";
}

}  // namespace study_report

namespace {

using namespace study_report;

const char* TableTitle(const std::string& kind) {
  if (kind == "mse") return "MSE (mean squared error, the square of the RMSE)";
  if (kind == "mae") return "MAE (mean absolute error)";
  return "RMSE";
}

std::string ParamsText(const ScenarioConfig& sc) {
  std::string out;
  for (size_t i = 0; i < sc.model->params.size(); ++i)
    out += (i ? ", " : "") + sc.model->params[i].name + " = " + FormatNumber(sc.truth.params[i]);
  return out;
}

std::string VectorText(const std::vector<double>& v) {
  std::string out = "[";
  for (size_t i = 0; i < v.size(); ++i) out += (i ? ", " : "") + FormatNumber(v[i]);
  return out + "]";
}

std::string DiagText(const std::vector<double>& a, int n) {
  bool diagonal = true;
  std::vector<double> d;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      if (i == j)
        d.push_back(a[i * n + j]);
      else if (a[i * n + j] != 0.0)
        diagonal = false;
    }
  return (diagonal ? "diag" : "matrix with diagonal ") + VectorText(d);
}

// The updates a run's mean NIS averages (the longest file, after the burn-in, on recorded data).
int MeasurementsPerRun(const ScenarioConfig& sc) {
  return sc.steps + (sc.measure_at_t0 ? 1 : 0) - sc.burn_in;
}

// The updates of a simulated run and their observed components, each output
// at its sensor's rate (truth.output_every: measured in rows k with
// k % every == 0); every output in every row without rates.
void ObservedPerRun(const ScenarioConfig& sc, int nz, long* updates, long* dof) {
  const std::vector<int>& every = sc.truth.output_every;
  if (every.empty()) {
    *updates = MeasurementsPerRun(sc);
    *dof = *updates * nz;
    return;
  }
  long skipped = 0;
  for (long k = sc.measure_at_t0 ? 0 : 1; k <= long(sc.steps); ++k) {
    int observed = 0;
    for (const int e : every) observed += k % e == 0;
    if (observed == 0) continue;
    if (skipped++ < long(sc.burn_in)) continue;
    ++*updates;
    *dof += observed;
  }
}

bool Matches(const std::string& pattern, const ScenarioConfig& sc) {
  return pattern == "*" || pattern == sc.name || "scenario." + pattern == sc.section;
}

// The Q/R the tuner found for this scenario, beside the truth's.
void TunedTable(std::ostringstream& md, const StudyTables& t, const ScenarioConfig& sc) {
  const CsvText& tu = t.tuned;
  bool any = false;
  for (const auto& r : tu.rows) any |= r[0] == sc.name;
  if (!any) return;
  const int n = int(sc.model->states.size());
  std::string oracle_q =
      sc.oracle_q_white_accel ? "qc " + FormatNumber(sc.oracle_qc) : DiagText(sc.oracle_q, n);
  const int m = int(sc.truth.meas_noise_var.size());
  if (sc.recorded)
    md << "\nTuned noise (the noise setting's estimator, maximum likelihood unless it says "
          "otherwise, on the scenario's "
       << sc.tune_runs.size()
       << " tune-data files, then fixed for every run; recorded data: the true noise is "
          "unknown):\n\n";
  else
    md << "\nTuned noise (the noise setting's estimator, maximum likelihood unless it says "
          "otherwise, on the scenario's own tuning "
          "trajectories, then fixed for every run); the truth has Q "
       << oracle_q << ", R " << DiagText(sc.oracle_r, m) << ":\n\n";
  md << "| filter | noise | status | Q | R | NLL start → tuned | iterations |\n"
     << "|---|---|---|---|---|---|---|\n";
  const int f = tu.Column("filter"), no = tu.Column("noise"), st = tu.Column("status");
  const int qc = tu.Column("qc"), q = tu.Column("q"), r = tu.Column("r");
  const int qp = tu.Column("q_param"), rp = tu.Column("r_param");
  const int n0 = tu.Column("nll_initial"), n1 = tu.Column("nll_tuned"),
            it = tu.Column("iterations");
  const int msg = tu.Column("message");
  for (const auto& row : tu.rows) {
    if (row[0] != sc.name) continue;
    auto shorten = [](const std::string& values) {  // "a b c" with 4 significant digits
      std::istringstream in(values);
      std::string out, v;
      while (in >> v) {
        if (!out.empty()) out += ' ';
        out += Sig(std::strtod(v.c_str(), nullptr));
      }
      return out;
    };
    const std::string qtext = !row[qc].empty() ? "qc " + shorten(row[qc]) : shorten(row[q]);
    md << "| " << row[f] << " | " << row[no] << " | " << row[st]
       << (row[msg].empty() ? "" : ": " + row[msg]) << " | " << qtext << " (" << row[qp] << ") | "
       << shorten(row[r]) << " (" << row[rp] << ") | " << shorten(row[n0]) << " → "
       << shorten(row[n1]) << " | " << row[it] << " |\n";
  }
  md << "\n(Q and R row-major; for white-accel Q is qc · Q(dt).)\n\n";
}

void ScenarioSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t,
                     const ScenarioConfig& sc) {
  const int nx = int(sc.model->states.size());
  const MeasurementDesc& meas = sc.model->FindMeasurement(sc.truth.measurement);
  const int nz = int(meas.outputs.size());
  md << "## Scenario `" << sc.name << "`\n\n";
  md << "- model `" << sc.model->name << "` (" << ParamsText(sc) << ")\n";
  if (sc.recorded) {
    md << "- data: " << sc.truth_description << " (one run each, up to " << sc.steps
       << " rows), measurement `" << meas.name << "`, median dt = " << FormatNumber(sc.truth.dt)
       << "\n";
  } else {
    md << "- truth: " << sc.truth_description << "; x0 = " << VectorText(sc.truth.x0)
       << (sc.sample_x0 ? " + a draw from N(0, P0) per run" : "") << "\n";
    md << "- measurement `" << meas.name << "` every dt = " << FormatNumber(sc.truth.dt) << " for "
       << sc.steps << " steps, "
       << (sc.poisson_meas ? "Poisson counts with lambda " + VectorText(sc.poisson_lambda)
                           : "noise variance " + VectorText(sc.truth.meas_noise_var))
       << "\n";
  }
  md << "- filter prior x0 = " << VectorText(sc.prior_x0) << ", P0 = " << DiagText(sc.prior_p0, nx)
     << "\n\n";

  for (const std::string& kind : sc.has_truth ? c.tables : std::vector<std::string>{}) {
    std::string upper = kind;
    for (char& ch : upper) ch = char(std::toupper(static_cast<unsigned char>(ch)));
    md << TableTitle(kind)
       << " per state over each run, then mean ± sd over runs [95 % CI of the mean]:\n\n";
    md << "| filter | noise | ok/runs |";
    for (const auto& s : sc.model->states) md << " " << upper << " " << s << " |";
    md << " µs/step |\n|---|---|---|";
    for (int i = 0; i < nx; ++i) md << "---|";
    md << "---|\n";
    for (const Combo& cb : sc.combos) {
      const std::string& f = c.filters[cb.filter].name;
      const std::string& n = c.noises[cb.noise].name;
      const GroupValues* g = FindGroup(t, GroupKey(sc.name, f, n));
      md << "| " << f << " | " << n << " | " << (g ? g->ok : 0) << "/" << (g ? g->runs : 0) << " |";
      for (const auto& s : sc.model->states)
        md << " " << MeanCell(ComputeStats(Values(g, kind + "_" + s))) << " |";
      const MetricStats us = ComputeStats(g ? g->us_per_step : std::vector<double>{});
      md << " " << Sig(us.mean, 3) << " |\n";
    }
    md << "\n";
  }
  TunedTable(md, t, sc);
  double nees_b[2], nis_b[2];
  ChiSquareBounds95(MeasurementsPerRun(sc), nx, nees_b);
  long nis_updates = 0, nis_dof = 0;
  ObservedPerRun(sc, nz, &nis_updates, &nis_dof);
  ChiSquareMeanBounds95(nis_updates, nis_dof, nis_b);
  md << "\nConsistency: time-averaged NEES (dimension " << nx << ") and NIS (dimension " << nz;
  if (nis_dof != nis_updates * nz)  // sensor rates: fewer components in some rows
    md << ", " << nis_dof << " observed components over " << nis_updates << " updates";
  md << ") per run; a consistent filter has 95 % of its runs inside the χ² bounds "
     << "[" << Sig(nees_b[0]) << ", " << Sig(nees_b[1]) << "] and [" << Sig(nis_b[0]) << ", "
     << Sig(nis_b[1]) << "].\n\n";
  md << "| filter | noise | mean NEES | runs inside | mean NIS | runs inside | mean log-lik |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const Combo& cb : sc.combos) {
    const std::string& f = c.filters[cb.filter].name;
    const std::string& n = c.noises[cb.noise].name;
    const GroupValues* g = FindGroup(t, GroupKey(sc.name, f, n));
    const MetricStats nees = ComputeStats(Values(g, "mean_nees"));
    const MetricStats nis = ComputeStats(Values(g, "mean_nis"));
    const MetricStats nees_in = ComputeStats(Values(g, "nees_in95"));
    const MetricStats nis_in = ComputeStats(Values(g, "nis_in95"));
    const MetricStats ll = ComputeStats(Values(g, "loglik"));
    md << "| " << f << " | " << n << " | " << Sig(nees.mean) << " | "
       << (nees_in.n ? Sig(100 * nees_in.mean, 3) + " %" : "–") << " | " << Sig(nis.mean) << " | "
       << (nis_in.n ? Sig(100 * nis_in.mean, 3) + " %" : "–") << " | " << Sig(ll.mean, 6) << " |\n";
  }
  md << "\n";
}

// The paper's numbers beside ours: one row per scenario x filter x noise
// that a reference names, one paper/estlab column pair per metric and
// statistic (so a sweep such as paper 003's Tables 1 and 2 reads as a table).
void ReferenceSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t) {
  if (c.references.empty()) return;
  std::vector<std::pair<std::string, std::string>> columns;  // (metric, stat)
  for (const ReferenceValue& r : c.references)
    for (const auto& st : r.stats)
      if (std::find(columns.begin(), columns.end(), std::make_pair(r.metric, st.first)) ==
          columns.end())
        columns.emplace_back(r.metric, st.first);
  md << "## The paper's numbers beside estlab's\n\n| scenario | filter | noise |";
  for (const auto& [metric, stat] : columns)
    md << " " << metric << " " << stat << " paper | estlab |";
  md << " n | µs/step | source |\n|---|---|---|";
  for (size_t i = 0; i < columns.size(); ++i) md << "---|---|";
  md << "---|---|---|\n";
  for (const ScenarioConfig& sc : c.scenarios) {
    for (const Combo& cb : sc.combos) {
      const std::string& f = c.filters[cb.filter].name;
      const std::string& n = c.noises[cb.noise].name;
      std::vector<double> paper(columns.size(), std::nan(""));
      std::vector<std::string> sources;
      for (const ReferenceValue& r : c.references) {
        if (!Matches(r.scenario, sc) || (r.filter != "*" && r.filter != f) ||
            (r.noise != "*" && r.noise != n))
          continue;
        for (const auto& [stat, value] : r.stats) {
          const auto col =
              std::find(columns.begin(), columns.end(), std::make_pair(r.metric, stat));
          paper[col - columns.begin()] = value;
        }
        if (!r.source.empty() &&
            std::find(sources.begin(), sources.end(), r.source) == sources.end())
          sources.push_back(r.source);
      }
      if (std::all_of(paper.begin(), paper.end(), [](double v) { return std::isnan(v); })) continue;
      const GroupValues* g = FindGroup(t, GroupKey(sc.name, f, n));
      md << "| " << sc.name << " | " << f << " | " << n << " |";
      long count = 0;
      for (size_t i = 0; i < columns.size(); ++i) {
        const MetricStats s = ComputeStats(Values(g, columns[i].first));
        count = std::max(count, s.n);
        const std::string& stat = columns[i].second;
        std::string ours = "–";
        if (s.n > 0) {
          if (stat == "mean")
            ours = Sig(s.mean) + " [" + Sig(s.ci95_lo) + ", " + Sig(s.ci95_hi) + "]";
          if (stat == "var") ours = Sig(s.var);
          if (stat == "std") ours = Sig(s.std);
          if (stat == "median") ours = Sig(s.median);
        }
        md << " " << Sig(paper[i]) << " | " << ours << " |";
      }
      const MetricStats us = ComputeStats(g ? g->us_per_step : std::vector<double>{});
      std::string src;
      for (const auto& x : sources) src += (src.empty() ? "" : "; ") + x;
      md << " " << count << " | " << Sig(us.mean, 3) << " | " << src << " |\n";
    }
  }
  md << "\nestlab's mean is given with the 95 % confidence interval of the mean over the n "
        "runs; var and std are over runs.\n\n";
}

// ---------------------------------------------------------------------------
// Hand-tuned vs auto-tuned vs oracle Q/R (noise roles, see NoiseConfig::role).

struct RoleCell {
  std::string noise;
  MetricStats stats;
  std::vector<double> values;
  std::vector<long> runs;
};

RoleCell Cell(const StudyTables& t, const ScenarioConfig& sc, const std::string& filter,
              const std::string& noise, const std::string& metric) {
  RoleCell cell;
  cell.noise = noise;
  const GroupValues* g = FindGroup(t, GroupKey(sc.name, filter, noise));
  cell.values = Values(g, metric);
  if (g) cell.runs = g->run_index;
  cell.stats = ComputeStats(cell.values);
  return cell;
}

// True when two specs use the same Q and R (a hand setting equal to the oracle).
bool SameNoise(const FilterSpec& a, const FilterSpec& b) {
  if (a.q_white_accel != b.q_white_accel || a.r != b.r) return false;
  return a.q_white_accel ? a.qc == b.qc : a.q == b.q;
}

std::string TunerStatus(const StudyTables& t, const std::string& scen, const std::string& filter,
                        const std::string& noise) {
  const CsvText& tu = t.tuned;
  const int f = tu.Column("filter"), n = tu.Column("noise"), st = tu.Column("status");
  if (f < 0 || n < 0 || st < 0) return "";
  for (const auto& row : tu.rows)
    if (row[0] == scen && row[f] == filter && row[n] == noise) return row[st];
  return "";
}

// One scenario x filter x tuned setting of the comparison. A setting's score
// is the mean over the states of its mean RMSE divided by the oracle's (the
// reference; the first hand setting when there is no oracle), so states in
// different units count alike and the oracle scores 1.
struct CompareCase {
  const ScenarioConfig* sc = nullptr;
  std::string filter, tuned, reference, best_hand;
  std::vector<std::string> hands;
  bool has_oracle = false, hand_is_oracle = false;
  std::string tuner_status;
  double auto_score = NAN, hand_score = NAN;
  MetricStats auto_vs_ref, auto_vs_hand;  // per-run paired score differences
};

// Per-run score difference a - b (normalised by the reference means) over
// the runs where all three finished every state.
MetricStats ScoreDifference(const StudyTables& t, const ScenarioConfig& sc,
                            const std::string& filter, const std::string& a, const std::string& b,
                            const std::string& ref) {
  return PairedScoreDifference(t, sc, {filter, a}, {filter, b}, {filter, ref});
}

double Score(const StudyTables& t, const ScenarioConfig& sc, const std::string& filter,
             const std::string& noise, const std::string& ref) {
  return ScoreAgainst(t, sc, {filter, noise}, {filter, ref});
}

}  // namespace

namespace study_report {

MetricStats PairedScoreDifference(const StudyTables& t, const ScenarioConfig& sc,
                                  const FilterNoise& a, const FilterNoise& b,
                                  const FilterNoise& ref) {
  const auto& states = sc.model->states;
  std::map<long, std::pair<double, int>> per_run;  // run -> (sum, states seen)
  for (const auto& st : states) {
    const std::string metric = "rmse_" + st;
    const RoleCell ca = Cell(t, sc, a.filter, a.noise, metric);
    const RoleCell cb = Cell(t, sc, b.filter, b.noise, metric);
    const double scale = Cell(t, sc, ref.filter, ref.noise, metric).stats.mean;
    std::map<long, double> vb;
    for (size_t i = 0; i < cb.runs.size(); ++i) vb[cb.runs[i]] = cb.values[i];
    for (size_t i = 0; i < ca.runs.size(); ++i) {
      const auto it = vb.find(ca.runs[i]);
      if (it == vb.end() || !std::isfinite(ca.values[i]) || !std::isfinite(it->second)) continue;
      auto& acc = per_run[ca.runs[i]];
      acc.first += (ca.values[i] - it->second) / scale;
      ++acc.second;
    }
  }
  std::vector<double> d;
  for (const auto& [run, acc] : per_run)
    if (acc.second == int(states.size())) d.push_back(acc.first / double(states.size()));
  return ComputeStats(d);
}

double ScoreAgainst(const StudyTables& t, const ScenarioConfig& sc, const FilterNoise& x,
                    const FilterNoise& ref) {
  double sum = 0;
  for (const auto& st : sc.model->states) {
    const MetricStats ms = Cell(t, sc, x.filter, x.noise, "rmse_" + st).stats;
    const double r = Cell(t, sc, ref.filter, ref.noise, "rmse_" + st).stats.mean;
    if (ms.n == 0 || !(r > 0)) return NAN;
    sum += ms.mean / r;
  }
  return sum / double(sc.model->states.size());
}

}  // namespace study_report

namespace {

// The case of one tuned setting `tc` of filter `fi` in scenario `sc`: its
// score and those of the hand settings against the reference, the best hand
// setting and the paired differences.
CompareCase MakeCompareCase(const StudyConfig& c, const StudyTables& t, const ScenarioConfig& sc,
                            size_t fi, const Combo* tc, const std::vector<const Combo*>& hands,
                            const std::vector<const Combo*>& oracles) {
  CompareCase k;
  k.sc = &sc;
  k.filter = c.filters[fi].name;
  k.tuned = c.noises[tc->noise].name;
  k.has_oracle = !oracles.empty();
  k.reference = c.noises[(k.has_oracle ? oracles[0] : hands[0])->noise].name;
  k.tuner_status = TunerStatus(t, sc.name, k.filter, k.tuned);
  k.auto_score = Score(t, sc, k.filter, k.tuned, k.reference);
  for (const Combo* h : hands) {
    const std::string name = c.noises[h->noise].name;
    k.hands.push_back(name);
    const double score = Score(t, sc, k.filter, name, k.reference);
    if (std::isfinite(score) && !(score >= k.hand_score)) {
      k.hand_score = score;
      k.best_hand = name;
      k.hand_is_oracle = false;
      for (const Combo* o : oracles) k.hand_is_oracle |= SameNoise(h->spec, o->spec);
    }
  }
  k.auto_vs_ref = ScoreDifference(t, sc, k.filter, k.tuned, k.reference, k.reference);
  if (!k.best_hand.empty())
    k.auto_vs_hand = ScoreDifference(t, sc, k.filter, k.tuned, k.best_hand, k.reference);
  return k;
}

// Every scenario x filter x tuned setting (tuned once, not per run) that has
// a hand or an oracle setting to compare with.
std::vector<CompareCase> CompareCases(const StudyConfig& c, const StudyTables& t) {
  std::vector<CompareCase> cases;
  for (const ScenarioConfig& sc : c.scenarios) {
    if (!sc.has_truth) continue;  // no RMSE: RecordedDataSection compares them
    for (size_t fi = 0; fi < c.filters.size(); ++fi) {
      std::vector<const Combo*> hands, tuneds, oracles;
      for (const Combo& cb : sc.combos) {
        if (cb.filter != int(fi)) continue;
        const NoiseRole role = c.noises[cb.noise].role;
        if (role == NoiseRole::kHand) hands.push_back(&cb);
        if (role == NoiseRole::kTuned && !cb.tune_per_run) tuneds.push_back(&cb);  // per run: below
        if (role == NoiseRole::kOracle) oracles.push_back(&cb);
      }
      if (tuneds.empty() || (hands.empty() && oracles.empty())) continue;
      for (const Combo* tc : tuneds)
        cases.push_back(MakeCompareCase(c, t, sc, fi, tc, hands, oracles));
    }
  }
  return cases;
}

// " [lo, hi]": the 95 % CI of base + the paired differences d ("" for a
// single run).
std::string PairedInterval(const MetricStats& d, double base) {
  return d.n > 1 ? " [" + Sig(base + d.ci95_lo, 3) + ", " + Sig(base + d.ci95_hi, 3) + "]"
                 : std::string();
}

// The section's heading, its explanation and the table of scores, one row
// per case, and the count of cases that meet each target.
// The hand settings are "the paper's" only when [report] names a paper; a
// study of the user's own data has its own hand settings.
void CompareScoreTable(std::ostringstream& md, const StudyConfig& c,
                       const std::vector<CompareCase>& cases) {
  md << "## Hand-tuned vs auto-tuned vs oracle Q/R\n\n"
     << "Each filter with "
     << (c.paper.empty() ? "the config's hand noise settings"
                         : "the paper's hand-tuned noise settings")
     << ", with Q/R from the likelihood "
        "tuner (fitted on separate training trajectories, then fixed for every run) and with the "
        "truth's own noise (the oracle). **Score** = mean over the states of the setting's mean "
        "RMSE divided by the oracle's, so the oracle scores 1 and states in different units "
        "weigh alike; the best hand setting is the one with the lowest score. The interval is "
        "the 95 % CI from the per-run paired differences. Targets: auto ≤ 1.1 × oracle and "
        "auto ≤ best hand.\n\n"
     << "| scenario | filter | best hand setting | hand score | auto score [95 % CI] | "
        "auto ≤ 1.1 × oracle | auto ≤ best hand | tuner |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  long n_oracle = 0, ok_oracle = 0, n_hand = 0, ok_hand = 0;
  for (const CompareCase& k : cases) {
    const bool o_ok = k.has_oracle && k.auto_score <= 1.1;
    const bool h_ok = !k.best_hand.empty() && k.auto_score <= k.hand_score;
    if (k.has_oracle) ++n_oracle, ok_oracle += o_ok;
    if (!k.best_hand.empty()) ++n_hand, ok_hand += h_ok;
    md << "| " << k.sc->name << " | " << k.filter
       << (k.tuned != "tuned" ? " (" + k.tuned + ")" : "") << " | "
       << (k.best_hand.empty() ? "–"
                               : "`" + k.best_hand + "`" + (k.hand_is_oracle ? " (= oracle)" : ""))
       << " | " << Sig(k.hand_score, 3) << " | " << Sig(k.auto_score, 3)
       << PairedInterval(k.auto_vs_ref, 1.0) << " | "
       << (k.has_oracle ? (o_ok ? "yes" : "**no**") : "–") << " | "
       << (k.best_hand.empty() ? "–" : (h_ok ? "yes" : "**no**")) << " | "
       << (k.tuner_status.empty() ? "–" : k.tuner_status) << " |\n";
  }
  md << "\nauto ≤ 1.1 × oracle holds in " << ok_oracle << " of " << n_oracle
     << " scenario × filter cases; auto ≤ best hand in " << ok_hand << " of " << n_hand << ".\n\n";
}

// The states where auto loses most against the oracle: "state ratio ×" for
// every state whose mean RMSE is above 1.1 × the reference's.
std::string WorstStates(const StudyTables& t, const CompareCase& k) {
  std::string worst;
  for (const auto& st : k.sc->model->states) {
    const double a = Cell(t, *k.sc, k.filter, k.tuned, "rmse_" + st).stats.mean;
    const double o = Cell(t, *k.sc, k.filter, k.reference, "rmse_" + st).stats.mean;
    if (a / o > 1.1) worst += (worst.empty() ? "" : ", ") + st + " " + Sig(a / o, 3) + " ×";
  }
  return worst;
}

// The sentence for a case where auto scores above the best hand setting
// (`who` names the case, `tuner` is the tuner's status sentence or "").
std::string HandMissSentence(const CompareCase& k, const std::string& who,
                             const std::string& tuner) {
  const MetricStats& d = k.auto_vs_hand;
  const bool noise = d.n > 1 && d.ci95_lo <= 0.0 && d.ci95_hi >= 0.0;
  return who + ": auto scores " + Sig(k.auto_score, 3) + ", the best hand setting `" + k.best_hand +
         "` " + Sig(k.hand_score, 3) + " (paired difference " + Sig(d.mean, 3) +
         (d.n > 1 ? " [" + Sig(d.ci95_lo, 3) + ", " + Sig(d.ci95_hi, 3) + "]" : "") +
         (noise ? ", within the Monte Carlo noise" : ", significant") + ")." +
         (k.hand_is_oracle ? " That hand setting is the truth's own noise, so the tuner can at "
                             "best tie it."
                           : "") +
         (k.has_oracle && k.hand_score < 1.0 && !k.hand_is_oracle
              ? " The hand setting beats the truth's own noise (score < 1): the filter's "
                "process model is wrong (e.g. a coarse fixed-step integrator), its error acts "
                "as extra, time-correlated process noise, and larger hand Q/R absorb it better "
                "than the Q/R that maximise the likelihood of a white-noise model, which land "
                "near the oracle."
              : "") +
         tuner;
}

// Plain sentences for every case that misses a target, and why as far as
// the numbers tell.
void CompareMisses(std::ostringstream& md, const StudyTables& t,
                   const std::vector<CompareCase>& cases) {
  std::vector<std::string> misses;
  for (const CompareCase& k : cases) {
    const std::string who = "`" + k.sc->name + "` / " + k.filter;
    if (!std::isfinite(k.auto_score)) {
      misses.push_back(who + ": the auto-tuned setting has no finished runs" +
                       (k.tuner_status.empty() ? "" : " (tuner: " + k.tuner_status + ")") + ".");
      continue;
    }
    const std::string tuner = k.tuner_status.empty() || k.tuner_status == "converged"
                                  ? ""
                                  : " The tuner ended with status '" + k.tuner_status + "'.";
    const std::string worst = WorstStates(t, k);
    if (k.has_oracle && !(k.auto_score <= 1.1)) {
      misses.push_back(who + ": auto scores " + Sig(k.auto_score, 3) + " × the oracle" +
                       PairedInterval(k.auto_vs_ref, 1.0) + ", above 1.1" +
                       (worst.empty() ? "" : " (states above 1.1 × the oracle: " + worst + ")") +
                       "." + tuner);
    }
    if (!k.best_hand.empty() && !(k.auto_score <= k.hand_score))
      misses.push_back(HandMissSentence(k, who, tuner));
  }
  if (misses.empty()) {
    md << "Both targets hold in every case where they apply.\n\n";
  } else {
    md << "Where a target is missed:\n\n";
    for (const auto& m : misses) md << "- " << m << "\n";
    md << "\n";
  }
}

// "mean [ci95_lo, ci95_hi]" of a cell's RMSE, "–" without runs.
std::string RmseCellText(const RoleCell& cell) {
  return cell.stats.n ? Sig(cell.stats.mean) + " [" + Sig(cell.stats.ci95_lo, 3) + ", " +
                            Sig(cell.stats.ci95_hi, 3) + "]"
                      : std::string("–");
}

// Per state: the best hand setting (by score), auto and oracle mean RMSE.
void ComparePerStateTable(std::ostringstream& md, const StudyTables& t,
                          const std::vector<CompareCase>& cases) {
  md << "Per state, mean RMSE over the runs [95 % CI of the mean]:\n\n"
     << "| scenario | filter | state | best hand | auto | oracle | auto / oracle |\n"
     << "|---|---|---|---|---|---|---|\n";
  for (const CompareCase& k : cases) {
    for (const auto& st : k.sc->model->states) {
      const std::string metric = "rmse_" + st;
      const RoleCell a = Cell(t, *k.sc, k.filter, k.tuned, metric);
      const RoleCell o = Cell(t, *k.sc, k.filter, k.reference, metric);
      md << "| " << k.sc->name << " | " << k.filter << " | " << st << " | "
         << (k.best_hand.empty() ? "–"
                                 : RmseCellText(Cell(t, *k.sc, k.filter, k.best_hand, metric)))
         << " | " << RmseCellText(a) << " | " << (k.has_oracle ? RmseCellText(o) : "–") << " | "
         << (k.has_oracle && o.stats.n ? Sig(a.stats.mean / o.stats.mean, 3) : "–") << " |\n";
    }
  }
  md << "\n";
}

// The comparison of hand, auto-tuned and oracle Q/R: the score table, the
// missed targets and the per-state RMSE (nothing without a case to compare).
void HandAutoOracleSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t) {
  const std::vector<CompareCase> cases = CompareCases(c, t);
  if (cases.empty()) return;
  CompareScoreTable(md, c, cases);
  CompareMisses(md, t, cases);
  ComparePerStateTable(md, t, cases);
}

struct ClaimCase {
  std::string label;
  double mean_a, mean_b, diff, lo, hi;
  long n;
  bool holds, significant;
};

bool Compare(double a, double b, const std::string& op) {
  if (op == "<") return a < b;
  if (op == "<=") return a <= b;
  if (op == ">") return a > b;
  return a >= b;
}

std::vector<ClaimCase> EvaluateClaim(const StudyConfig& c, const StudyTables& t, const Claim& cl) {
  auto split = [](const std::string& ref) {
    const auto slash = ref.find('/');
    return std::make_pair(ref.substr(0, slash),
                          slash == std::string::npos ? std::string() : ref.substr(slash + 1));
  };
  const auto [fa, na] = split(cl.a);
  const auto [fb, nb] = split(cl.b);
  std::vector<ClaimCase> cases;
  // A side without a noise setting takes the other side's; with neither,
  // every noise setting is a case.
  std::vector<std::pair<std::string, std::string>> noise_pairs;
  if (na.empty() && nb.empty()) {
    for (const NoiseConfig& noise : c.noises) noise_pairs.emplace_back(noise.name, noise.name);
  } else {
    noise_pairs.emplace_back(na.empty() ? nb : na, nb.empty() ? na : nb);
  }
  for (const ScenarioConfig& sc : c.scenarios) {
    for (const auto& [a_noise, b_noise] : noise_pairs) {
      const GroupValues* ga = FindGroup(t, GroupKey(sc.name, fa, a_noise));
      const GroupValues* gb = FindGroup(t, GroupKey(sc.name, fb, b_noise));
      if (!ga || !gb) continue;
      const auto va = Values(ga, cl.metric), vb = Values(gb, cl.metric);
      if (va.empty() || vb.empty()) continue;
      // Pair the runs both filters finished.
      std::vector<double> pa, pb, d;
      size_t j = 0;
      for (size_t i = 0; i < ga->run_index.size(); ++i) {
        while (j < gb->run_index.size() && gb->run_index[j] < ga->run_index[i]) ++j;
        if (j < gb->run_index.size() && gb->run_index[j] == ga->run_index[i] &&
            std::isfinite(va[i]) && std::isfinite(vb[j])) {
          pa.push_back(va[i]);
          pb.push_back(vb[j]);
          d.push_back(va[i] - vb[j]);
        }
      }
      if (d.empty()) continue;
      const MetricStats sa = ComputeStats(pa), sb = ComputeStats(pb), sd = ComputeStats(d);
      ClaimCase cc;
      cc.label = sc.name + (na.empty() && nb.empty() && c.noises.size() > 1 ? "/" + a_noise : "");
      cc.mean_a = sa.mean;
      cc.mean_b = sb.mean;
      cc.diff = sd.mean;
      cc.lo = sd.ci95_lo;
      cc.hi = sd.ci95_hi;
      cc.n = sd.n;
      cc.holds = Compare(sa.mean, sb.mean, cl.op);
      cc.significant = cc.holds && sd.n > 1 &&
                       ((cl.op[0] == '<' && cc.hi < 0) || (cl.op[0] == '>' && cc.lo > 0));
      cases.push_back(cc);
    }
  }
  return cases;
}

void ClaimsSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t) {
  if (c.claims.empty()) return;
  md << "## Claims\n\n";
  for (const Claim& cl : c.claims) {
    const auto cases = EvaluateClaim(c, t, cl);
    const std::string stmt = cl.metric + ": " + cl.a + " " + cl.op + " " + cl.b;
    md << "- " << (cl.text.empty() ? "" : "**" + cl.text + "** ") << "(`" << stmt << "`): ";
    if (cases.empty()) {
      md << "no scenario has results for both sides.\n";
      continue;
    }
    long holds = 0, significant = 0;
    for (const auto& cc : cases) holds += cc.holds, significant += cc.significant;
    if (cases.size() == 1) {
      const ClaimCase& cc = cases[0];
      md << (cc.holds ? "holds" : "does not hold") << " (" << cl.a << " " << Sig(cc.mean_a)
         << " vs " << cl.b << " " << Sig(cc.mean_b) << "; paired difference " << Sig(cc.diff)
         << ", 95 % CI [" << Sig(cc.lo) << ", " << Sig(cc.hi) << "], n = " << cc.n << ")"
         << (cc.significant                   ? ", and the difference is significant"
             : (cc.lo <= 0.0 && cc.hi >= 0.0) ? ", but the difference is within the noise"
                                              : "")
         << ".\n";
      continue;
    }
    md << "holds in " << holds << " of " << cases.size() << " cases (" << significant
       << " with a paired 95 % interval that excludes zero).";
    // The cases where it fails, the first few with their numbers.
    std::string fails;
    long failed = 0;
    for (const auto& cc : cases) {
      if (cc.holds) continue;
      if (++failed > 4) continue;
      fails += (fails.empty() ? "" : "; ") + cc.label + " (" + Sig(cc.mean_a, 6) + " vs " +
               Sig(cc.mean_b, 6) + ", paired difference " + Sig(cc.diff, 3) + " [" + Sig(cc.lo, 3) +
               ", " + Sig(cc.hi, 3) + "])";
    }
    if (failed > 4) fails += "; and " + std::to_string(failed - 4) + " more (see summary.csv)";
    long within = 0;
    for (const auto& cc : cases) within += !cc.holds && cc.lo <= 0.0 && cc.hi >= 0.0;
    if (!fails.empty()) md << " It does not hold in: " << fails << ".";
    if (within > 0)
      md << " In " << within << " of the " << failed
         << " cases where it does not hold, the paired difference is within the noise.";
    md << "\n";
  }
  md << "\n";
}

void OverviewSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t) {
  if ((c.scenarios.size() < 2 && c.overview.empty()) ||
      (c.overview.size() == 1 && c.overview[0] == "none"))
    return;
  // One column per filter x noise; one row per scenario and overview metric
  // (default: the RMSE of the scenario's first state).
  std::vector<std::pair<int, int>> columns;
  for (const auto& sc : c.scenarios)
    for (const Combo& cb : sc.combos)
      if (std::find(columns.begin(), columns.end(), std::make_pair(cb.filter, cb.noise)) ==
          columns.end())
        columns.emplace_back(cb.filter, cb.noise);
  md << "## Overview: " << (c.overview.empty() ? "mean RMSE of the first state" : "mean over runs")
     << "\n\n"
     << "| scenario | metric |";
  for (const auto& [f, n] : columns)
    md << " " << c.filters[f].name << "/" << c.noises[n].name << " |";
  md << "\n|---|---|";
  for (size_t i = 0; i < columns.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& sc : c.scenarios) {
    std::vector<std::string> metrics;
    if (c.overview.empty()) {
      metrics.push_back("rmse_" + sc.model->states[0]);
    } else {
      for (const auto& m : c.overview) {
        const auto us = m.find('_');
        const std::string state = us == std::string::npos ? "" : m.substr(us + 1);
        const bool per_state =
            m.rfind("rmse_", 0) == 0 || m.rfind("mse_", 0) == 0 || m.rfind("mae_", 0) == 0;
        if (!per_state || std::find(sc.model->states.begin(), sc.model->states.end(), state) !=
                              sc.model->states.end())
          metrics.push_back(m);
      }
    }
    for (const auto& metric : metrics) {
      md << "| " << sc.name << " | " << metric << " |";
      for (const auto& [f, n] : columns) {
        const GroupValues* g = FindGroup(t, GroupKey(sc.name, c.filters[f].name, c.noises[n].name));
        // us_per_step: wall-clock cost per filter step (timing.csv).
        const MetricStats s =
            ComputeStats(metric == "us_per_step" ? (g ? g->us_per_step : std::vector<double>{})
                                                 : Values(g, metric));
        md << " " << (s.n ? Sig(s.mean) : "–") << " |";
      }
      md << "\n";
    }
  }
  md << "\n";
}

}  // namespace

std::string StudyReportMarkdown(const StudyConfig& c, const StudyTables& t,
                                const StudyState& state) {
  std::ostringstream md;
  md << "# Study `" << c.study.name << "`" << (c.title.empty() ? "" : ": " + c.title) << "\n\n";
  if (!c.study.description.empty()) md << c.study.description << "\n\n";
  if (!c.paper.empty()) {
    // The five built-in papers (000 ... 004) are cited in docs/paperNNN.md.
    const bool built_in =
        c.paper.size() == 3 && c.paper.find_first_not_of("0123456789") == std::string::npos;
    md << "Reproduces paper " << c.paper
       << (built_in ? " (cited in estlab's docs/paper" + c.paper + ".md)" : std::string())
       << ".\n\n";
  }
  long recorded = 0;
  for (const auto& sc : c.scenarios) recorded += sc.recorded;
  if (recorded == long(c.scenarios.size()))
    md << "Recorded data: one run per recorded file, nothing simulated, ";
  else
    md << state.runs << " Monte Carlo runs per scenario (study seed " << c.study.seed
       << "; run i of scenario s uses seed DeriveSeed({seed, s, i})"
       << (recorded ? "; a scenario on recorded data has one run per file" : "") << "), ";
  md << c.scenarios.size() << " scenario(s), " << c.filters.size() << " filter(s), "
     << c.noises.size() << " noise setting(s). Status: " << state.status << "; wall time "
     << Sig(state.wall_s, 3) << " s with " << state.jobs << " worker thread(s).\n\n";
  md << "Filters:\n\n";
  for (const auto& f : c.filters) md << "- `" << f.name << "`: " << f.description << "\n";
  md << "\nNoise settings (Q = process noise, R = measurement noise; oracle = the truth's):\n\n";
  for (const auto& n : c.noises) md << "- `" << n.name << "`: " << n.description << "\n";
  md << "\n";
  // The headline numbers first (the paper's beside ours, hand/auto/oracle,
  // the claims), the per-scenario detail after them.
  OverviewSection(md, c, t);
  ReferenceSection(md, c, t);
  HandAutoOracleSection(md, c, t);
  study_report::NoiseIdentificationSection(md, c, t);
  study_report::RecordedDataSection(md, c, t);
  ClaimsSection(md, c, t);
  if (!c.notes.empty()) {
    md << "## Notes\n\n";
    for (const auto& n : c.notes) md << n << "\n\n";
  }
  for (const auto& sc : c.scenarios) ScenarioSection(md, c, t, sc);
  md << "## Files\n\n"
     << "runs.csv (one row per scenario, run, filter and noise setting), summary.csv (mean, sd, "
        "variance, 95 % CI of the mean, 2.5/50/97.5 percentiles per group and metric), "
        "time_metrics.csv (RMSE, NEES and NIS over time across runs), timing.csv, timeseries/ "
        "(kept runs), manifest.json. `estlab figures DIR` draws the figures.\n";
  return md.str();
}

}  // namespace estlab
