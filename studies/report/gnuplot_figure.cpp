#include "studies/report/gnuplot_figure.h"

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>

#include "src/io/output_file.h"
#include "src/io/shell.h"

namespace estlab {

std::string GnuplotFigure::Write(const std::string& png_terminal, int width, int height) const {
  WriteTextFile(folder_ + "/" + name_ + ".dat", dat_.str());
  std::ostringstream gp;
  gp << "# estlab figure; redraw with: gnuplot " << name_ << ".gp (in this folder)\n"
     << "# data: " << name_ << ".dat\n"
     << "do for [fmt in \"png svg\"] {\n"
     << "  if (fmt eq \"png\") {\n"
     << "    set terminal " << png_terminal << " enhanced size " << width << "," << height
     << "\n  } else {\n"
     << "    set terminal svg enhanced size " << width << "," << height << " dynamic\n"
     << "  }\n"
     << "  set output '" << name_ << ".'.fmt\n"
     << "  reset\n"
     << "  set grid\n"
     << "  set key outside right top noenhanced\n"
     << "  set format x '%h'\n"
     << "  set format y '%h'\n"
     << body_.str() << "  set output\n}\n";
  WriteTextFile(folder_ + "/" + name_ + ".gp", gp.str());
  return folder_ + "/" + name_ + ".gp";
}

std::string PngTerminal(const std::string& gnuplot, std::string* message) {
  std::string terminals;
  if (RunShell(gnuplot + " -e 'set terminal'", &terminals) != 0) {
    *message = "gnuplot ('" + gnuplot + "') did not run; the scripts are written";
    return "";
  }
  return terminals.find("pngcairo") == std::string::npos ? "png" : "pngcairo";
}

bool RenderFigure(const std::string& script, const std::string& gnuplot, std::string* message) {
  const std::filesystem::path path(script);
  const std::string folder = path.parent_path().empty() ? "." : path.parent_path().string();
  std::string log;
  const int status = RunShell(
      "cd " + ShellQuote(folder) + " && " + gnuplot + " " + ShellQuote(path.filename().string()),
      &log);
  if (status == 0) return true;
  *message = "gnuplot failed on " + script + ": " + log;
  return false;
}

std::string GnuplotText(const std::string& text) { return GnuplotQuote(text) + " noenhanced"; }

std::string GnuplotLogAxis(const std::string& axis) {
  return "  set logscale " + axis + "\n  set format " + axis + " '10^{%L}'\n";
}

std::string ScriptTerminal(const FiguresOptions& options, std::string* message) {
  if (!options.render) return "pngcairo";
  const std::string term = PngTerminal(options.gnuplot, message);
  return term.empty() ? "pngcairo" : term;
}

void RenderFigures(const FiguresOptions& options, FiguresSummary* f) {
  if (!options.render || !f->message.empty()) return;
  for (const auto& script : f->scripts)
    if (!RenderFigure(script, options.gnuplot, &f->message)) return;
  f->rendered = true;
}

std::string GnuplotQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

}  // namespace estlab
