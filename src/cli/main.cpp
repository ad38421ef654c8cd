// estlab: nonlinear state estimation from one command line.
#include <boost/program_options/errors.hpp>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <new>
#include <string>
#include <vector>

#include "estlab_version.h"
#include "src/cli/commands.h"
#include "src/core/types.h"
#include "src/io/temp_files.h"
#include "src/registry/model_plugin.h"

namespace {

struct Command {
  const char* name;
  const char* summary;
  std::function<int(const std::vector<std::string>&)> run;
};

const std::vector<Command>& Commands() {
  static const std::vector<Command> commands = {
      {"simulate", "integrate a model (CVODES or fixed step), add noise, write a CSV",
       estlab::cli::RunSimulate},
      {"filter", "run KF, EKF/IEKF, UKF/CKF/GHKF (optionally adaptive) or PF over a data CSV",
       estlab::cli::RunFilterCommand},
      {"smooth", "run a filter, then its smoother (RTS, ERTS, URTS, ..., particle FFBSi)",
       estlab::cli::RunSmoothCommand},
      {"tune", "tune Q and R by maximum innovation likelihood (Ceres), validate",
       estlab::cli::RunTune},
      {"study", "run a Monte Carlo study from a config file", estlab::cli::RunStudyCommand},
      {"merge", "join the result folders of a sharded study", estlab::cli::RunMerge},
      {"figures", "draw a study's figures with gnuplot", estlab::cli::RunFigures},
      {"list", "list models, measurements, parameters and integrators", estlab::cli::RunList},
      {"model", "check, build, show or write the sources of a model file (.model or C++ header)",
       estlab::cli::RunModel},
  };
  return commands;
}

void PrintUsage(std::ostream& out) {
  out << "estlab " << ESTLAB_VERSION << " - nonlinear state estimation research toolkit\n\n"
      << "Usage: estlab COMMAND [OPTIONS]\n       estlab COMMAND --help\n\nCommands:\n";
  for (const auto& c : Commands()) {
    out << "  " << c.name << std::string(12 - std::strlen(c.name), ' ') << c.summary << "\n";
  }
  out << "\nOptions:\n  --help       this text\n  --version    version and git commit\n"
      << "  --model-cache DIR   where model files are compiled to (else $ESTLAB_MODEL_CACHE,\n"
      << "               $XDG_CACHE_HOME/estlab or ~/.cache/estlab)\n\n"
      << "Examples:\n"
      << "  estlab list\n"
      << "  estlab simulate --model double-pendulum --x0 theta1=0.785398,theta2=0.523599 \\\n"
      << "      --t-end 10 --dt 0.01 --measure angles --meas-noise-var 0.0025,0.0016 --out "
         "traj.csv\n";
}

}  // namespace

int main(int argc, char** argv) {
  estlab::InstallTempFileCleanup();  // a Ctrl-C leaves no .estlab-*.tmp behind
  std::vector<std::string> args(argv + 1, argv + argc);
  // --model-cache DIR (anywhere): where model files' libraries are cached.
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] != "--model-cache") continue;
    if (i + 1 >= args.size()) {
      std::cerr << "estlab: error: --model-cache needs a folder\n";
      return 2;
    }
    estlab::SetModelCacheDir(args[i + 1]);
    args.erase(args.begin() + long(i), args.begin() + long(i) + 2);
    break;
  }
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    PrintUsage(std::cout);
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--version") {
    std::cout << "estlab " << ESTLAB_VERSION << " (git " << ESTLAB_GIT_COMMIT << ")\n";
    return 0;
  }
  const std::string name = args[0];
  args.erase(args.begin());
  for (const auto& c : Commands()) {
    if (c.name != name) continue;
    try {
      return c.run(args);
    } catch (const estlab::InputError& e) {
      std::cerr << "estlab: error: " << e.what() << "\n";
      return 2;
    } catch (const boost::program_options::error& e) {
      std::cerr << "estlab: error: " << e.what() << " (see 'estlab " << name << " --help')\n";
      return 2;
    } catch (const std::filesystem::filesystem_error& e) {
      // A folder or file that cannot be made or written (read-only, full,
      // a path through a file) is the environment's, as bad input is: the
      // user changes something and runs again. Exit 1 stays for numerical
      // failures, whose rows so far are kept.
      std::cerr << "estlab: error: " << e.what() << "\n";
      return 2;
    } catch (const std::bad_alloc&) {
      // A size no check caught (the known ones are refused, exit 2, before
      // anything is allocated): say what to look at, not "std::bad_alloc".
      std::cerr << "estlab: error: out of memory: a size given (data rows, particles, "
                   "smoother trajectories, starts, lags, grid points, study runs or steps) "
                   "needs more memory than this machine has; make it smaller\n";
      return 1;
    } catch (const std::exception& e) {
      std::cerr << "estlab: error: " << e.what() << "\n";
      return 1;
    }
  }
  std::cerr << "estlab: error: unknown command '" << name << "' (see 'estlab --help')\n";
  return 2;
}
