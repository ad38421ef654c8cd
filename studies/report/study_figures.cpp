#include "studies/report/study_figures.h"

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "src/core/types.h"
#include "src/io/csv_reader.h"
#include "src/io/output_file.h"
#include "src/registry/registry.h"
#include "studies/config/study_config.h"
#include "studies/report/gnuplot_figure.h"
#include "studies/report/study_figures_identification.h"
#include "studies/results/study_results.h"

namespace fs = std::filesystem;

namespace estlab {

namespace {

constexpr const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                   "#9467bd", "#8c564b", "#e377c2", "#17becf"};

std::string Color(size_t i) { return kColors[i % (sizeof kColors / sizeof kColors[0])]; }

// Line j of a figure with several filter x noise lines: its colour, its own
// dash pattern and its own marker every `point_every` rows, so that lines
// that coincide still show every legend entry.
std::string LineStyle(size_t j, size_t point_every) {
  return "with linespoints lw 1.5 lc rgb '" + Color(j) + "' dt " + std::to_string(1 + j % 5) +
         " pt " + std::to_string(1 + j % 7) + " ps 0.8 pi " +
         std::to_string(std::max<size_t>(1, point_every));
}

std::string DatValue(const std::string& s) { return s.empty() ? "NaN" : s; }

// "theta [rad]": the state's unit as its model header states it
// (Model::kStateUnits); none for an unknown model or state.
std::string Unit(const std::string& model, const std::string& state) {
  for (const ModelEntry* m : AllModels()) {
    if (m->name != model) continue;
    const int i = m->StateIndex(state);
    return i >= 0 ? m->state_units[i] : "";
  }
  return "";
}
std::string Label(const std::string& model, const std::string& what) {
  // what = "RMSE theta" etc.: the unit of its last word
  const auto sp = what.rfind(' ');
  const std::string u = Unit(model, sp == std::string::npos ? what : what.substr(sp + 1));
  return u.empty() ? what : what + " [" + u + "]";
}

using Figure = GnuplotFigure;

struct ComboName {
  std::string filter, noise;
  std::string label() const { return filter + "/" + noise; }
};

std::vector<ComboName> Combos(const StudyConfig& c, const ScenarioConfig& sc) {
  std::vector<ComboName> out;
  for (const Combo& cb : sc.combos)
    out.push_back({c.filters[cb.filter].name, c.noises[cb.noise].name});
  return out;
}

// Estimate vs truth with the +-2 sd band in one kept run, and the
// measurements: as points on the panel of the state an output is named
// after (pendulum angle: theta), else on a panel of their own (sin_theta).
void EstimateFigure(const ScenarioConfig& sc, int run, const ComboName& cn, const std::string& csv,
                    const std::string& folder, const std::string& term,
                    std::vector<std::string>* scripts) {
  const CsvTable ts = ReadCsv(csv);
  const auto& states = sc.model->states;
  std::vector<std::string> outputs;  // those the time series has (older folders: none)
  for (const auto& o : sc.model->FindMeasurement(sc.truth.measurement).outputs)
    if (ts.ColumnIndex("z_" + o) >= 0) outputs.push_back(o);
  Figure fig(folder,
             sc.name + "_estimate_run" + std::to_string(run) + "_" + cn.filter + "_" + cn.noise);
  fig.dat() << "# " << sc.name << " run " << run << ", " << cn.label() << ": t";
  for (const auto& s : states)
    fig.dat() << " " << s << "_true " << s << "_est " << s << "_lo2sd " << s << "_hi2sd";
  for (const auto& o : outputs) fig.dat() << " z_" << o;
  fig.dat() << "\n";
  for (const auto& row : ts.rows) {
    fig.dat() << FormatDouble(row[0]);
    auto put = [&](const std::string& column) {
      const double v = row[ts.ColumnIndex(column)];
      fig.dat() << " " << (std::isfinite(v) ? FormatDouble(v) : "NaN");
    };
    for (const auto& s : states)
      for (const char* suffix : {"_true", "_est", "_lo2sd", "_hi2sd"}) put(s + suffix);
    for (const auto& o : outputs) put("z_" + o);
    fig.dat() << "\n";
  }
  const size_t z0 = 2 + 4 * states.size();  // first measurement column
  std::vector<size_t> own_panel;            // outputs not named like a state
  for (size_t j = 0; j < outputs.size(); ++j)
    if (sc.model->StateIndex(outputs[j]) < 0) own_panel.push_back(j);
  const size_t panels = states.size() + own_panel.size();
  const std::string points = " with points pt 7 ps 0.35 lc rgb '#7f7f7f' title 'measurement'";
  auto& b = fig.body();
  b << "  set multiplot layout " << panels << ",1 title "
    << GnuplotText(sc.name + ", run " + std::to_string(run) + ": " + cn.label() +
                   (sc.has_truth ? " estimate vs truth" : " estimate (recorded data, no truth)"))
    << "\n";
  for (size_t i = 0; i < states.size(); ++i) {
    const size_t c0 = 2 + 4 * i;  // true, est, lo, hi columns
    b << "  set ylabel " << GnuplotText(Label(sc.model->name, states[i])) << "\n"
      << (i + 1 == panels ? "  set xlabel 't [s]'\n" : "  unset xlabel\n") << "  plot "
      << GnuplotQuote(fig.dat_name()) << " using 1:" << c0 + 2 << ":" << c0 + 3
      << " with filledcurves fillstyle solid 1.0 noborder lc rgb '#c6dbef' title '+-2 sd'";
    for (size_t j = 0; j < outputs.size(); ++j)
      if (outputs[j] == states[i]) b << ", \\\n       '' using 1:" << z0 + j << points;
    if (sc.has_truth)
      b << ", \\\n       '' using 1:" << c0 << " with lines lw 2 lc rgb 'black' title 'truth'";
    b << ", \\\n       '' using 1:" << c0 + 1
      << " with lines lw 1.5 lc rgb '#1f77b4' title 'estimate'\n";
  }
  for (size_t p = 0; p < own_panel.size(); ++p) {
    const size_t j = own_panel[p];
    b << "  set ylabel " << GnuplotText("z " + outputs[j]) << "\n"
      << (states.size() + p + 1 == panels ? "  set xlabel 't [s]'\n" : "  unset xlabel\n")
      << "  plot " << GnuplotQuote(fig.dat_name()) << " using 1:" << z0 + j << points << "\n";
  }
  b << "  unset multiplot\n";
  scripts->push_back(fig.Write(term, 900, 300 * int(panels) + 60));
}

// One panel per state, one line per block j of the figure's .dat (t in
// column 1, state i in column i + 2), the y label WHAT + state with its unit.
void StatePanels(const ScenarioConfig& sc, const std::vector<ComboName>& combos,
                 const std::vector<size_t>& blocks, const std::string& what, size_t point_every,
                 Figure* fig) {
  const auto& states = sc.model->states;
  auto& b = fig->body();
  for (size_t i = 0; i < states.size(); ++i) {
    b << "  set ylabel " << GnuplotText(Label(sc.model->name, what + states[i])) << "\n"
      << (i + 1 == states.size() ? "  set xlabel 't [s]'\n" : "  unset xlabel\n") << "  plot ";
    for (size_t j = 0; j < blocks.size(); ++j)
      b << (j ? ", \\\n       " : "") << GnuplotQuote(fig->dat_name()) << " index " << j
        << " using 1:" << i + 2 << " " << LineStyle(j, point_every) << " title "
        << GnuplotText(combos[blocks[j]].label());
    b << "\n";
  }
}

void RmseTimeFigure(const ScenarioConfig& sc, const std::vector<ComboName>& combos,
                    const std::vector<size_t>& blocks, size_t point_every, const std::string& term,
                    Figure* fig, std::vector<std::string>* scripts) {
  const auto& states = sc.model->states;
  Figure& rmse = *fig;
  auto& b = rmse.body();
  b << "  set multiplot layout " << states.size() << ",1 title "
    << GnuplotText(sc.name + ": RMSE over time across runs (filter/noise)") << "\n";
  StatePanels(sc, combos, blocks, "RMSE ", point_every, &rmse);
  b << "  unset multiplot\n";
  scripts->push_back(rmse.Write(term, 900, 300 * int(states.size()) + 60));
}

// Mean NEES and NIS over time with their bounds; NIS only without truth.
void ConsistencyFigure(const ScenarioConfig& sc, const std::vector<ComboName>& combos,
                       const std::vector<size_t>& blocks, size_t point_every,
                       const std::string& term, Figure* fig, std::vector<std::string>* scripts) {
  Figure& cons = *fig;
  auto& c = cons.body();
  c << "  set multiplot layout " << (sc.has_truth ? 2 : 1) << ",1 title "
    << GnuplotText(sc.name +
                   (sc.has_truth ? ": mean NEES and NIS" : ": mean NIS (no truth: no NEES)") +
                   " across runs, 95 % bounds dashed")
    << "\n"
    << GnuplotLogAxis("y");
  for (int panel = sc.has_truth ? 0 : 1; panel < 2; ++panel) {
    const int col = panel == 0 ? 2 : 5;
    c << "  set ylabel " << GnuplotText(panel == 0 ? "NEES" : "NIS") << "\n"
      << (panel == 1 ? "  set xlabel 't [s]'\n" : "  unset xlabel\n") << "  plot ";
    for (size_t j = 0; j < blocks.size(); ++j)
      c << (j ? ", \\\n       " : "") << GnuplotQuote(cons.dat_name()) << " index " << j
        << " using 1:" << col << " " << LineStyle(j, point_every) << " title "
        << GnuplotText(combos[blocks[j]].label());
    c << ", \\\n       '' index 0 using 1:" << col + 1
      << " with lines dt 2 lc rgb 'gray30' title '95 % bounds', \\\n       '' index 0 using 1:"
      << col + 2 << " with lines dt 2 lc rgb 'gray30' notitle\n";
  }
  c << "  unset multiplot\n";
  scripts->push_back(cons.Write(term, 900, sc.has_truth ? 700 : 380));
}

void TimeFigures(const ScenarioConfig& sc, const std::vector<ComboName>& combos, const CsvText& tm,
                 const std::string& folder, const std::string& term,
                 std::vector<std::string>* scripts) {
  const auto& states = sc.model->states;
  Figure rmse(folder, sc.name + "_rmse_time");
  Figure cons(folder, sc.name + "_nees_nis");
  const int tc = tm.Column("t");
  std::vector<int> rc;
  for (const auto& s : states) rc.push_back(tm.Column("rmse_" + s));
  const char* cons_cols[] = {"mean_nees", "nees_lo95", "nees_hi95",
                             "mean_nis",  "nis_lo95",  "nis_hi95"};
  std::vector<size_t> blocks;  // combos that have data
  size_t rows_per_block = 0;
  for (size_t k = 0; k < combos.size(); ++k) {
    bool any = false;
    size_t rows = 0;
    for (const auto& r : tm.rows) {
      if (r[0] != sc.name || r[1] != combos[k].filter || r[2] != combos[k].noise) continue;
      rows_per_block = std::max(rows_per_block, ++rows);
      if (!any) {
        rmse.dat() << "# " << combos[k].label() << ": t";
        for (const auto& s : states) rmse.dat() << " rmse_" << s;
        rmse.dat() << "\n";
        cons.dat() << "# " << combos[k].label()
                   << ": t mean_nees nees_lo95 nees_hi95 mean_nis nis_lo95 nis_hi95\n";
      }
      any = true;
      rmse.dat() << r[tc];
      for (int c : rc) rmse.dat() << " " << DatValue(r[c]);
      rmse.dat() << "\n";
      cons.dat() << r[tc];
      for (const char* c : cons_cols) cons.dat() << " " << DatValue(r[tm.Column(c)]);
      cons.dat() << "\n";
    }
    if (any) {
      rmse.dat() << "\n\n";
      cons.dat() << "\n\n";
      blocks.push_back(k);
    }
  }
  if (blocks.empty()) return;
  const size_t point_every = rows_per_block / 15;  // about 15 markers per line
  if (sc.has_truth) RmseTimeFigure(sc, combos, blocks, point_every, term, &rmse, scripts);
  ConsistencyFigure(sc, combos, blocks, point_every, term, &cons, scripts);
}

// One panel of MeansFigure: a summary.csv metric and its axis label.
struct MeanPanel {
  std::string metric, label;
};

// The mean of each panel's metric per filter x noise with the 95 % CI of the
// mean, settings on the y axis (long names stay readable), coloured by their
// role: oracle blue, auto-tuned red, hand-tuned grey. SCEN_rmse_means has one
// panel per state; on recorded data SCEN_pred_rmse_means one per output.
void MeansFigure(const StudyConfig& c, const ScenarioConfig& sc,
                 const std::vector<ComboName>& combos, const CsvText& summary,
                 const std::vector<MeanPanel>& panels, const std::string& name,
                 const std::string& what, const std::string& folder, const std::string& term,
                 std::vector<std::string>* scripts) {
  Figure fig(folder, sc.name + "_" + name);
  const int mc = summary.Column("metric"), mean = summary.Column("mean");
  const int lo = summary.Column("ci95_lo"), hi = summary.Column("ci95_hi");
  auto role_color = [&](const std::string& noise) {
    for (const auto& n : c.noises)
      if (n.name == noise)
        return n.role == NoiseRole::kOracle ? 0 : n.role == NoiseRole::kTuned ? 1 : 2;
    return 2;
  };
  for (const MeanPanel& p : panels) {
    fig.dat() << "# " << p.metric
              << ": index label mean ci95_lo ci95_hi role(0 oracle, 1 tuned, 2 hand)\n";
    for (size_t k = 0; k < combos.size(); ++k)
      for (const auto& r : summary.rows)
        if (r[0] == sc.name && r[1] == combos[k].filter && r[2] == combos[k].noise &&
            r[mc] == p.metric)
          fig.dat() << k << " \"" << combos[k].label() << "\" " << DatValue(r[mean]) << " "
                    << DatValue(r[lo]) << " " << DatValue(r[hi]) << " "
                    << role_color(combos[k].noise) << "\n";
    fig.dat() << "\n\n";
  }
  size_t longest = 8;
  for (const auto& cn : combos) longest = std::max(longest, cn.label().size());
  auto& b = fig.body();
  b << "  set multiplot layout " << panels.size() << ",1 title "
    << GnuplotText(sc.name + ": " + what +
                   ", 95 % CI of the mean (blue oracle, red tuned, grey hand)")
    << "\n"
    << "  set yrange [" << double(combos.size()) - 0.5 << ":-0.5]\n"
    << "  set lmargin " << longest + 3 << "\n  unset key\n  set ytics noenhanced\n"
    << "  set palette defined (0 '#1f77b4', 1 '#d62728', 2 '#7f7f7f')\n"
    << "  set cbrange [0:2]\n  unset colorbox\n";
  for (size_t i = 0; i < panels.size(); ++i)
    b << "  set xlabel " << GnuplotText(panels[i].label) << "\n  plot "
      << GnuplotQuote(fig.dat_name()) << " index " << i
      << " using 3:1:4:5:6:ytic(2) with xerrorbars pt 7 ps 1.2 lc palette\n";
  b << "  unset multiplot\n";
  const int panel = 22 * int(combos.size()) + 90;
  scripts->push_back(fig.Write(term, 900, panel * int(panels.size()) + 40));
}

// The MeansFigures of a scenario: RMSE with truth; prediction RMSE and NLL
// per step on recorded data.
void MeansFigures(const StudyConfig& c, const ScenarioConfig& sc,
                  const std::vector<ComboName>& combos, const CsvText& summary,
                  const std::string& folder, const std::string& term,
                  std::vector<std::string>* scripts) {
  const std::string& model = sc.model->name;
  if (sc.has_truth) {
    std::vector<MeanPanel> panels;
    for (const auto& s : sc.model->states)
      panels.push_back({"rmse_" + s, Label(model, "mean RMSE " + s)});
    MeansFigure(c, sc, combos, summary, panels, "rmse_means", "mean RMSE", folder, term, scripts);
  }
  if (!sc.recorded) return;
  std::vector<MeanPanel> panels;
  for (const auto& o : sc.model->FindMeasurement(sc.truth.measurement).outputs)
    panels.push_back({"pred_rmse_" + o, Label(model, "one-step prediction RMSE " + o)});
  MeansFigure(c, sc, combos, summary, panels, "pred_rmse_means", "one-step prediction RMSE", folder,
              term, scripts);
  MeansFigure(c, sc, combos, summary, {{"nll_per_step", "NLL per step"}}, "nll_means",
              "innovation NLL per step", folder, term, scripts);
}

// The filters' own standard deviation sqrt(P_ii) over time in one kept run
// (paper 000 plots it beside the error), every filter x noise of the run.
void SigmaFigure(const ScenarioConfig& sc, int run, const std::vector<ComboName>& combos,
                 const std::string& dir, const std::string& folder, const std::string& term,
                 std::vector<std::string>* scripts) {
  const auto& states = sc.model->states;
  Figure fig(folder, sc.name + "_sigma_run" + std::to_string(run));
  std::vector<size_t> blocks;
  size_t rows_per_block = 0;
  for (size_t k = 0; k < combos.size(); ++k) {
    const std::string csv = dir + "/timeseries/" + sc.name + "/run" + std::to_string(run) + "_" +
                            combos[k].filter + "_" + combos[k].noise + ".csv";
    if (!fs::exists(csv)) continue;
    const CsvTable ts = ReadCsv(csv);
    rows_per_block = std::max(rows_per_block, ts.rows.size());
    fig.dat() << "# " << combos[k].label() << ": t";
    for (const auto& s : states) fig.dat() << " sd_" << s;
    fig.dat() << "\n";
    for (const auto& row : ts.rows) {
      fig.dat() << FormatDouble(row[0]);
      for (const auto& s : states) {
        // The time series keep est -+ 2 sd; the band's width is 4 sd.
        const double sd =
            (row[ts.ColumnIndex(s + "_hi2sd")] - row[ts.ColumnIndex(s + "_lo2sd")]) / 4.0;
        fig.dat() << " " << (std::isfinite(sd) ? FormatDouble(sd) : "NaN");
      }
      fig.dat() << "\n";
    }
    fig.dat() << "\n\n";
    blocks.push_back(k);
  }
  if (blocks.empty()) return;
  auto& b = fig.body();
  b << "  set multiplot layout " << states.size() << ",1 title "
    << GnuplotText(sc.name + ", run " + std::to_string(run) +
                   ": filter standard deviation sqrt(P) over time (log scale)")
    << "\n"
    << GnuplotLogAxis("y");
  StatePanels(sc, combos, blocks, "sd ", rows_per_block / 15, &fig);
  b << "  unset multiplot\n";
  scripts->push_back(fig.Write(term, 900, 300 * int(states.size()) + 60));
}

// Mean RMSE against the one varied key of a scenario section (a noise sweep
// such as paper 003's), with the 95 % CI of the mean, one line per filter x
// noise. Drawn for sections expanded over exactly one key into >= 3 scenarios.
void SweepFigures(const StudyConfig& c, const CsvText& summary, const std::string& folder,
                  const std::string& term, std::vector<std::string>* scripts) {
  std::map<std::string, std::vector<const ScenarioConfig*>> sections;
  std::vector<std::string> order;
  for (const auto& sc : c.scenarios) {
    if (!sections.count(sc.section)) order.push_back(sc.section);
    sections[sc.section].push_back(&sc);
  }
  const int mc = summary.Column("metric"), mean = summary.Column("mean");
  const int lo = summary.Column("ci95_lo"), hi = summary.Column("ci95_hi");
  for (const auto& section : order) {
    const auto& scs = sections[section];
    if (scs.size() < 3 || scs[0]->choices.size() != 1) continue;
    const ScenarioConfig& first = *scs[0];
    const std::string key = first.choices[0].first;
    const auto combos = Combos(c, first);
    const auto& states = first.model->states;
    const std::string base = section.substr(section.find('.') + 1);
    Figure fig(folder, base + "_rmse_vs_" + key);
    for (const auto& s : states) {
      for (const auto& cn : combos) {
        fig.dat() << "# rmse_" << s << ", " << cn.label() << ": index " << key
                  << " mean ci95_lo ci95_hi\n";
        for (size_t k = 0; k < scs.size(); ++k)
          for (const auto& r : summary.rows)
            if (r[0] == scs[k]->name && r[1] == cn.filter && r[2] == cn.noise &&
                r[mc] == "rmse_" + s)
              fig.dat() << k << " \"" << scs[k]->choices[0].second << "\" " << DatValue(r[mean])
                        << " " << DatValue(r[lo]) << " " << DatValue(r[hi]) << "\n";
        fig.dat() << "\n\n";
      }
    }
    auto& b = fig.body();
    b << "  set multiplot layout " << (states.size() + 1) / 2 << ",2 title "
      << GnuplotText(base + ": mean RMSE over runs vs " + key + " (95 % CI of the mean)") << "\n"
      << "  set xrange [-0.5:" << double(scs.size()) - 0.5 << "]\n"
      << GnuplotLogAxis("y") << "  set xlabel " << GnuplotText(key + " (scenario label)")
      << "\n  set xtics rotate by -40 noenhanced\n  set key inside top left\n";
    for (size_t i = 0; i < states.size(); ++i) {
      b << "  set ylabel " << GnuplotText(Label(first.model->name, "RMSE " + states[i]))
        << "\n  plot ";
      for (size_t j = 0; j < combos.size(); ++j) {
        const size_t index = i * combos.size() + j;
        b << (j ? ", \\\n       " : "") << GnuplotQuote(fig.dat_name()) << " index " << index
          << " using 1:3:4:5:xticlabels(2) with yerrorlines pt " << 1 + j % 7
          << " ps 0.8 lw 1.5 dt " << 1 + j % 5 << " lc rgb '" << Color(j) << "' title "
          << GnuplotText(combos[j].label());
      }
      b << "\n";
    }
    b << "  unset multiplot\n";
    scripts->push_back(fig.Write(term, 1200, 380 * int((states.size() + 1) / 2) + 60));
  }
}

}  // namespace

FiguresSummary DrawStudyFigures(const std::string& dir, const FiguresOptions& options) {
  StudyState state;
  if (!ReadStudyState(dir, &state))
    throw InputError("'" + dir + "' is not a study results folder (no study.state)");
  if (state.status != "complete")
    throw InputError("the study in '" + dir + "' is " + state.status +
                     "; finish it first (run its estlab study command again)");
  const StudyConfig config = LoadResultsConfig(dir, state);
  const CsvText summary = ReadCsvText(dir + "/summary.csv");
  const CsvText tm = ReadCsvText(dir + "/time_metrics.csv");

  FiguresSummary out;
  out.folder = dir + "/figures";
  fs::create_directories(out.folder);
  const std::string term = ScriptTerminal(options, &out.message);
  out.terminal = term;

  int estimate_figures = 0;
  for (const ScenarioConfig& sc : config.scenarios) {
    const auto combos = Combos(config, sc);
    for (int run : config.study.keep_runs) {
      bool drawn = false;
      for (const auto& cn : combos) {
        const std::string csv = dir + "/timeseries/" + sc.name + "/run" + std::to_string(run) +
                                "_" + cn.filter + "_" + cn.noise + ".csv";
        if (!fs::exists(csv) || estimate_figures >= options.max_estimate_figures) continue;
        EstimateFigure(sc, run, cn, csv, out.folder, term, &out.scripts);
        ++estimate_figures;
        drawn = true;
      }
      if (drawn) {  // the first kept run that exists
        SigmaFigure(sc, run, combos, dir, out.folder, term, &out.scripts);
        break;
      }
    }
    TimeFigures(sc, combos, tm, out.folder, term, &out.scripts);
    MeansFigures(config, sc, combos, summary, out.folder, term, &out.scripts);
  }
  SweepFigures(config, summary, out.folder, term, &out.scripts);
  IdentificationFigures(dir + "/identification.csv", out.folder, term, &out.scripts);
  RenderFigures(options, &out);
  return out;
}

}  // namespace estlab
