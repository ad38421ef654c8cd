// The likelihood tuner: the innovation NLL of adaptive/likelihood.h minimised
// with bounds, multi-start, standard errors and a verdict. Split by concern:
//   tuner_objective.h    the NLL and its gradient, least-squares residuals
//   tuner_drivers.h      one start of L-BFGS or Levenberg-Marquardt
//   tuner_starts.h       bounds, start points, scale search, parallel starts
//   tuner_information.h  the Hessian, standard errors, identifiability
//   tuner_result.h       the tuned spec and flags once the optimum is known
//   tune_verdict.h       whether the result may be called converged
//   ml.h, em.h, als.h    the estimators (adaptive/estimators.h), one each,
//                        on a TuneProblem (tune_problem.h)
// This file is the entry: TuneWith and TuneModel. Include only from the per-model
// instantiation units adaptive/tune_<model>.cpp and from tests; everything
// else reaches it through ModelEntry::tune (adaptive/tuner.h).
//
// Usage (what ModelEntry::tune does):
//   TuneResult r = TuneWith<models::Pendulum, models::Pendulum::Sin>(spec, options, data);
//
// Gradients and the least-squares residuals: adaptive/tuner_objective.h.
//
// Infeasible points. The objective returns false (the optimiser backs off)
// when the filter fails (Cholesky failure, non-finite value, trace(P) too
// large). Bounds: no point outside the box is ever evaluated, so no model
// sees a parameter outside its constraint. The L-BFGS form is the projected
// L-BFGS of adaptive/bounded_lbfgs.h; the least-squares form is Ceres'
// Levenberg-Marquardt, whose bounded parameter blocks clamp every candidate
// into the box. The Hessian takes one-sided differences at a bound. A
// parameter that ends at or near a bound is flagged at_bound (NearBound,
// adaptive/tune_verdict.h).
//
// Values reported. The trace (TuneResult::trace, TunerOptions::progress) is
// the NLL at each accepted iterate; for least squares it is the cost plus the
// constant that makes it the NLL (LeastSquaresCost), so both forms trace
// NLLs of admissible points.
//
// Verdict: the status is checked after the fit (adaptive/tune_verdict.h):
// worse than the start, a saddle, or against the search box are failures
// whatever the optimiser said.
//
// Standard errors: H = central differences of the exact gradient at the
// optimum (step options.hessian_step), symmetrised; cov = H^-1 by Cholesky
// solve; SE_i = sqrt(cov_ii), +inf for all when H is not positive definite.
#ifndef ESTLAB_ADAPTIVE_TUNER_IMPL_H_
#define ESTLAB_ADAPTIVE_TUNER_IMPL_H_

#include <chrono>
#include <string>
#include <vector>

#include "adaptive/als.h"
#include "adaptive/em.h"
#include "adaptive/likelihood.h"
#include "adaptive/ml.h"
#include "adaptive/tune_problem.h"
#include "adaptive/tuner.h"
#include "adaptive/tuner_objective.h"
#include "adaptive/tuner_starts.h"

namespace estlab {

template <class Model, class Meas>
TuneResult TuneWith(const FilterSpec& spec, const TunerOptions& options,
                    const std::vector<FilterData>& datasets) {
  using namespace tuner_internal;
  const auto clock_start = std::chrono::steady_clock::now();
  const InnovationLikelihood<Model, Meas> lik(spec, options, datasets);
  // the threads that the starts leave free run each gradient's passes
  const Objective<Model, Meas> objective(lik, std::max(1, options.jobs / std::max(1, options.starts)));
  const int k = lik.NumParams();

  TuneResult result;
  result.estimator = EstimatorName(options.estimator);
  result.names = lik.ParamNames();
  result.is_log = lik.ParamIsLog();
  result.theta_initial = lik.InitialTheta();
  result.q_param = options.q_param;
  result.r_param = lik.r_param().kind();
  if (lik.r_param().Blockwise()) result.r_param_groups = options.r_param_groups;
  if (lik.r_param().Blockwise() && options.estimator != Estimator::kMl) {
    throw InputError(std::string("--r-param: a kind per sensor group is for the ml estimator; ") +
                     EstimatorName(options.estimator) + " takes one kind for all of R");
  }
  result.dt_ref = lik.dt_ref();
  result.updates = lik.NumTerms();
  const int noise = lik.NumNoiseParams();
  for (int i = 0; i < k; ++i) result.is_physical.push_back(i >= noise);
  TuneProblem problem{.spec = spec,
                      .options = options,
                      .datasets = datasets,
                      .lower = {},
                      .upper = {},
                      .spread = {},
                      .lower_is_constraint = {}};
  LikelihoodBounds(lik, options, &problem.lower, &problem.upper);
  ParameterFacts(lik, options, problem.lower, problem.upper, &problem.spread,
                 &problem.lower_is_constraint);
  if (!lik.Nll(result.theta_initial.data(), &result.nll_initial) ||
      !std::isfinite(result.nll_initial))
    result.nll_initial = kInf;
  switch (options.estimator) {  // exhaustive: adaptive/estimators.h
    case Estimator::kMl:
      RunMl(objective, problem, &result);
      break;
    case Estimator::kEm:
      RunEm(objective, problem, &result);
      break;
    case Estimator::kAls:
      RunAls(objective, problem, &result);
      break;
    case Estimator::kOutputError:
      throw InputError(
          "the output-error estimator simulates (studies/run/output_error.h): it does not run "
          "through the tuner");
  }
  result.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return result;
}

// Dispatches on the measurement name.
template <class Model>
TuneResult TuneModel(const FilterSpec& spec, const TunerOptions& options,
                     const std::vector<FilterData>& datasets) {
  TuneResult result;
  const bool found = VisitMeasurement<Model>(spec.measurement, [&](auto m) {
    result = TuneWith<Model, decltype(m)>(spec, options, datasets);
  });
  if (!found) {
    throw InputError("unknown measurement '" + spec.measurement + "' for model '" +
                     std::string(Model::kName) + "'");
  }
  return result;
}

}  // namespace estlab

// The entry point of a model's tuner library compiled at run time
// (src/registry/model_plugin.cpp): the address of TuneModel<Model>.
#define ESTLAB_DEFINE_TUNER_PLUGIN(Model)                     \
  extern "C" estlab::TuneResult (*estlab_model_tuner_v1())(   \
      const estlab::FilterSpec&, const estlab::TunerOptions&, \
      const std::vector<estlab::FilterData>&) {               \
    return &estlab::TuneModel<Model>;                         \
  }

#endif  // ESTLAB_ADAPTIVE_TUNER_IMPL_H_
