// One gnuplot figure: NAME.dat (the numbers), NAME.gp (the script, which
// draws NAME.png and NAME.svg: `cd FOLDER && gnuplot NAME.gp` redraws it),
// and rendering with the gnuplot found on this machine. Used by the study
// figures (study_figures.h) and by `estlab tune --profile`.
//
// Usage:
//   GnuplotFigure fig("results", "profile_L");
//   fig.dat() << "# L nll\n0.15 -3.1e5\n";
//   fig.body() << "  plot 'profile_L.dat' using 1:2 with linespoints\n";
//   std::string message;
//   const std::string term = PngTerminal("gnuplot", &message);  // "" + message if none
//   const std::string script = fig.Write(term.empty() ? "png" : term, 800, 500);
//   if (!term.empty()) RenderFigure(script, "gnuplot", &message);
#ifndef ESTLAB_STUDIES_GNUPLOT_FIGURE_H_
#define ESTLAB_STUDIES_GNUPLOT_FIGURE_H_

#include <sstream>
#include <string>

namespace estlab {

class GnuplotFigure {
 public:
  GnuplotFigure(std::string folder, std::string name)
      : folder_(std::move(folder)), name_(std::move(name)) {}
  std::ostringstream& dat() { return dat_; }
  // The plotting commands, run once per format (png, svg) after `reset`,
  // `set grid` and `set key outside right top`.
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

// 'text' quoted for a gnuplot string; "text" quoted for the shell.
std::string GnuplotQuote(const std::string& text);
std::string ShellQuote(const std::string& text);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_GNUPLOT_FIGURE_H_
