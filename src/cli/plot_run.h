// `--plot DIR` of estlab filter, smooth and tune: one run's figures
// (studies/report/run_figures.h) from the run's rows, its data and its model.
//
// Usage:
//   PlotRequest plot{.dir = "plots", .what = "ekf on d.csv"};
//   if (!PlotRun(model, meas, data, run, plot)) return 1;
#ifndef ESTLAB_SRC_CLI_PLOT_RUN_H_
#define ESTLAB_SRC_CLI_PLOT_RUN_H_

#include <string>
#include <vector>

#include "src/registry/registry.h"
#include "src/run/filter_spec.h"
#include "studies/run/output_error.h"

namespace estlab::cli {

struct PlotRequest {
  std::string dir = {};
  std::string what = {};             // the title after the model's name: "ekf on d.csv"
  std::vector<double> history = {};  // the tuner's objective from its start point (or empty)
  std::string objective = "NLL";
  bool json = false;  // --json: nothing on stdout
  // tune --plot: the free simulation on the same data (free-simulation
  // figure) and its title after the model's name ("free simulation on
  // v.csv from x0 = (h1 = 0.1, ...)").
  const FreeSimulation* simulation = nullptr;
  std::string sim_what = {};
};

// Draws the figures and prints "figures  N in DIR (png via T, svg)"; false,
// with the reason on stderr, when they could not be rendered.
bool PlotRun(const ModelEntry& model, const MeasurementDesc& meas, const FilterData& data,
             const FilterRunOutput& run, const PlotRequest& request);

}  // namespace estlab::cli

#endif  // ESTLAB_SRC_CLI_PLOT_RUN_H_
