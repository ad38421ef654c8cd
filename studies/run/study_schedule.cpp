#include "studies/run/study_schedule.h"

#include <algorithm>
#include <numeric>
#include <variant>

namespace estlab {

namespace {

constexpr double kTuningIterations = 100.0;

int OutputsOf(const ScenarioConfig& sc, const Combo& cb) {
  for (const MeasurementDesc& d : sc.model->measurements)
    if (d.name == cb.spec.measurement) return int(d.outputs.size());
  return 1;
}

double Rows(const ScenarioConfig& sc, int run) {
  if (sc.recorded && run >= 0 && size_t(run) < sc.data_runs.size())
    return double(sc.data_runs[size_t(run)].t.size());
  return double(sc.steps);
}

}  // namespace

double ComboStepCost(const ScenarioConfig& sc, const Combo& cb) {
  const double size = double(sc.model->states.size()) + double(OutputsOf(sc, cb));
  double cost = size * size * size * double(std::max(cb.spec.transition.substeps, 0) + 1);
  if (const auto* pf = std::get_if<ParticleOptions>(&cb.spec.filter))
    cost *= std::max(1.0, double(pf->num_particles) / 10.0);
  return cost;
}

double RunCost(const ScenarioConfig& sc, int run) {
  double per_row = 0.0;
  for (const Combo& cb : sc.combos)
    per_row += ComboStepCost(sc, cb) * (cb.tune_per_run ? kTuningIterations : 1.0);
  return Rows(sc, run) * per_row;
}

double TuningCost(const ScenarioConfig& sc, const Combo& cb) {
  double rows = 0.0;
  if (sc.recorded)
    for (const FilterData& d : sc.tune_runs) rows += double(d.t.size());
  else
    rows = double(std::max(cb.tune_datasets, 1)) * double(sc.steps);
  return rows * ComboStepCost(sc, cb) * kTuningIterations;
}

std::vector<size_t> LongestFirst(const std::vector<double>& costs) {
  std::vector<size_t> order(costs.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return costs[a] > costs[b]; });
  return order;
}

}  // namespace estlab
