// Prediction-error maximum likelihood (`estlab tune --estimator ml`,
// Estimator::kMl): the innovation NLL of adaptive/likelihood.h minimised from
// every start point (the initial guess and a Latin hypercube,
// tuner_starts.h) by the solver of TunerOptions::solver (tuner_drivers.h),
// the best start kept, its Hessian, standard errors and identifiability
// computed (tuner_result.h, tuner_information.h) and the verdict applied
// (tune_verdict.h). Include only through adaptive/tuner_impl.h.
#ifndef ESTLAB_ADAPTIVE_ML_H_
#define ESTLAB_ADAPTIVE_ML_H_

#include "adaptive/tune_problem.h"
#include "adaptive/tune_verdict.h"
#include "adaptive/tuner_objective.h"
#include "adaptive/tuner_result.h"
#include "adaptive/tuner_starts.h"

namespace estlab {
namespace tuner_internal {

template <class Model, class Meas>
void RunMl(const Objective<Model, Meas>& objective, const TuneProblem& p, TuneResult* result) {
  const TunerOptions& options = p.options;
  result->solver = MlSolverName(options.solver);
  if (result->theta_initial.empty()) {
    NothingToTune(result);
  } else {
    const auto points = StartPoints(options, result->theta_initial, p.spread, p.lower, p.upper);
    RunStarts(objective, p.spec, options, p.datasets, points, p.lower, p.upper, &result->starts);
  }
  if (!PickBest(result)) return;
  const Eigen::MatrixXd H = FinishTune(objective, p.spec, options, p.lower, p.upper, result);
  ApplyVerdict(H, p.lower_is_constraint, p.lower, p.upper, NllFunction(objective), result);
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_ML_H_
