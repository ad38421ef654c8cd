#include "studies/report/run_figures.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "src/core/types.h"
#include "src/io/output_file.h"
#include "src/run/filter_spec.h"

namespace fs = std::filesystem;

namespace estlab {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// The columns of the run's table by name.
class Table {
 public:
  explicit Table(const RunFigureInput& in) : in_(in) {}
  int Col(const std::string& name) const {
    const auto it = std::find(in_.columns.begin(), in_.columns.end(), name);
    return it == in_.columns.end() ? -1 : int(it - in_.columns.begin());
  }
  double At(size_t row, int col) const {
    return col >= 0 && size_t(col) < in_.rows[row].size() ? in_.rows[row][col] : kNan;
  }
  size_t rows() const { return in_.rows.size(); }

 private:
  const RunFigureInput& in_;
};

// Single-panel figures keep the whole width for the plot (and its title).
constexpr const char* kKeyBelow = "  set key below\n";

std::string Dat(double v) { return std::isfinite(v) ? FormatDouble(v) : "NaN"; }

std::string XLabel(bool last) { return last ? "  set xlabel 't [s]'\n" : "  unset xlabel\n"; }

struct RunContext {
  const RunFigureInput& in;
  Table table;
  std::vector<std::string> states;   // from the <state>_est columns
  std::vector<std::string> outputs;  // in.outputs, else from nu_<output>
  std::string folder, term;
  std::vector<std::string>* scripts;
};

std::string StateLabel(const RunContext& c, const std::string& state) {
  for (const auto& [name, unit] : c.in.state_units)
    if (name == state && !unit.empty()) return state + " [" + unit + "]";
  return state;
}

// Block 0: t, then est, est - 2 sd, est + 2 sd, truth per state; block 1:
// the measurements (t, z per output).
void EstimatesFigure(const RunContext& c) {
  GnuplotFigure fig(c.folder, "estimates");
  const Table& tb = c.table;
  const int tc = tb.Col("t");
  bool truth = true;
  for (const auto& s : c.states) truth = truth && tb.Col(s + "_err") >= 0;
  fig.dat() << "# t";
  for (const auto& s : c.states)
    fig.dat() << " " << s << "_est " << s << "_lo2sd " << s << "_hi2sd " << s << "_true";
  fig.dat() << "\n";
  for (size_t k = 0; k < tb.rows(); ++k) {
    fig.dat() << Dat(tb.At(k, tc));
    for (const auto& s : c.states) {
      const double est = tb.At(k, tb.Col(s + "_est"));
      const double sd = std::sqrt(std::max(0.0, tb.At(k, tb.Col(s + "_var"))));
      const double err = truth ? tb.At(k, tb.Col(s + "_err")) : kNan;
      fig.dat() << " " << Dat(est) << " " << Dat(est - 2 * sd) << " " << Dat(est + 2 * sd) << " "
                << Dat(est - err);
    }
    fig.dat() << "\n";
  }
  const size_t m = c.outputs.size();
  const bool have_z = m > 0 && c.in.meas_z.size() == c.in.meas_t.size() * m;
  fig.dat() << "\n\n# t";
  for (const auto& o : c.outputs) fig.dat() << " z_" << o;
  fig.dat() << "\n";
  if (have_z) {
    for (size_t k = 0; k < c.in.meas_t.size(); ++k) {
      fig.dat() << Dat(c.in.meas_t[k]);
      for (size_t j = 0; j < m; ++j) fig.dat() << " " << Dat(c.in.meas_z[k * m + j]);
      fig.dat() << "\n";
    }
  } else {
    fig.dat() << "NaN\n";  // an empty block would stop gnuplot
  }
  auto& b = fig.body();
  const size_t n = c.states.size();
  b << "  set multiplot layout " << n << ",1 title "
    << GnuplotText(c.in.title + (truth ? ": estimate, +-2 sd and truth" : ": estimate and +-2 sd"))
    << "\n";
  for (size_t i = 0; i < n; ++i) {
    const size_t c0 = 2 + 4 * i;  // est, lo, hi, truth
    b << "  set ylabel " << GnuplotText(StateLabel(c, c.states[i])) << "\n"
      << XLabel(i + 1 == n) << "  plot " << GnuplotQuote(fig.dat_name())
      << " index 0 using 1:" << c0 + 1 << ":" << c0 + 2
      << " with filledcurves fillstyle solid 1.0 noborder lc rgb '#c6dbef' title '+-2 sd'";
    for (size_t j = 0; j < m && have_z; ++j)
      if (c.outputs[j] == c.states[i])
        b << ", \\\n       '' index 1 using 1:" << j + 2
          << " with points pt 7 ps 0.35 lc rgb '#7f7f7f' title 'measurement'";
    if (truth)
      b << ", \\\n       '' index 0 using 1:" << c0 + 3
        << " with lines lw 2 lc rgb 'black' title 'truth'";
    b << ", \\\n       '' index 0 using 1:" << c0
      << " with lines lw 1.5 lc rgb '#1f77b4' title 'estimate'\n";
  }
  b << "  unset multiplot\n";
  c.scripts->push_back(fig.Write(c.term, 900, 260 * int(n) + 60));

  // Outputs that are not a state (sin_theta) get their own figure.
  std::vector<size_t> other;
  for (size_t j = 0; j < m && have_z; ++j)
    if (std::find(c.states.begin(), c.states.end(), c.outputs[j]) == c.states.end())
      other.push_back(j);
  if (other.empty()) return;
  GnuplotFigure mf(c.folder, "measurements");
  mf.dat() << fig.dat().str().substr(fig.dat().str().find("\n\n# t") + 2);
  auto& mb = mf.body();
  mb << "  set multiplot layout " << other.size() << ",1 title "
     << GnuplotText(c.in.title + ": measurements") << "\n";
  for (size_t p = 0; p < other.size(); ++p)
    mb << "  set ylabel " << GnuplotText("z " + c.outputs[other[p]]) << "\n"
       << XLabel(p + 1 == other.size()) << "  plot " << GnuplotQuote(mf.dat_name())
       << " using 1:" << other[p] + 2 << " with points pt 7 ps 0.35 lc rgb '#7f7f7f' title "
       << GnuplotText(c.outputs[other[p]]) << "\n";
  mb << "  unset multiplot\n";
  c.scripts->push_back(mf.Write(c.term, 900, 260 * int(other.size()) + 60));
}

// nu_k with +-2 sqrt(S_k), one panel per output.
void InnovationsFigure(const RunContext& c) {
  const Table& tb = c.table;
  GnuplotFigure fig(c.folder, "innovations");
  fig.dat() << "# t";
  for (const auto& o : c.outputs)
    fig.dat() << " nu_" << o << " lo2sqrtS_" << o << " hi2sqrtS_" << o;
  fig.dat() << "\n";
  for (size_t k = 0; k < tb.rows(); ++k) {
    fig.dat() << Dat(tb.At(k, tb.Col("t")));
    for (const auto& o : c.outputs) {
      const double s = std::sqrt(tb.At(k, tb.Col("S_" + o)));
      fig.dat() << " " << Dat(tb.At(k, tb.Col("nu_" + o))) << " " << Dat(-2 * s) << " "
                << Dat(2 * s);
    }
    fig.dat() << "\n";
  }
  auto& b = fig.body();
  const size_t m = c.outputs.size();
  b << "  set multiplot layout " << m << ",1 title "
    << GnuplotText(c.in.title + ": innovations with +-2 sqrt(S)") << "\n";
  for (size_t j = 0; j < m; ++j) {
    const size_t c0 = 2 + 3 * j;
    b << "  set ylabel " << GnuplotText("nu " + c.outputs[j]) << "\n"
      << XLabel(j + 1 == m) << "  plot " << GnuplotQuote(fig.dat_name()) << " using 1:" << c0 + 1
      << ":" << c0 + 2
      << " with filledcurves fillstyle solid 1.0 noborder lc rgb '#fdd0a2' title '+-2 sqrt(S)', "
         "\\\n       '' using 1:"
      << c0 << " with points pt 7 ps 0.35 lc rgb '#d62728' title 'innovation'\n";
  }
  b << "  unset multiplot\n";
  c.scripts->push_back(fig.Write(c.term, 900, 260 * int(m) + 60));
}

// NIS_k (log scale) with the chi-square 95 % bounds of one step, for each
// number of observed components a row has (its finite nu_<output> cells: a
// sensor group missing in a row leaves it fewer), and of the mean NIS over
// the K updates with all their observed components (ChiSquareMeanBounds95).
void NisFigure(const RunContext& c) {
  const Table& tb = c.table;
  const int nis_c = tb.Col("nis");
  std::vector<int> nu_c;
  for (const auto& o : c.outputs) nu_c.push_back(tb.Col("nu_" + o));
  long updates = 0, dof = 0;
  double sum = 0.0;
  std::set<int> dofs;  // the observed counts that occur
  for (size_t k = 0; k < tb.rows(); ++k) {
    if (!std::isfinite(tb.At(k, nis_c))) continue;
    int observed = 0;
    for (const int col : nu_c) observed += col < 0 || std::isfinite(tb.At(k, col));
    ++updates, sum += tb.At(k, nis_c), dof += observed;
    dofs.insert(observed);
  }
  if (updates == 0) return;
  double mean[2];
  ChiSquareMeanBounds95(updates, dof, mean);
  GnuplotFigure fig(c.folder, "nis");
  fig.dat() << "# t nis\n";
  for (size_t k = 0; k < tb.rows(); ++k)
    if (std::isfinite(tb.At(k, nis_c)))
      fig.dat() << Dat(tb.At(k, tb.Col("t"))) << " " << Dat(tb.At(k, nis_c)) << "\n";
  auto& b = fig.body();
  b << "  set title "
    << GnuplotText(c.in.title + ": NIS, mean " + FormatNumber(sum / double(updates)) +
                   " (95 % bounds of the mean " + FormatNumber(mean[0]) + " .. " +
                   FormatNumber(mean[1]) + ")")
    << "\n"
    << GnuplotLogAxis("y") << kKeyBelow << "  set ylabel 'NIS'\n  set xlabel 't [s]'\n"
    << "  plot " << GnuplotQuote(fig.dat_name())
    << " using 1:2 with points pt 7 ps 0.35 lc rgb '#1f77b4' title 'NIS', \\\n       ";
  for (const int d : dofs) {
    double step[2];
    ChiSquareBounds95(1, d, step);
    b << FormatDouble(step[0]) << " with lines dt 2 lc rgb 'gray30' title "
      << GnuplotText("95 % of one step (chi2, " + std::to_string(d) + " dof)") << ", \\\n       "
      << FormatDouble(step[1]) << " with lines dt 2 lc rgb 'gray30' notitle, \\\n       ";
  }
  b << FormatDouble(sum / double(updates))
    << " with lines lw 2 lc rgb '#d62728' title 'mean NIS', \\\n       " << FormatDouble(mean[0])
    << " with lines dt 3 lc rgb '#d62728' title '95 % of the mean', \\\n       "
    << FormatDouble(mean[1]) << " with lines dt 3 lc rgb '#d62728' notitle\n";
  c.scripts->push_back(fig.Write(c.term, 900, 420));
}

void AutocorrelationFigure(const RunContext& c) {
  const Table& tb = c.table;
  std::vector<std::vector<double>> rho;
  size_t updates = 0;
  for (const auto& o : c.outputs) {
    std::vector<double> e;
    for (size_t k = 0; k < tb.rows(); ++k) {
      const double v = tb.At(k, tb.Col("nu_" + o)) / std::sqrt(tb.At(k, tb.Col("S_" + o)));
      if (std::isfinite(v)) e.push_back(v);
    }
    updates = std::max(updates, e.size());
    const int lags = int(std::min<size_t>(50, e.size() / 4));
    rho.push_back(Autocorrelation(e, lags));
  }
  if (updates < 8) return;
  GnuplotFigure fig(c.folder, "autocorrelation");
  for (size_t j = 0; j < rho.size(); ++j) {
    fig.dat() << "# " << c.outputs[j] << ": lag rho\n";
    for (size_t l = 0; l < rho[j].size(); ++l) fig.dat() << l + 1 << " " << Dat(rho[j][l]) << "\n";
    if (rho[j].empty()) fig.dat() << "NaN NaN\n";
    fig.dat() << "\n\n";
  }
  const double band = 1.96 / std::sqrt(double(updates));
  auto& b = fig.body();
  b << "  set title "
    << GnuplotText(c.in.title + ": autocorrelation of the whitened innovations nu/sqrt(S), " +
                   std::to_string(updates) + " updates")
    << "\n"
    << kKeyBelow << "  set xlabel 'lag [updates]'\n  set ylabel 'autocorrelation'\n  plot ";
  for (size_t j = 0; j < rho.size(); ++j)
    b << (j ? ", \\\n       " : "") << GnuplotQuote(fig.dat_name()) << " index " << j
      << " using 1:2 with impulses lw 2 lc rgb '" << (j % 2 ? "#d62728" : "#1f77b4") << "' title "
      << GnuplotText(c.outputs[j]);
  b << ", \\\n       " << FormatDouble(band)
    << " with lines dt 2 lc rgb 'gray30' title '95 % band of white noise', \\\n       "
    << FormatDouble(-band) << " with lines dt 2 lc rgb 'gray30' notitle\n";
  c.scripts->push_back(fig.Write(c.term, 900, 420));
}

void ConvergenceFigure(const RunContext& c) {
  GnuplotFigure fig(c.folder, "convergence");
  fig.dat() << "# iteration " << c.in.objective_name << "\n";
  for (size_t i = 0; i < c.in.objective_history.size(); ++i)
    fig.dat() << i << " " << Dat(c.in.objective_history[i]) << "\n";
  auto& b = fig.body();
  b << "  set title "
    << GnuplotText(c.in.title + ": the tuner's " + c.in.objective_name + " by iteration") << "\n"
    << kKeyBelow << "  set xlabel 'iteration (0: the start point)'\n  set ylabel "
    << GnuplotText(c.in.objective_name) << "\n  plot " << GnuplotQuote(fig.dat_name())
    << " using 1:2 with linespoints pt 7 ps 0.6 lc rgb '#1f77b4' title "
    << GnuplotText(c.in.objective_name) << "\n";
  c.scripts->push_back(fig.Write(c.term, 900, 420));
}

}  // namespace

// Per output two panels: z (points) with the free simulation y (line), then
// the errors e = z - y with their RMSE. Columns: t, then z, y, e per output.
void FreeSimulationFigure(const RunContext& c) {
  const RunFigureInput& in = c.in;
  const size_t m = c.outputs.size(), rows = in.meas_t.size();
  GnuplotFigure fig(c.folder, "free-simulation");
  fig.dat() << "# t";
  for (const auto& o : c.outputs) fig.dat() << " z_" << o << " sim_" << o << " err_" << o;
  fig.dat() << "\n";
  for (size_t k = 0; k < rows; ++k) {
    fig.dat() << Dat(in.meas_t[k]);
    for (size_t j = 0; j < m; ++j) {
      const double z = in.meas_z[k * m + j];
      fig.dat() << " " << Dat(z) << " " << Dat(in.sim_y[k * m + j]) << " "
                << Dat(std::isfinite(z) ? in.sim_e[k * m + j] : kNan);
    }
    fig.dat() << "\n";
  }
  auto& b = fig.body();
  b << "  set multiplot layout " << 2 * m << ",1 title " << GnuplotText(in.sim_title) << "\n"
    << "  set lmargin at screen 0.10\n  set rmargin at screen 0.68\n";  // panels aligned
  for (size_t j = 0; j < m; ++j) {
    const size_t c0 = 2 + 3 * j;
    const std::string rmse = j < in.sim_rmse.size() ? FormatNumber(in.sim_rmse[j]) : "-";
    b << "  set ylabel " << GnuplotText(c.outputs[j]) << "\n"
      << XLabel(false) << "  plot " << GnuplotQuote(fig.dat_name()) << " using 1:" << c0
      << " with points pt 7 ps 0.3 lc rgb '#7f7f7f' title 'measured', \\\n       '' using 1:"
      << c0 + 1 << " with lines lw 1.5 lc rgb '#1f77b4' title 'free simulation'\n"
      << "  set ylabel " << GnuplotText("z - y " + c.outputs[j]) << "\n"
      << XLabel(j + 1 == m) << "  plot " << GnuplotQuote(fig.dat_name()) << " using 1:" << c0 + 2
      << " with lines lc rgb '#d62728' title " << GnuplotText("error, RMSE " + rmse)
      << ", 0 with lines lc rgb 'black' notitle\n";
  }
  b << "  unset multiplot\n";
  c.scripts->push_back(fig.Write(c.term, 900, 220 * int(2 * m) + 60));
}

std::vector<double> Autocorrelation(const std::vector<double>& e, int max_lag) {
  std::vector<double> x;
  for (double v : e)
    if (std::isfinite(v)) x.push_back(v);
  if (max_lag < 1 || x.size() < size_t(max_lag) + 2) return {};
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= double(x.size());
  auto c = [&](int lag) {  // (1/K) sum_k (x_k - mean)(x_{k+lag} - mean)
    double s = 0.0;
    for (size_t k = 0; k + lag < x.size(); ++k) s += (x[k] - mean) * (x[k + lag] - mean);
    return s / double(x.size());
  };
  const double c0 = c(0);
  if (!(c0 > 0.0)) return {};
  std::vector<double> rho;
  for (int l = 1; l <= max_lag; ++l) rho.push_back(c(l) / c0);
  return rho;
}

void CheckFigureFolder(const std::string& dir) {
  if (fs::exists(dir) && !fs::is_directory(dir))
    throw InputError("figures: '" + dir + "' exists and is not a folder");
}

FiguresSummary DrawRunFigures(const RunFigureInput& in, const std::string& dir,
                              const FiguresOptions& options) {
  CheckFigureFolder(dir);
  RunContext c{in, Table(in), {}, in.outputs, dir, "", nullptr};
  if (c.table.Col("t") < 0) throw InputError("the estimates have no 't' column");
  for (const auto& col : in.columns)
    if (col.size() > 4 && col.compare(col.size() - 4, 4, "_est") == 0)
      c.states.push_back(col.substr(0, col.size() - 4));
  if (c.states.empty()) throw InputError("the estimates have no <state>_est column");
  if (c.outputs.empty())
    for (const auto& col : in.columns)
      if (col.rfind("nu_", 0) == 0) c.outputs.push_back(col.substr(3));
  FiguresSummary out;
  out.folder = dir;
  fs::create_directories(dir);
  c.term = ScriptTerminal(options, &out.message);
  out.terminal = c.term;
  c.scripts = &out.scripts;
  EstimatesFigure(c);
  bool innovations = !c.outputs.empty();
  for (const auto& o : c.outputs)
    innovations = innovations && c.table.Col("nu_" + o) >= 0 && c.table.Col("S_" + o) >= 0;
  if (innovations) {
    InnovationsFigure(c);
    if (c.table.Col("nis") >= 0) NisFigure(c);
    AutocorrelationFigure(c);
  }
  if (!in.objective_history.empty()) ConvergenceFigure(c);
  if (!in.sim_y.empty()) {
    const size_t cells = in.meas_t.size() * c.outputs.size();
    if (in.sim_y.size() != cells || in.sim_e.size() != cells || in.meas_z.size() != cells)
      throw InputError("the free simulation has " + std::to_string(in.sim_y.size()) +
                       " values for " + std::to_string(cells) + " measurements");
    FreeSimulationFigure(c);
  }
  RenderFigures(options, &out);
  return out;
}

}  // namespace estlab
