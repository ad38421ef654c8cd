#include "studies/study_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <set>
#include <sstream>

#include "src/core/types.h"

namespace estlab {

namespace {

std::string Sig(double v, int digits = 4) {
  if (std::isnan(v)) return "–";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string GroupKey(const std::string& s, const std::string& f, const std::string& n) {
  return s + "/" + f + "/" + n;
}

const GroupValues* FindGroup(const StudyTables& t, const std::string& key) {
  const auto it = t.groups.find(key);
  return it == t.groups.end() ? nullptr : &it->second;
}

std::vector<double> Values(const GroupValues* g, const std::string& metric) {
  if (!g) return {};
  const auto it = g->values.find(metric);
  return it == g->values.end() ? std::vector<double>{} : it->second;
}

// "0.1734 ± 0.045 [0.1646, 0.1822]"
std::string MeanCell(const MetricStats& s) {
  if (s.n == 0) return "–";
  return Sig(s.mean) + " ± " + Sig(s.std, 2) + " [" + Sig(s.ci95_lo) + ", " + Sig(s.ci95_hi) + "]";
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

int MeasurementsPerRun(const ScenarioConfig& sc) { return sc.steps + (sc.measure_at_t0 ? 1 : 0); }

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
  md << "\nTuned noise (maximum innovation likelihood on the scenario's own tuning "
        "trajectories, then fixed for every run); the truth has Q "
     << oracle_q << ", R " << DiagText(sc.oracle_r, m) << ":\n\n"
     << "| filter | noise | status | Q | R | NLL start → tuned | iterations |\n"
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
  md << "- truth: " << sc.truth_description << "; x0 = " << VectorText(sc.truth.x0)
     << (sc.sample_x0 ? " + a draw from N(0, P0) per run" : "") << "\n";
  md << "- measurement `" << meas.name << "` every dt = " << FormatNumber(sc.truth.dt) << " for "
     << sc.steps << " steps, noise variance " << VectorText(sc.truth.meas_noise_var) << "\n";
  md << "- filter prior x0 = " << VectorText(sc.prior_x0) << ", P0 = " << DiagText(sc.prior_p0, nx)
     << "\n\n";

  md << "RMSE per state over each run, then mean ± sd over runs [95 % CI of the mean]:\n\n";
  md << "| filter | noise | ok/runs |";
  for (const auto& s : sc.model->states) md << " RMSE " << s << " |";
  md << " µs/step |\n|---|---|---|";
  for (int i = 0; i < nx; ++i) md << "---|";
  md << "---|\n";
  for (const Combo& cb : sc.combos) {
    const std::string& f = c.filters[cb.filter].name;
    const std::string& n = c.noises[cb.noise].name;
    const GroupValues* g = FindGroup(t, GroupKey(sc.name, f, n));
    md << "| " << f << " | " << n << " | " << (g ? g->ok : 0) << "/" << (g ? g->runs : 0) << " |";
    for (const auto& s : sc.model->states)
      md << " " << MeanCell(ComputeStats(Values(g, "rmse_" + s))) << " |";
    const MetricStats us = ComputeStats(g ? g->us_per_step : std::vector<double>{});
    md << " " << Sig(us.mean, 3) << " |\n";
  }
  TunedTable(md, t, sc);
  double nees_b[2], nis_b[2];
  ChiSquareBounds95(MeasurementsPerRun(sc), nx, nees_b);
  ChiSquareBounds95(MeasurementsPerRun(sc), nz, nis_b);
  md << "\nConsistency: time-averaged NEES (dimension " << nx << ") and NIS (dimension " << nz
     << ") per run; a consistent filter has 95 % of its runs inside the χ² bounds "
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

void ReferenceSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t) {
  if (c.references.empty()) return;
  md << "## The paper's numbers beside estlab's\n\n"
     << "| scenario | filter | noise | metric | statistic | paper | estlab | source |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const ReferenceValue& r : c.references) {
    for (const ScenarioConfig& sc : c.scenarios) {
      if (!Matches(r.scenario, sc)) continue;
      for (const Combo& cb : sc.combos) {
        const std::string& f = c.filters[cb.filter].name;
        const std::string& n = c.noises[cb.noise].name;
        if ((r.filter != "*" && r.filter != f) || (r.noise != "*" && r.noise != n)) continue;
        const MetricStats s = ComputeStats(Values(FindGroup(t, GroupKey(sc.name, f, n)), r.metric));
        for (const auto& [stat, paper] : r.stats) {
          std::string ours;
          if (stat == "mean")
            ours = Sig(s.mean) + " [" + Sig(s.ci95_lo) + ", " + Sig(s.ci95_hi) + "]";
          if (stat == "var") ours = Sig(s.var);
          if (stat == "std") ours = Sig(s.std);
          if (stat == "median") ours = Sig(s.median);
          md << "| " << sc.name << " | " << f << " | " << n << " | " << r.metric << " | " << stat
             << " | " << Sig(paper) << " | " << ours << " (n = " << s.n << ") | " << r.source
             << " |\n";
        }
      }
    }
  }
  md << "\nestlab's mean is given with the 95 % confidence interval of the mean over runs.\n\n";
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
  if (c.scenarios.size() < 2) return;
  // One column per filter x noise, the first state's mean RMSE.
  std::vector<std::pair<int, int>> columns;
  for (const auto& sc : c.scenarios)
    for (const Combo& cb : sc.combos)
      if (std::find(columns.begin(), columns.end(), std::make_pair(cb.filter, cb.noise)) ==
          columns.end())
        columns.emplace_back(cb.filter, cb.noise);
  md << "## Overview: mean RMSE of the first state\n\n| scenario | state |";
  for (const auto& [f, n] : columns)
    md << " " << c.filters[f].name << "/" << c.noises[n].name << " |";
  md << "\n|---|---|";
  for (size_t i = 0; i < columns.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& sc : c.scenarios) {
    const std::string& st = sc.model->states[0];
    md << "| " << sc.name << " | " << st << " |";
    for (const auto& [f, n] : columns) {
      const MetricStats s = ComputeStats(Values(
          FindGroup(t, GroupKey(sc.name, c.filters[f].name, c.noises[n].name)), "rmse_" + st));
      md << " " << (s.n ? Sig(s.mean) : "–") << " |";
    }
    md << "\n";
  }
  md << "\n";
}

}  // namespace

std::string StudyReportMarkdown(const StudyConfig& c, const StudyTables& t,
                                const StudyState& state) {
  std::ostringstream md;
  md << "# Study `" << c.study.name << "`" << (c.title.empty() ? "" : ": " + c.title) << "\n\n";
  if (!c.study.description.empty()) md << c.study.description << "\n\n";
  if (!c.paper.empty())
    md << "Reproduces paper " << c.paper << " (see /work/shared/STUDIES.md).\n\n";
  md << state.runs << " Monte Carlo runs per scenario (study seed " << c.study.seed
     << "; run i of scenario s uses seed DeriveSeed({seed, s, i})), " << c.scenarios.size()
     << " scenario(s), " << c.filters.size() << " filter(s), " << c.noises.size()
     << " noise setting(s). Status: " << state.status << "; wall time " << Sig(state.wall_s, 3)
     << " s with " << state.jobs << " worker thread(s).\n\n";
  md << "Filters:\n\n";
  for (const auto& f : c.filters) md << "- `" << f.name << "`: " << f.description << "\n";
  md << "\nNoise settings (Q = process noise, R = measurement noise; oracle = the truth's):\n\n";
  for (const auto& n : c.noises) md << "- `" << n.name << "`: " << n.description << "\n";
  md << "\n";
  OverviewSection(md, c, t);
  for (const auto& sc : c.scenarios) ScenarioSection(md, c, t, sc);
  ReferenceSection(md, c, t);
  ClaimsSection(md, c, t);
  if (!c.notes.empty()) {
    md << "## Notes\n\n";
    for (const auto& n : c.notes) md << n << "\n\n";
  }
  md << "## Files\n\n"
     << "runs.csv (one row per scenario, run, filter and noise setting), summary.csv (mean, sd, "
        "variance, 95 % CI of the mean, 2.5/50/97.5 percentiles per group and metric), "
        "time_metrics.csv (RMSE, NEES and NIS over time across runs), timing.csv, timeseries/ "
        "(kept runs), manifest.json. `estlab figures DIR` draws the figures.\n";
  return md.str();
}

}  // namespace estlab
