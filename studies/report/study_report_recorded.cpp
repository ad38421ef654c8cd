// report.md on recorded data (study_report_parts.h): without a truth the
// errors and NEES are unknown and there is no oracle, so the section says so
// and compares the noise settings on what the measurements alone tell: the
// innovation likelihood, the NIS and the one-step-ahead prediction error.
#include <algorithm>
#include <map>

#include "src/core/types.h"
#include "studies/report/study_report_parts.h"

namespace estlab::study_report {

namespace {

// "0.1734 [0.1646, 0.1822]" (mean and the 95 % CI of the mean).
std::string CiCell(const MetricStats& s, int digits = 4) {
  if (s.n == 0) return "–";
  return Sig(s.mean, digits) + " [" + Sig(s.ci95_lo, 3) + ", " + Sig(s.ci95_hi, 3) + "]";
}

// Per-run differences a - b of a metric over the runs both finished.
MetricStats Paired(const GroupValues* a, const GroupValues* b, const std::string& metric) {
  if (!a || !b) return ComputeStats({});
  const std::vector<double> va = Values(a, metric), vb = Values(b, metric);
  std::map<long, double> by_run;
  for (size_t i = 0; i < vb.size(); ++i) by_run[b->run_index[i]] = vb[i];
  std::vector<double> d;
  for (size_t i = 0; i < va.size(); ++i) {
    const auto it = by_run.find(a->run_index[i]);
    if (it != by_run.end() && std::isfinite(va[i]) && std::isfinite(it->second))
      d.push_back(va[i] - it->second);
  }
  return ComputeStats(d);
}

void AvailabilityText(std::ostringstream& md, const ScenarioConfig& sc,
                      const std::vector<std::string>& outputs) {
  md << "Scenario `" << sc.name << "`: " << sc.data_runs.size() << " recorded run(s) ("
     << sc.data_runs.front().path << (sc.data_runs.size() > 1 ? ", ..." : "") << ")";
  if (!sc.tune_runs.empty())
    md << ", tuned Q/R fitted on " << sc.tune_runs.size() << " other recorded run(s) ("
       << sc.tune_runs.front().path << (sc.tune_runs.size() > 1 ? ", ..." : "") << ")";
  md << ".\n\n";
  if (sc.has_truth) {
    md << "- Truth: the files' state columns (`truth = columns`); RMSE, MAE and NEES are in the "
          "scenario's section.\n";
  } else {
    md << "- **No truth**: the recordings' state-like columns are not taken as truth (`truth = "
          "none`), so RMSE, MAE and NEES are **not available**.\n";
  }
  md << "- **No oracle**: the noise of real data is unknown; the comparison is hand vs tuned "
        "Q/R only.\n"
     << "- Metrics available without truth: the innovation log-likelihood (NLL per step, lower "
        "is better), the mean NIS with its 95 % χ² bounds, and the one-step-ahead prediction "
        "RMSE of each measured output (";
  for (size_t j = 0; j < outputs.size(); ++j) md << (j ? ", " : "") << "`" << outputs[j] << "`";
  md << "): the recorded measurement against the filter's prediction h(x_k|k-1), the innovation, "
        "angles wrapped.\n";
  if (sc.burn_in > 0)
    md << "- The first " << sc.burn_in
       << " rows of each run (the prior's transient) are left out of the NIS, the NLL per step "
          "and the prediction RMSE (`burn-in`); `loglik` in runs.csv is the whole run's.\n";
  md << "\n";
}

void MetricsTable(std::ostringstream& md, const StudyConfig& c, const StudyTables& t,
                  const ScenarioConfig& sc, const std::vector<std::string>& outputs) {
  md << "| filter | noise | role | ok/runs | NLL per step [95 % CI] | mean NIS | NIS 95 % bounds "
        "| runs inside |";
  for (const auto& o : outputs) md << " prediction RMSE " << o << " |";
  md << "\n|---|---|---|---|---|---|---|---|";
  for (size_t j = 0; j < outputs.size(); ++j) md << "---|";
  md << "\n";
  for (const Combo& cb : sc.combos) {
    const std::string& f = c.filters[cb.filter].name;
    const NoiseConfig& nc = c.noises[cb.noise];
    const GroupValues* g = FindGroup(t, GroupKey(sc.name, f, nc.name));
    const MetricStats inside = ComputeStats(Values(g, "nis_in95"));
    md << "| " << f << " | " << nc.name << " | " << NoiseRoleName(nc.role) << " | "
       << (g ? g->ok : 0) << "/" << (g ? g->runs : 0) << " | "
       << CiCell(ComputeStats(Values(g, "nll_per_step")), 6) << " | "
       << Sig(ComputeStats(Values(g, "mean_nis")).mean) << " | ["
       << Sig(ComputeStats(Values(g, "nis_lo95")).mean) << ", "
       << Sig(ComputeStats(Values(g, "nis_hi95")).mean) << "] | "
       << (inside.n ? Sig(100 * inside.mean, 3) + " %" : "–") << " |";
    for (const auto& o : outputs)
      md << " " << CiCell(ComputeStats(Values(g, "pred_rmse_" + o))) << " |";
    md << "\n";
  }
  md << "\n";
}

// Per filter: the best hand setting by NLL per step against each tuned one.
void HandVsTuned(std::ostringstream& md, const StudyConfig& c, const StudyTables& t,
                 const ScenarioConfig& sc, const std::vector<std::string>& outputs) {
  std::ostringstream rows;
  long cases = 0, better = 0;
  for (size_t fi = 0; fi < c.filters.size(); ++fi) {
    const std::string& f = c.filters[fi].name;
    std::string best_hand;
    double best = NAN;
    std::vector<std::string> tuned;
    for (const Combo& cb : sc.combos) {
      if (cb.filter != int(fi)) continue;
      const NoiseConfig& nc = c.noises[cb.noise];
      if (nc.role == NoiseRole::kTuned) tuned.push_back(nc.name);
      if (nc.role != NoiseRole::kHand) continue;
      const double v =
          ComputeStats(Values(FindGroup(t, GroupKey(sc.name, f, nc.name)), "nll_per_step")).mean;
      if (std::isfinite(v) && !(v >= best)) best = v, best_hand = nc.name;
    }
    if (best_hand.empty()) continue;
    const GroupValues* h = FindGroup(t, GroupKey(sc.name, f, best_hand));
    for (const std::string& tn : tuned) {
      const GroupValues* a = FindGroup(t, GroupKey(sc.name, f, tn));
      const MetricStats d = Paired(a, h, "nll_per_step");
      const bool wins = d.n > 0 && d.mean < 0;
      ++cases;
      better += wins;
      rows << "| " << f << " | `" << best_hand << "` | `" << tn << "` | " << CiCell(d, 4) << " |";
      for (const auto& o : outputs) {
        const std::string metric = "pred_rmse_" + o;
        rows << " " << Sig(ComputeStats(Values(h, metric)).mean) << " → "
             << Sig(ComputeStats(Values(a, metric)).mean) << ", Δ "
             << CiCell(Paired(a, h, metric), 3) << " |";
      }
      rows << " " << (d.n == 0 ? "–" : wins ? "tuned" : "hand") << " |\n";
    }
  }
  if (cases == 0) return;
  md << "Hand vs tuned on the same recordings (paired per run; Δ NLL per step = tuned − best "
        "hand, negative: the tuned Q/R explain the measurements better):\n\n"
     << "| filter | best hand (by NLL) | tuned | Δ NLL per step [95 % CI] |";
  for (const auto& o : outputs)
    md << " prediction RMSE " << o << ": hand → tuned, Δ = tuned − hand [95 % CI] |";
  md << " lower NLL |\n|---|---|---|---|";
  for (size_t j = 0; j < outputs.size(); ++j) md << "---|";
  md << "---|\n"
     << rows.str() << "\nThe tuned Q/R have the lower NLL per step in " << better << " of " << cases
     << " filter case(s).\n\n";
}

}  // namespace

void RecordedDataSection(std::ostringstream& md, const StudyConfig& c, const StudyTables& t) {
  bool any = false;
  for (const auto& sc : c.scenarios) any |= sc.recorded;
  if (!any) return;
  md << "## Recorded data: metrics without truth\n\n";
  for (const ScenarioConfig& sc : c.scenarios) {
    if (!sc.recorded) continue;
    const auto& outputs = sc.model->FindMeasurement(sc.truth.measurement).outputs;
    AvailabilityText(md, sc, outputs);
    MetricsTable(md, c, t, sc, outputs);
    HandVsTuned(md, c, t, sc, outputs);
  }
}

}  // namespace estlab::study_report
