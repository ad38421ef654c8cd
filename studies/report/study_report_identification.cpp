// report.md's noise-identification comparison and identification.csv
// (study_report_parts.h, study_report.h).
//
// A case is a scenario with a truth and one filter kind (ekf, ukf, kf, ...):
// its entries are every noise setting run with a filter of that kind, an
// adaptive filter counting as "RULE from NOISE". The reference of a case is
// its non-adaptive filter with the truth's noise (the oracle):
//
//   score(x) = (1/n) sum_i mean RMSE_i(x) / mean RMSE_i(oracle)
//
// with the 95 % CI of the per-run paired differences x - oracle. Within a
// case an entry ties with the best when the paired CI of its difference to
// the best contains 0.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

#include "src/core/types.h"
#include "src/io/output_file.h"
#include "src/run/filter_kinds.h"
#include "studies/report/study_report_parts.h"

namespace estlab {

namespace study_report {

namespace {

struct Entry {
  std::string label;  // the noise name, or "RULE from NOISE" for an adaptive filter
  FilterNoise fn;
  const NoiseConfig* noise = nullptr;
  bool per_run = false;
  long runs = 0, tune_failed = 0;
  double score = NAN;
  MetricStats vs_oracle;  // paired score differences entry - oracle
  MetricStats nees, nees_in95, q_err, r_err, iterations, converged, at_bound;
  double cost_s = NAN;  // mean wall time per run: identification + filter
  const GroupValues* group = nullptr;
};

struct Case {
  const ScenarioConfig* sc = nullptr;
  std::string kind;
  FilterNoise oracle;
  std::vector<Entry> entries;  // sorted by score
};

double Mean(const std::vector<double>& v) { return ComputeStats(v).mean; }

// The start of a tuned setting as a multiple of the oracle (1 without
// init-scale; the config check refuses init-scale with init-* keys).
double InitScale(const NoiseConfig& n) {
  return n.init_scale.empty() ? 1.0 : std::strtod(n.init_scale.c_str(), nullptr);
}

Entry MakeEntry(const StudyConfig& c, const StudyTables& t, const ScenarioConfig& sc,
                const Combo& cb, const FilterNoise& oracle) {
  Entry e;
  e.fn = {c.filters[cb.filter].name, c.noises[cb.noise].name};
  e.noise = &c.noises[cb.noise];
  e.label = cb.spec.adapt.rule.empty() ? e.fn.noise : cb.spec.adapt.rule + " from " + e.fn.noise;
  e.per_run = cb.tune_per_run;
  const GroupValues* g = FindGroup(t, GroupKey(sc.name, e.fn.filter, e.fn.noise));
  e.group = g;
  if (g == nullptr) return e;
  e.runs = g->runs;
  e.tune_failed = g->tune_failed;
  e.score = ScoreAgainst(t, sc, e.fn, oracle);
  e.vs_oracle = PairedScoreDifference(t, sc, e.fn, oracle, oracle);
  e.nees = ComputeStats(Values(g, "mean_nees"));
  e.nees_in95 = ComputeStats(Values(g, "nees_in95"));
  if (e.per_run) {
    e.q_err = ComputeStats(Values(g, "id_q_err"));
    e.r_err = ComputeStats(Values(g, "id_r_err"));
    e.iterations = ComputeStats(Values(g, "id_iterations"));
    e.converged = ComputeStats(Values(g, "id_converged"));
    e.at_bound = ComputeStats(Values(g, "id_at_bound"));
  }
  e.cost_s = Mean(g->filter_wall_s) + (e.per_run ? Mean(g->identify_wall_s) : 0.0);
  return e;
}

// One case per scenario with a truth and non-adaptive filter that runs the
// oracle; an adaptive filter joins the case of the first such filter of its
// kind (its rule starts from the same model and noise).
std::vector<Case> Cases(const StudyConfig& c, const StudyTables& t) {
  std::vector<Case> cases;
  for (const ScenarioConfig& sc : c.scenarios) {
    if (!sc.has_truth) continue;
    const size_t first = cases.size();
    for (const Combo& cb : sc.combos)
      if (cb.spec.adapt.rule.empty() && c.noises[cb.noise].role == NoiseRole::kOracle) {
        bool known = false;
        for (size_t i = first; i < cases.size(); ++i)
          known = known || cases[i].oracle.filter == c.filters[cb.filter].name;
        if (known) continue;
        Case k;
        k.sc = &sc;
        k.kind = FilterKindName(cb.spec.kind());
        k.oracle = {c.filters[cb.filter].name, c.noises[cb.noise].name};
        cases.push_back(std::move(k));
      }
    for (const Combo& cb : sc.combos) {
      const std::string& filter = c.filters[cb.filter].name;
      const std::string kind = FilterKindName(cb.spec.kind());
      for (size_t i = first; i < cases.size(); ++i) {
        Case& k = cases[i];
        const bool own = k.oracle.filter == filter;
        if (own || (!cb.spec.adapt.rule.empty() && k.kind == kind)) {
          k.entries.push_back(MakeEntry(c, t, sc, cb, k.oracle));
          break;
        }
      }
    }
    for (size_t i = first; i < cases.size(); ++i)
      std::stable_sort(cases[i].entries.begin(), cases[i].entries.end(),
                       [](const Entry& a, const Entry& b) {
                         return std::isfinite(a.score) && !(a.score >= b.score);
                       });
  }
  return cases;
}

std::string Percent(long part, long whole) {
  return whole > 0 ? Sig(100.0 * double(part) / double(whole), 3) + " %" : "–";
}

// "0.31 [0.05, 1.2]": median and the 2.5 / 97.5 percentiles over the runs.
std::string Spread(const MetricStats& s) {
  if (s.n == 0) return "–";
  return Sig(s.median, 3) + " [" + Sig(s.p2_5, 2) + ", " + Sig(s.p97_5, 2) + "]";
}

std::string ScoreCell(const Entry& e) {
  if (!std::isfinite(e.score)) return "–";
  const MetricStats& d = e.vs_oracle;
  return Sig(e.score, 4) +
         (d.n > 1 ? " [" + Sig(1.0 + d.ci95_lo, 4) + ", " + Sig(1.0 + d.ci95_hi, 4) + "]" : "");
}

// A result worth a sentence: b's score is lower than a's by at least this
// (1 % of the oracle's RMSE) and the difference is significant.
constexpr double kMaterialDifference = 0.01;

// True when b is better (lower score) than a, significantly (the 95 % CI of
// the paired difference below 0) and materially (by kMaterialDifference).
bool SignificantlyBetter(const StudyTables& t, const Case& k, const Entry& b, const Entry& a) {
  if (!std::isfinite(a.score) || !std::isfinite(b.score)) return false;
  const MetricStats d = PairedScoreDifference(t, *k.sc, b.fn, a.fn, k.oracle);
  return d.n > 1 && d.ci95_hi < 0.0 && d.mean <= -kMaterialDifference;
}

// True when the 95 % CI of the paired difference b - a contains 0 (over at
// least two shared runs).
bool TiedWith(const StudyTables& t, const Case& k, const Entry& b, const Entry& a) {
  if (!std::isfinite(a.score) || !std::isfinite(b.score)) return false;
  const MetricStats d = PairedScoreDifference(t, *k.sc, b.fn, a.fn, k.oracle);
  return d.n > 1 && d.ci95_lo <= 0.0 && d.ci95_hi >= 0.0;
}

// The paired interval of b - a, in score units: " (difference -0.02 [-0.03, -0.01])".
std::string DiffText(const StudyTables& t, const Case& k, const Entry& b, const Entry& a) {
  const MetricStats d = PairedScoreDifference(t, *k.sc, b.fn, a.fn, k.oracle);
  return " (paired difference " + Sig(d.mean, 3) + " [" + Sig(d.ci95_lo, 3) + ", " +
         Sig(d.ci95_hi, 3) + "], " + std::to_string(d.n) + " runs)";
}

// Per diagonal element of Q and R, identified / true variance over the runs
// of the per-run settings: bias shows as a median away from 1.
void ElementTable(std::ostringstream& md, const Case& k) {
  std::vector<const Entry*> rows;
  for (const Entry& e : k.entries)
    if (e.per_run && e.group != nullptr) rows.push_back(&e);
  if (rows.empty()) return;
  std::vector<std::string> columns;
  for (const auto& st : k.sc->model->states) columns.push_back("id_q_" + st);
  for (const auto& o : k.sc->model->FindMeasurement(k.sc->truth.measurement).outputs)
    columns.push_back("id_r_" + o);
  md << "Identified / true variance per element, median [2.5 %, 97.5 %] over the runs:\n\n"
     << "| setting | filter |";
  for (const auto& col : columns)
    md << " " << (col[3] == 'q' ? "Q " : "R ") << col.substr(5) << " |";
  md << "\n|---|---|";
  for (size_t i = 0; i < columns.size(); ++i) md << "---|";
  md << "\n";
  for (const Entry* e : rows) {
    md << "| `" << e->label << "` | " << e->fn.filter << " |";
    for (const auto& col : columns)
      md << " " << Spread(ComputeStats(Values(e->group, col))) << " |";
    md << "\n";
  }
  md << "\n";
}

void CaseTable(std::ostringstream& md, const Case& k) {
  md << "### `" << k.sc->name << "`, " << k.oracle.filter << " (" << k.kind << "; reference `"
     << k.oracle.filter << "/" << k.oracle.noise << "`)\n\n"
     << "| rank | setting | filter | score [95 % CI] | ANEES | NEES in 95 % | Q error | R error "
        "| failed | at bound | not converged | iterations | cost per run |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  int rank = 0;
  for (const Entry& e : k.entries) {
    md << "| " << ++rank << " | `" << e.label << "` | " << e.fn.filter << " | " << ScoreCell(e)
       << " | " << (e.nees.n ? Sig(e.nees.mean, 3) : "–") << " | "
       << (e.nees_in95.n ? Sig(100.0 * e.nees_in95.mean, 3) + " %" : "–") << " | "
       << Spread(e.q_err) << " | " << Spread(e.r_err) << " | "
       << (e.per_run ? Percent(e.tune_failed, e.runs) : "–") << " | "
       << (e.at_bound.n ? Sig(100.0 * e.at_bound.mean, 3) + " %" : "–") << " | "
       << (e.converged.n ? Sig(100.0 * (1.0 - e.converged.mean), 3) + " %" : "–") << " | "
       << (e.iterations.n ? Sig(e.iterations.mean, 3) : "–") << " | "
       << (std::isfinite(e.cost_s) ? Sig(1e3 * e.cost_s, 3) + " ms" : "–") << " |\n";
  }
  md << "\n";
  ElementTable(md, k);
}

// One sentence per result that goes against what is commonly assumed.
std::vector<std::string> Reversals(const StudyTables& t, const std::vector<Case>& cases) {
  std::vector<std::string> out;
  for (const Case& k : cases) {
    const std::string where = "`" + k.sc->name + "` (" + k.oracle.filter + ")";
    const Entry* oracle = nullptr;
    for (const Entry& e : k.entries)
      if (e.fn.filter == k.oracle.filter && e.fn.noise == k.oracle.noise) oracle = &e;
    for (const Entry& e : k.entries) {
      if (oracle == nullptr || &e == oracle || !SignificantlyBetter(t, k, e, *oracle)) continue;
      out.push_back(where + ": `" + e.label + "` beats the truth's own noise, score " +
                    Sig(e.score, 4) + DiffText(t, k, e, *oracle) +
                    ". The truth's Q/R are optimal only for the exact filter of a "
                    "linear-Gaussian system; this filter approximates (linearisation, sigma "
                    "points, discretisation), and " +
                    (e.per_run ? std::string("Q/R fitted to the run itself also follow its "
                                             "realised noise (in-sample).")
                               : std::string("other Q/R absorb the approximation error better.")));
    }
    // Likelihood maximisation is expected to be at least as good as the
    // approximate estimators from the same start.
    for (const Entry& ml : k.entries) {
      if (!ml.per_run || ml.noise->estimator != "ml") continue;
      for (const Entry& e : k.entries)
        if (e.per_run && e.noise->estimator != "ml" && e.fn.filter == ml.fn.filter &&
            InitScale(*e.noise) == InitScale(*ml.noise) && SignificantlyBetter(t, k, e, ml))
          out.push_back(where + ": " + e.noise->estimator + " (`" + e.label +
                        "`) filters better than maximum likelihood (`" + ml.label + "`), " +
                        Sig(e.score, 4) + " against " + Sig(ml.score, 4) + DiffText(t, k, e, ml) +
                        ": the likelihood optimum is not the RMSE optimum of a filter whose "
                        "model is wrong.");
    }
    // Auto-tuning is expected to beat hand-tuning.
    for (const Entry& h : k.entries) {
      if (h.noise->role != NoiseRole::kHand || h.label != h.fn.noise) continue;
      int identified = 0, beaten = 0;
      for (const Entry& e : k.entries) {
        if (!e.per_run || e.fn.filter != h.fn.filter) continue;
        ++identified;
        beaten += SignificantlyBetter(t, k, h, e);
      }
      if (identified > 0 && beaten == identified)
        out.push_back(where + ": the hand setting `" + h.label + "` (score " + Sig(h.score, 4) +
                      ") beats every Q/R the " + h.fn.filter +
                      " identified from the run's own data.");
    }
  }
  return out;
}

// The ranking over all cases: per setting label, how often it ties with the
// case's best (paired CI of the difference contains 0), its median score
// and identification errors.
void SummaryRanking(std::ostringstream& md, const StudyTables& t, const std::vector<Case>& cases) {
  struct Acc {
    int cases = 0, best = 0;
    std::vector<double> scores, q_med, r_med, cost;
    long runs = 0, failed = 0;
  };
  std::map<std::string, Acc> acc;
  std::vector<std::string> order;
  for (const Case& k : cases) {
    if (k.entries.empty() || !std::isfinite(k.entries.front().score)) continue;
    const Entry& best = k.entries.front();
    for (const Entry& e : k.entries) {
      if (!acc.count(e.label)) order.push_back(e.label);
      Acc& a = acc[e.label];
      ++a.cases;
      a.scores.push_back(e.score);
      if (&e == &best || TiedWith(t, k, best, e)) ++a.best;
      if (e.q_err.n) a.q_med.push_back(e.q_err.median);
      if (e.r_err.n) a.r_med.push_back(e.r_err.median);
      a.cost.push_back(e.cost_s);
      if (e.per_run) a.runs += e.runs, a.failed += e.tune_failed;
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](const std::string& a, const std::string& b) {
    const Acc &x = acc[a], &y = acc[b];
    const double fx = double(x.best) / x.cases, fy = double(y.best) / y.cases;
    if (fx != fy) return fx > fy;
    return ComputeStats(x.scores).median < ComputeStats(y.scores).median;
  });
  md << "### Ranking over the scenarios\n\n"
     << "Per setting: in how many cases (scenario × filter kind) it is the best or statistically "
        "tied with the best (the 95 % CI of the paired per-run difference to the best contains "
        "0), its median and worst score, the median over cases of its median Q and R errors, "
        "its failure rate and its median cost per run.\n\n"
     << "| setting | best or tied | cases | median score | worst score | Q error | R error | "
        "failed | cost per run |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& label : order) {
    const Acc& a = acc[label];
    const MetricStats s = ComputeStats(a.scores);
    md << "| `" << label << "` | " << a.best << " | " << a.cases << " | " << Sig(s.median, 4)
       << " | " << Sig(s.max, 4) << " | "
       << (a.q_med.empty() ? "–" : Sig(ComputeStats(a.q_med).median, 3)) << " | "
       << (a.r_med.empty() ? "–" : Sig(ComputeStats(a.r_med).median, 3)) << " | "
       << (a.runs ? Percent(a.failed, a.runs) : "–") << " | "
       << Sig(1e3 * ComputeStats(a.cost).median, 3) << " ms |\n";
  }
  md << "\n";
}

// The per-run settings whose tuner failed, stopped at a bound or did not
// converge in more than 1 % of the runs.
void Robustness(std::ostringstream& md, const std::vector<Case>& cases) {
  std::vector<std::string> lines;
  for (const Case& k : cases)
    for (const Entry& e : k.entries) {
      if (!e.per_run || e.runs == 0) continue;
      const double failed = double(e.tune_failed) / double(e.runs);
      const double bound = e.at_bound.n ? e.at_bound.mean : 0.0;
      const double unconverged = e.converged.n ? 1.0 - e.converged.mean : 0.0;
      if (failed <= 0.01 && bound <= 0.01 && unconverged <= 0.01) continue;
      lines.push_back("`" + k.sc->name + "` / " + e.fn.filter + " / `" + e.label + "`: failed in " +
                      Percent(e.tune_failed, e.runs) + " of " + std::to_string(e.runs) +
                      " runs, at a bound in " + Sig(100.0 * bound, 3) + " %, not converged in " +
                      Sig(100.0 * unconverged, 3) + " % of those that ran.");
    }
  md << "### Robustness\n\n";
  if (lines.empty())
    md << "Every per-run identification converged inside its bounds in at least 99 % of the "
          "runs.\n";
  for (const auto& l : lines) md << "- " << l << "\n";
  md << "\n";
}

}  // namespace

void NoiseIdentificationSection(std::ostringstream& md, const StudyConfig& c,
                                const StudyTables& t) {
  if (!c.identification) return;
  const std::vector<Case> cases = Cases(c, t);
  if (cases.empty()) return;
  md << "## Noise identification\n\n"
     << "Every Q/R estimator of the study against the truth's noise. Settings with "
        "`tune-per-run` fit Q/R in every run on that run's own measurements (in-sample, as a "
        "user tunes one recording) and filter them with the result. **Score** = mean over the "
        "states of the mean RMSE divided by the same filter kind's with the truth's noise "
        "(1 = the oracle; [95 % CI] from the per-run paired differences). Q error and R error: "
        "the relative Frobenius error ‖Q̂ − Q‖/‖Q‖ of the identified per-step covariance, "
        "median [2.5 %, 97.5 %] over the runs. Failed: runs whose tuning gave no Q/R (status "
        "tune_failed); at bound: runs with an estimate at its search bound; not converged: the "
        "tuner stopped at its iteration limit. Cost: mean wall time per run of identification "
        "and filter (this machine).\n\n";
  SummaryRanking(md, t, cases);
  const std::vector<std::string> reversals = Reversals(t, cases);
  md << "### Results against common wisdom\n\n"
     << "Differences that are significant (the 95 % CI of the paired difference excludes 0) "
        "and at least 0.01 in score (1 % of the oracle's RMSE).\n\n";
  if (reversals.empty()) md << "None: no result here reverses the usual expectations.\n";
  for (const auto& r : reversals) md << "- " << r << "\n";
  md << "\n";
  Robustness(md, cases);
  for (const Case& k : cases) CaseTable(md, k);
}

}  // namespace study_report

std::string IdentificationCsv(const StudyConfig& config, const StudyTables& tables) {
  using namespace study_report;
  if (!config.identification) return "";
  std::string csv = FormatCsvRow(
      {"scenario",    "case",         "kind",       "setting",       "filter",       "noise",
       "per_run",     "runs",         "score",      "score_lo",      "score_hi",     "mean_nees",
       "nees_in95",   "q_err_median", "q_err_p2_5", "q_err_p97_5",   "r_err_median", "r_err_p2_5",
       "r_err_p97_5", "failed",       "at_bound",   "not_converged", "iterations",   "cost_s"});
  auto num = [](double v) { return std::isfinite(v) ? FormatDouble(v) : std::string(); };
  // A statistic of the runs, "" when there are none (settings not tuned per run).
  auto stat = [&](const MetricStats& s, double MetricStats::*field) {
    return s.n ? num(s.*field) : std::string();
  };
  auto rate = [&](const MetricStats& s, bool flip) {
    return s.n ? num(flip ? 1.0 - s.mean : s.mean) : std::string();
  };
  for (const Case& k : Cases(config, tables))
    for (const Entry& e : k.entries) {
      const bool ci = e.vs_oracle.n > 1;
      csv += FormatCsvRow({k.sc->name,
                           k.oracle.filter,
                           k.kind,
                           e.label,
                           e.fn.filter,
                           e.fn.noise,
                           e.per_run ? "1" : "0",
                           std::to_string(e.runs),
                           num(e.score),
                           ci ? num(1.0 + e.vs_oracle.ci95_lo) : "",
                           ci ? num(1.0 + e.vs_oracle.ci95_hi) : "",
                           stat(e.nees, &MetricStats::mean),
                           stat(e.nees_in95, &MetricStats::mean),
                           stat(e.q_err, &MetricStats::median),
                           stat(e.q_err, &MetricStats::p2_5),
                           stat(e.q_err, &MetricStats::p97_5),
                           stat(e.r_err, &MetricStats::median),
                           stat(e.r_err, &MetricStats::p2_5),
                           stat(e.r_err, &MetricStats::p97_5),
                           e.per_run && e.runs ? num(double(e.tune_failed) / double(e.runs)) : "",
                           rate(e.at_bound, false),
                           rate(e.converged, true),
                           stat(e.iterations, &MetricStats::mean),
                           num(e.cost_s)});
    }
  return csv;
}

}  // namespace estlab
