#include "src/cli/tune_profile.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "src/core/params.h"
#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/io/output_file.h"
#include "studies/report/gnuplot_figure.h"

namespace estlab::cli {
namespace {

constexpr double kHalfChi2 = 1.920729410347062;  // chi2_1(0.95) / 2

// Where Delta crosses kHalfChi2 between grid points i and i + 1.
double Crossing(const ProfileResult& p, size_t i, double optimum) {
  const double d0 = p.nll[i] - optimum, d1 = p.nll[i + 1] - optimum;
  const double f = (kHalfChi2 - d0) / (d1 - d0);
  return p.values[i] + f * (p.values[i + 1] - p.values[i]);
}

}  // namespace

ProfileRequest ParseProfileRequest(const std::string& text) {
  ProfileRequest r;
  const size_t eq = text.find('=');
  r.name = Trim(text.substr(0, eq));
  if (r.name.empty()) throw InputError("--profile: expected NAME[=LO:HI[:N]], got '" + text + "'");
  if (eq == std::string::npos) return r;
  std::vector<std::string> parts;
  std::stringstream ss(text.substr(eq + 1));
  for (std::string part; std::getline(ss, part, ':');) parts.push_back(Trim(part));
  if (parts.size() < 2 || parts.size() > 3)
    throw InputError("--profile: expected NAME=LO:HI[:N], got '" + text + "'");
  r.has_range = true;
  r.lo = ParseNumber(parts[0], "--profile " + r.name);
  r.hi = ParseNumber(parts[1], "--profile " + r.name);
  if (!(r.lo < r.hi))
    throw InputError("--profile " + r.name + ": LO " + parts[0] + " is not below HI " + parts[1]);
  if (parts.size() == 3) {
    const long n = ParseInteger(parts[2], "--profile " + r.name + " N", 3);
    if (n > kMaxProfilePoints)
      throw InputError("--profile " + r.name + ": N = " + parts[2] + " points exceeds " +
                       std::to_string(kMaxProfilePoints) + " (each point is a full re-fit)");
    r.points = int(n);
  }
  return r;
}

void CheckProfileRequest(const ModelEntry& model, const ProfileRequest& request) {
  if (!request.has_range) return;  // the default range stays inside the constraint
  for (const ParamDesc& d : model.params) {
    if (d.name != request.name) continue;
    for (const double v : {request.lo, request.hi}) {  // a line: its ends decide
      try {
        CheckConstraint(model.name, d.name.c_str(), v, d.constraint);
      } catch (const InputError& e) {
        throw InputError("--profile " + request.name + "=" + FormatNumber(request.lo) + ":" +
                         FormatNumber(request.hi) + ": the grid leaves the parameter's range (" +
                         e.what() + ")");
      }
    }
  }
}

ProfileResult ProfileLikelihood(const ModelEntry& model, const TunerOptions& options,
                                const std::vector<FilterData>& datasets, const TuneResult& best,
                                const ProfileRequest& request) {
  int j = -1;
  for (size_t i = 0; i < best.param_names.size(); ++i)
    if (best.param_names[i] == request.name) j = int(i);
  if (j < 0) throw InputError("--profile: '" + request.name + "' is not in --estimate-param");
  int index = -1;
  for (size_t i = 0; i < model.params.size(); ++i)
    if (model.params[i].name == request.name) index = int(i);

  ProfileResult p;
  p.name = request.name;
  p.estimate = best.param_values[j];
  p.nll_optimum = best.nll_tuned;
  double lo = request.lo, hi = request.hi;
  if (!request.has_range) {
    const double se = best.param_std_errors[j];
    const bool positive = model.params[index].constraint == Constraint::kPositive;
    if (std::isfinite(se) && se > 0) {
      lo = p.estimate - 4.0 * se;
      hi = p.estimate + 4.0 * se;
      if (positive) lo = std::max(lo, p.estimate / 4.0);
      if (model.params[index].constraint == Constraint::kNonNegative) lo = std::max(lo, 0.0);
    } else {
      lo = p.estimate / 2.0;
      hi = p.estimate * 2.0;
    }
  }
  // The rest start from the joint optimum: its noise and parameters.
  FilterSpec fixed = best.tuned_spec;
  TunerOptions rest = options;
  rest.estimate.erase(rest.estimate.begin() + j);
  rest.starts = 1;
  rest.compute_std_errors = false;
  for (int i = 0; i < request.points; ++i) {
    const double v = lo + (hi - lo) * i / (request.points - 1);
    fixed.params[index] = v;
    p.values.push_back(v);
    try {
      const TuneResult r = model.tune(fixed, rest, datasets);
      p.nll.push_back(r.IsSolutionUsable() ? r.nll_tuned : std::numeric_limits<double>::infinity());
      p.status.push_back(TuneStatusName(r.status));
    } catch (const InputError& e) {  // e.g. a value outside the parameter's constraint
      p.nll.push_back(std::numeric_limits<double>::infinity());
      p.status.push_back(std::string("invalid: ") + e.what());
    }
  }
  // The 95 % interval around the grid's minimum.
  const size_t best_i = size_t(std::min_element(p.nll.begin(), p.nll.end()) - p.nll.begin());
  const double optimum = std::min(p.nll_optimum, p.nll[best_i]);
  p.ci_lo = p.ci_hi = std::numeric_limits<double>::quiet_NaN();
  for (size_t i = best_i; i-- > 0;) {
    if (p.nll[i] - optimum > kHalfChi2) {
      p.ci_lo = std::isfinite(p.nll[i]) ? Crossing(p, i, optimum) : p.values[i + 1];
      break;
    }
  }
  for (size_t i = best_i + 1; i < p.nll.size(); ++i) {
    if (p.nll[i] - optimum > kHalfChi2) {
      p.ci_hi = std::isfinite(p.nll[i]) ? Crossing(p, i - 1, optimum) : p.values[i - 1];
      break;
    }
  }
  return p;
}

std::vector<std::string> WriteProfile(const ProfileResult& p, const std::string& prefix,
                                      std::string* render_message) {
  std::ostringstream csv;
  csv << p.name << ",nll,delta_nll,status\n";
  for (size_t i = 0; i < p.values.size(); ++i) {
    csv << FormatDouble(p.values[i]) << "," << FormatDouble(p.nll[i]) << ","
        << FormatDouble(p.nll[i] - p.nll_optimum) << "," << p.status[i] << "\n";
  }
  WriteTextFile(prefix + ".csv", csv.str());

  const std::filesystem::path path(prefix);
  const std::string folder = path.parent_path().empty() ? "." : path.parent_path().string();
  GnuplotFigure fig(folder, path.filename().string());
  fig.dat() << "# " << p.name << " delta_nll\n";
  for (size_t i = 0; i < p.values.size(); ++i)
    if (std::isfinite(p.nll[i]))
      fig.dat() << FormatDouble(p.values[i]) << " " << FormatDouble(p.nll[i] - p.nll_optimum)
                << "\n";
  fig.body() << "  set title " << GnuplotText("profile likelihood of " + p.name) << "\n"
             << "  set key inside top center\n  set format x '%.6g'\n  set xtics rotate by -30\n"
             << "  set xlabel " << GnuplotText(p.name) << "\n"
             << "  set ylabel 'NLL - NLL(optimum)'\n"
             << "  set arrow from first " << FormatDouble(p.estimate) << ", graph 0 to first "
             << FormatDouble(p.estimate) << ", graph 1 nohead dt 2\n"
             << "  plot " << GnuplotQuote(fig.dat_name())
             << " using 1:2 with linespoints pt 7 title 'profile', " << FormatDouble(kHalfChi2)
             << " with lines dt 3 title '95 % (chi2_1 / 2 = 1.92)'\n";
  const std::string term = PngTerminal("gnuplot", render_message);
  const std::string script = fig.Write(term.empty() ? "pngcairo" : term, 800, 500);
  std::vector<std::string> wrote = {prefix + ".csv", script};
  if (!term.empty() && RenderFigure(script, "gnuplot", render_message)) {
    wrote.push_back(prefix + ".png");
    wrote.push_back(prefix + ".svg");
  }
  return wrote;
}

}  // namespace estlab::cli
