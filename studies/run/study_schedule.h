// The order a study's task pool starts its tasks in (src/core/task_pool.h:
// a free worker takes the first ready task of the order): long tasks first,
// so that on many workers the last tasks to finish are short ones. Only the
// order of starting: the study's files are written in run order and never
// depend on it. studies/run/study_runner.cpp orders the tunings by cost, and
// the runs by cost within each scenario (recorded runs differ in length).
//
// Expected cost (a guess for scheduling, in filter steps of one state):
//   filter step  c = (n + m)^3, x particles / 10 for a particle filter,
//                x (substeps + 1) of the filter's transition
//   run          rows x sum over its combos of c, x 100 for a combo that
//                tunes on each run (tune-per-run)
//   tuning       tune datasets x steps x c x 100 (iterations of the tuner)
//
// Usage:
//   std::vector<size_t> order = LongestFirst(costs);   // costs per task
#ifndef ESTLAB_STUDIES_RUN_STUDY_SCHEDULE_H_
#define ESTLAB_STUDIES_RUN_STUDY_SCHEDULE_H_

#include <cstddef>
#include <vector>

#include "studies/config/study_config.h"

namespace estlab {

// The expected cost of one step of `cb` in scenario `sc`.
double ComboStepCost(const ScenarioConfig& sc, const Combo& cb);
// Run `run` of scenario `sc`: its rows times its combos' step costs.
double RunCost(const ScenarioConfig& sc, int run);
// Tuning combo `cb` of scenario `sc` before the runs.
double TuningCost(const ScenarioConfig& sc, const Combo& cb);
// The tasks 0..costs.size()-1, costliest first; equal costs keep their
// index order.
std::vector<size_t> LongestFirst(const std::vector<double>& costs);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_STUDY_SCHEDULE_H_
