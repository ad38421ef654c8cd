// One gnuplot figure: NAME.dat (the numbers), NAME.gp (the script, which
// draws NAME.png and NAME.svg: `cd FOLDER && gnuplot NAME.gp` redraws it),
// and rendering with the gnuplot found on this machine. Used by the study
// figures (study_figures.h), the run figures (run_figures.h) and by
// `estlab tune --profile`.
//
// Usage:
//   GnuplotFigure fig("results", "profile_L");
//   fig.dat() << "# L nll\n0.15 -3.1e5\n";
//   fig.body() << "  plot 'profile_L.dat' using 1:2 with linespoints\n";
//   std::string message;
//   const std::string term = PngTerminal("gnuplot", &message);  // "" + message if none
//   const std::string script = fig.Write(term.empty() ? "png" : term, 800, 500);
//   if (!term.empty()) RenderFigure(script, "gnuplot", &message);
#ifndef ESTLAB_STUDIES_REPORT_GNUPLOT_FIGURE_H_
#define ESTLAB_STUDIES_REPORT_GNUPLOT_FIGURE_H_

#include <sstream>
#include <string>
#include <vector>

namespace estlab {

struct FiguresOptions {
  bool render = true;  // false: write .dat and .gp only
  std::string gnuplot = "gnuplot";
  int max_estimate_figures = 64;  // studies: estimate-vs-truth figures (first kept run)
};

struct FiguresSummary {
  std::string folder;
  std::vector<std::string> scripts;  // NAME.gp paths
  std::string terminal;              // pngcairo or png ("" when not rendered)
  bool rendered = false;
  std::string message;  // why not rendered
};

// The terminals are enhanced (so that log axes read 10^{-3} as a power of
// ten) and every axis uses %h: significant digits with a x10^n exponent,
// never repeated tick labels. Names must therefore be written with
// GnuplotText (noenhanced: a '_' stays a '_'); the key is noenhanced.
class GnuplotFigure {
 public:
  GnuplotFigure(std::string folder, std::string name)
      : folder_(std::move(folder)), name_(std::move(name)) {}
  std::ostringstream& dat() { return dat_; }
  // The plotting commands, run once per format (png, svg) after `reset`,
  // `set grid`, `set key outside right top noenhanced` and `set format x/y
  // '%h'`.
  std::ostringstream& body() { return body_; }
  std::string dat_name() const { return name_ + ".dat"; }

  // Writes NAME.dat and NAME.gp; returns the script's path.
  std::string Write(const std::string& png_terminal, int width, int height) const;

 private:
  std::string folder_, name_;
  std::ostringstream dat_, body_;
};

// The PNG terminal of `gnuplot` (pngcairo, else png); "" with *message set
// when gnuplot does not run.
std::string PngTerminal(const std::string& gnuplot, std::string* message);

// Runs `gnuplot NAME.gp` in the script's folder; false with *message set
// (gnuplot's output) when it fails.
bool RenderFigure(const std::string& script, const std::string& gnuplot, std::string* message);

// A title or label shown as written: 'text' noenhanced.
std::string GnuplotText(const std::string& text);
// `set logscale AXIS` with its (decade) ticks labelled as powers of ten.
std::string GnuplotLogAxis(const std::string& axis);
// Renders every script of *f unless options.render is false; sets
// f->terminal, f->rendered, f->message.
void RenderFigures(const FiguresOptions& options, FiguresSummary* f);
// The PNG terminal to write into the scripts: PngTerminal's, or pngcairo
// (with *message set) when gnuplot does not run or rendering is off.
std::string ScriptTerminal(const FiguresOptions& options, std::string* message);

// 'text' quoted for a gnuplot string (ShellQuote, for the shell, is in
// src/io/shell.h).
std::string GnuplotQuote(const std::string& text);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_GNUPLOT_FIGURE_H_
