// What every estimator of the tuner is handed (adaptive/estimators.h): the
// filter spec with the initial guess, the options, the datasets and the
// search box of theta, with the facts the multi-start and the verdict need.
// TuneWith (adaptive/tuner_impl.h) builds it once; each estimator is
//   void RunFoo(const Objective<Model, Meas>& objective, const TuneProblem& problem,
//               TuneResult* result);
// and fills the one TuneResult (its names, theta_initial and nll_initial
// are already set).
#ifndef ESTLAB_ADAPTIVE_TUNE_PROBLEM_H_
#define ESTLAB_ADAPTIVE_TUNE_PROBLEM_H_

#include <utility>
#include <vector>

#include "adaptive/tuner.h"

namespace estlab {

struct TuneProblem {
  const FilterSpec& spec;
  const TunerOptions& options;
  const std::vector<FilterData>& datasets;
  // The box of theta (LikelihoodBounds): no point outside is evaluated.
  std::vector<double> lower, upper;
  // Where the multi-start spreads each parameter, and whether a lower bound
  // stands for the parameter's constraint (ParameterFacts).
  std::vector<std::pair<double, double>> spread;
  std::vector<bool> lower_is_constraint;
};

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNE_PROBLEM_H_
