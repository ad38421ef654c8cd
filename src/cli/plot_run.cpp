#include "src/cli/plot_run.h"

#include <iostream>

#include "studies/report/run_figures.h"

namespace estlab::cli {

bool PlotRun(const ModelEntry& model, const MeasurementDesc& meas, const FilterData& data,
             const FilterRunOutput& run, const PlotRequest& request) {
  RunFigureInput in;
  in.title = model.name + ": " + request.what;
  in.columns = run.columns;
  in.rows = run.rows;
  for (size_t i = 0; i < model.states.size(); ++i)
    in.state_units.emplace_back(model.states[i], model.state_units[i]);
  in.outputs = meas.outputs;
  in.meas_t = data.t;
  in.meas_z = data.z;
  in.objective_history = request.history;
  in.objective_name = request.objective;
  if (request.simulation != nullptr) {
    in.sim_y = request.simulation->y;
    in.sim_e = request.simulation->e;
    in.sim_rmse = request.simulation->rmse;
    in.sim_title = model.name + ": " + request.sim_what;
  }
  const FiguresSummary f = DrawRunFigures(in, request.dir, FiguresOptions{});
  if (!request.json)
    std::cout << "figures         " << f.scripts.size() << " in " << request.dir
              << (f.rendered ? " (png via " + f.terminal + ", svg)" : "") << "\n";
  if (f.message.empty()) return true;
  std::cerr << "estlab: error: figures: " << f.message << "\n";
  return false;
}

}  // namespace estlab::cli
