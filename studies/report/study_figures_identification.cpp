#include "studies/report/study_figures_identification.h"

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "studies/report/gnuplot_figure.h"
#include "studies/results/study_results.h"

namespace estlab {

namespace {

std::string DatValue(const std::string& s) { return s.empty() ? "NaN" : s; }

struct Rows {
  const CsvText& csv;
  std::string Get(const std::vector<std::string>& row, const std::string& column) const {
    const int c = csv.Column(column);
    return c >= 0 && size_t(c) < row.size() ? row[size_t(c)] : std::string();
  }
};

// Score [95 % CI] against cost, a labelled point per setting, a colour per
// case (its reference filter; one .dat block each).
void ScoreCostFigure(const Rows& r, const std::string& scenario, const std::string& folder,
                     const std::string& term, std::vector<std::string>* scripts) {
  GnuplotFigure fig(folder, scenario + "_score_cost");
  std::vector<std::string> kinds;
  for (const auto& row : r.csv.rows)
    if (row[0] == scenario &&
        std::find(kinds.begin(), kinds.end(), r.Get(row, "case")) == kinds.end())
      kinds.push_back(r.Get(row, "case"));
  for (const auto& kind : kinds) {
    fig.dat() << "# " << kind << ": cost_s score score_lo score_hi \"setting\"\n";
    for (const auto& row : r.csv.rows)
      if (row[0] == scenario && r.Get(row, "case") == kind)
        fig.dat() << DatValue(r.Get(row, "cost_s")) << " " << DatValue(r.Get(row, "score")) << " "
                  << DatValue(r.Get(row, "score_lo")) << " " << DatValue(r.Get(row, "score_hi"))
                  << " \"" << r.Get(row, "setting") << "\"\n";
    fig.dat() << "\n\n";
  }
  const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd"};
  auto& b = fig.body();
  b << "  set title " << GnuplotText(scenario + ": score (1 = the truth's noise) vs cost per run")
    << "\n"
    << GnuplotLogAxis("x") << "  set xlabel 'mean wall time per run, identification + filter [s]'\n"
    << "  set logscale y\n  set ylabel 'score [95 % CI] (log scale)'\n  plot ";
  for (size_t i = 0; i < kinds.size(); ++i) {
    const std::string color = colors[i % 5];
    b << (i ? ", \\\n       " : "") << GnuplotQuote(fig.dat_name()) << " index " << i
      << " using 1:2:3:4 with yerrorbars pt 7 ps 1.2 lc rgb '" << color << "' title "
      << GnuplotText(kinds[i]) << ", \\\n       '' index " << i
      << " using 1:2:5 with labels left offset 1,0 font ',9' tc rgb '" << color
      << "' noenhanced notitle";
  }
  b << "\n";
  scripts->push_back(fig.Write(term, 1000, 600));
}

// The identified Q's and R's errors of the per-run settings.
void ErrorFigure(const Rows& r, const std::string& scenario, const std::string& folder,
                 const std::string& term, std::vector<std::string>* scripts) {
  std::vector<const std::vector<std::string>*> rows;
  for (const auto& row : r.csv.rows)
    if (row[0] == scenario && r.Get(row, "per_run") == "1") rows.push_back(&row);
  if (rows.empty()) return;
  GnuplotFigure fig(folder, scenario + "_id_error");
  size_t longest = 8;
  for (const char* which : {"q", "r"}) {
    const std::string w = which;
    fig.dat() << "# " << w << ": index label median p2_5 p97_5\n";
    for (size_t k = 0; k < rows.size(); ++k) {
      const std::string label = r.Get(*rows[k], "filter") + " " + r.Get(*rows[k], "setting");
      longest = std::max(longest, label.size());
      fig.dat() << k << " \"" << label << "\" " << DatValue(r.Get(*rows[k], w + "_err_median"))
                << " " << DatValue(r.Get(*rows[k], w + "_err_p2_5")) << " "
                << DatValue(r.Get(*rows[k], w + "_err_p97_5")) << "\n";
    }
    fig.dat() << "\n\n";
  }
  auto& b = fig.body();
  // A side no setting tunes has no finite value: no panel (a log axis
  // without data stops gnuplot).
  const char* labels[] = {"relative Frobenius error of Q", "relative Frobenius error of R"};
  std::vector<int> panels;
  for (int i = 0; i < 2; ++i) {
    const std::string column = std::string(i == 0 ? "q" : "r") + "_err_median";
    bool any = false;
    for (const auto* row : rows) any = any || !r.Get(*row, column).empty();
    if (any) panels.push_back(i);
  }
  if (panels.empty()) return;
  b << "  set multiplot layout " << panels.size() << ",1 title "
    << GnuplotText(scenario + ": identified noise vs the truth's, median and 2.5-97.5 % of runs")
    << "\n  set yrange [" << double(rows.size()) - 0.5 << ":-0.5]\n  set lmargin " << longest + 3
    << "\n  unset key\n  set ytics noenhanced\n"
    << GnuplotLogAxis("x");
  for (int i : panels)
    b << "  set xlabel '" << labels[i] << "'\n  plot " << GnuplotQuote(fig.dat_name()) << " index "
      << i << " using 3:1:4:5:ytic(2) with xerrorbars pt 7 ps 1.2 lc rgb '#d62728'\n";
  b << "  unset multiplot\n";
  const int panel = 22 * int(rows.size()) + 90;
  scripts->push_back(fig.Write(term, 900, int(panels.size()) * panel + 40));
}

}  // namespace

void IdentificationFigures(const std::string& csv_path, const std::string& folder,
                           const std::string& term, std::vector<std::string>* scripts) {
  if (!std::filesystem::exists(csv_path)) return;
  const CsvText csv = ReadCsvText(csv_path);
  const Rows rows{csv};
  std::vector<std::string> scenarios;
  for (const auto& row : csv.rows)
    if (std::find(scenarios.begin(), scenarios.end(), row[0]) == scenarios.end())
      scenarios.push_back(row[0]);
  for (const auto& s : scenarios) {
    ScoreCostFigure(rows, s, folder, term, scripts);
    ErrorFigure(rows, s, folder, term, scripts);
  }
}

}  // namespace estlab
