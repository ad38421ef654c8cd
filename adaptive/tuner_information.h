// The observed Fisher information of the tuner's optimum (part of the tuner,
// adaptive/tuner_impl.h) and what follows from it: standard errors,
// correlations, identifiability (adaptive/identifiability.h), the physical
// parameters on their natural scale.
//
//   H = differences of the exact gradient at the optimum (step
//   options.hessian_step; one-sided at a bound), symmetrised; cov = H^-1 on
//   the identifiable directions; SE_i = sqrt(cov_ii).
#ifndef ESTLAB_ADAPTIVE_TUNER_INFORMATION_H_
#define ESTLAB_ADAPTIVE_TUNER_INFORMATION_H_

#include <Eigen/Core>
#include <algorithm>
#include <limits>
#include <vector>

#include "adaptive/identifiability.h"
#include "adaptive/tuner.h"
#include "adaptive/tuner_objective.h"

namespace estlab {
namespace tuner_internal {

// The observed Fisher information: H_ij = d g_j / d theta_i by differences
// of the exact gradient g, central inside the box and one-sided where theta_i
// is within a step of a bound (no point outside the box is evaluated); false
// when the filter fails within a step of theta.
template <class Model, class Meas>
bool ObservedFisher(const Objective<Model, Meas>& objective, const std::vector<double>& theta,
                    double step, const std::vector<double>& lower, const std::vector<double>& upper,
                    Eigen::MatrixXd* fisher) {
  const int k = objective.NumParams();
  Eigen::MatrixXd& H = *fisher;
  H.setZero(k, k);
  std::vector<double> plus(k), minus(k), x(theta);
  double f = 0.0;
  for (int i = 0; i < k; ++i) {
    const double hi = std::min(theta[i] + step, upper[i]);
    const double lo = std::max(theta[i] - step, lower[i]);
    if (!(hi > lo)) return false;  // a box narrower than the step
    x[i] = hi;
    if (!objective.ValueAndGradient(x.data(), &f, plus.data())) return false;
    x[i] = lo;
    if (!objective.ValueAndGradient(x.data(), &f, minus.data())) return false;
    x[i] = theta[i];
    for (int j = 0; j < k; ++j) H(i, j) = (plus[j] - minus[j]) / (hi - lo);
  }
  return H.allFinite();
}

// Standard errors, correlations and the identifiability sentences
// (adaptive/identifiability.h), and the physical parameters on their
// natural scale.
// The estimated initial states (TuneResult::x0 rows and their SEs) and the
// tuned spec's x0 (the first row's; first-sample no longer applies to it).
template <class Model, class Meas>
void FillInitialStates(const InnovationLikelihood<Model, Meas>& lik, TuneResult* result) {
  const InitialStates& x0s = lik.initial_states();
  if (x0s.empty()) return;
  const auto states = likelihood_internal::StateNames<Model>();
  for (int i : x0s.index) result->x0_names.push_back(states[i]);
  int at = lik.FirstX0Param();
  for (int row = 0; row < x0s.rows; ++row) {
    const auto start = lik.PriorMeanAt(result->theta_initial.data(), size_t(row));
    const auto x = lik.PriorMeanAt(result->theta.data(), size_t(row));
    std::vector<double> se(x.size(), std::numeric_limits<double>::quiet_NaN());
    for (int i : x0s.index) se[i] = result->std_errors[at++];
    result->x0_initial.emplace_back(start.data(), start.data() + start.size());
    result->x0.emplace_back(x.data(), x.data() + x.size());
    result->x0_std_errors.push_back(se);
  }
  result->tuned_spec.x0 = result->x0.front();
  result->tuned_spec.x0_first_sample = false;
}

template <class Model, class Meas>
void FillUncertainty(const Objective<Model, Meas>& objective, const TunerOptions& options,
                     const Eigen::MatrixXd& H, TuneResult* result) {
  const int k = objective.NumParams();
  if (!options.compute_std_errors) {
    result->std_errors.assign(k, kInf);
    result->identifiability.push_back("standard errors not computed (compute_std_errors off)");
  } else {
    FisherReport report =
        AnalyseFisher(H, result->theta, result->names, result->is_log, result->theta_initial);
    result->std_errors = report.std_errors;
    result->correlation = report.correlation;
    result->fisher_eigenvalues = report.eigenvalues;
    result->identifiability = report.sentences;
    result->hessian_positive_definite = report.positive_definite;
  }
  const auto& phys = objective.likelihood().physical();
  const int first = objective.likelihood().NumNoiseParams();
  if (!phys.empty()) {  // every parameter, defaults filled in
    const typename Model::Params nominal = ParamsFromVector<Model>(result->tuned_spec.params);
    result->tuned_spec.params.clear();
    for (const auto& spec : Model::kParams)
      result->tuned_spec.params.push_back(nominal.*spec.member);
  }
  for (int j = 0; j < phys.NumParams(); ++j) {
    const int i = first + j;
    result->param_names.push_back(Model::kParams[phys.ModelIndex(j)].name);
    result->param_initial.push_back(phys.Natural(j, result->theta_initial[i]));
    const double value = phys.Natural(j, result->theta[i]);
    result->param_values.push_back(value);
    result->param_std_errors.push_back(phys.IsLog(j) ? value * result->std_errors[i]
                                                     : result->std_errors[i]);
    result->tuned_spec.params[phys.ModelIndex(j)] = value;
  }
  FillInitialStates(objective.likelihood(), result);
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNER_INFORMATION_H_
