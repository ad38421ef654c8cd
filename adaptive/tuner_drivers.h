// The tuner's optimisers (part of the tuner, adaptive/tuner_impl.h), one
// start each: the projected L-BFGS of adaptive/bounded_lbfgs.h and Ceres'
// Levenberg-Marquardt with bounded parameter blocks. Neither evaluates a point
// outside the bounds; both record the NLL at every accepted iterate with the
// iterate (TuneStart::trace, trace_theta) and forward it to
// TunerOptions::progress.
#ifndef ESTLAB_ADAPTIVE_TUNER_DRIVERS_H_
#define ESTLAB_ADAPTIVE_TUNER_DRIVERS_H_

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>
#include <vector>

#include "adaptive/bounded_lbfgs.h"
#include "adaptive/tuner.h"
#include "adaptive/tuner_objective.h"

namespace estlab {
namespace tuner_internal {

// Forwards every successful Ceres iteration (after the zeroth, the start
// point) to start->trace with its point (update_state_every_iteration) and
// to TunerOptions::progress. The value is the NLL there, evaluated anew
// (nll(theta)): the least-squares cost is the NLL only up to a constant and
// the Jets' rounding.
class ProgressCallback final : public ceres::IterationCallback {
 public:
  ProgressCallback(const TunerOptions& o, const TuneProgress& where, const double* theta, int k,
                   std::function<double(const double*)> nll, TuneStart* start)
      : o_(o), where_(where), theta_(theta), k_(k), nll_(std::move(nll)), start_(start) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (it.iteration > 0 && it.step_is_successful) {
      const double value = nll_(theta_);
      const double change = value - start_->trace.back();
      start_->trace.push_back(value);
      start_->trace_theta.emplace_back(theta_, theta_ + k_);
      if (o_.progress) {
        where_.iteration = it.iteration;
        where_.value = value;
        where_.change = change;
        o_.progress(where_);
      }
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const TunerOptions& o_;
  TuneProgress where_;
  const double* theta_;
  int k_;
  std::function<double(const double*)> nll_;
  TuneStart* start_;
};

// One L-BFGS start from theta (inside the box): the projected L-BFGS of
// adaptive/bounded_lbfgs.h on the NLL, its accepted values in *trace.
template <class Model, class Meas>
TuneStart RunLbfgs(const Objective<Model, Meas>& objective, const TunerOptions& o,
                   const std::vector<double>& lower, const std::vector<double>& upper,
                   std::vector<double> theta, bool* converged, const TuneProgress& where) {
  TuneStart start;
  start.theta_start = theta;
  BoundedLbfgsOptions bo;
  bo.max_iterations = o.max_iterations;
  bo.function_tolerance = o.function_tolerance;
  bo.gradient_tolerance = o.gradient_tolerance;
  bo.parameter_tolerance = o.parameter_tolerance;
  auto f = [&](const double* x, double* value, double* gradient) {
    return objective.ValueAndGradient(x, value, gradient);
  };
  TuneProgress at = where;
  start.trace_theta = {theta};
  auto callback = [&](int iteration, const std::vector<double>& x, double value, double change) {
    start.trace.push_back(value);
    start.trace_theta.push_back(x);
    if (!o.progress) return;
    at.iteration = iteration, at.value = value, at.change = change;
    o.progress(at);
  };
  const BoundedLbfgsSummary summary = MinimizeBounded(f, lower, upper, bo, &theta, callback);
  start.theta_end = theta;
  start.termination = summary.message;
  start.iterations = summary.iterations;
  start.nll_scaled = summary.usable ? summary.initial_cost : kInf;
  start.trace.insert(start.trace.begin(), start.nll_scaled);
  start.ok = summary.usable;
  start.nll_end = summary.usable ? summary.final_cost : kInf;
  start.converged = *converged = summary.converged;
  return start;
}

// The Levenberg-Marquardt settings of the least-squares form (and ALS).
inline ceres::Solver::Options LevenbergMarquardtOptions(const TunerOptions& o) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = o.function_tolerance;
  so.gradient_tolerance = o.gradient_tolerance;
  so.parameter_tolerance = o.parameter_tolerance;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  return so;
}

// The finite bounds on the parameter block theta.
inline void SetBounds(const std::vector<double>& lower, const std::vector<double>& upper,
                      double* theta, ceres::Problem* problem) {
  for (size_t i = 0; i < lower.size(); ++i) {
    if (std::isfinite(lower[i])) problem->SetParameterLowerBound(theta, int(i), lower[i]);
    if (std::isfinite(upper[i])) problem->SetParameterUpperBound(theta, int(i), upper[i]);
  }
}

template <class Model, class Meas>
TuneStart RunLeastSquares(const Objective<Model, Meas>& objective, const TunerOptions& o,
                          const std::vector<double>& lower, const std::vector<double>& upper,
                          std::vector<double> theta, int num_meas, bool* converged,
                          const TuneProgress& where) {
  TuneStart start;
  start.theta_start = theta;
  *converged = false;
  double min_log_det = 0.0;
  if (!objective.MinLogDet(theta.data(), &min_log_det) ||
      !objective.Value(theta.data(), &start.nll_scaled)) {
    start.nll_scaled = start.nll_end = kInf;
    start.theta_end = theta;
    start.termination = "the filter failed at the start point";
    return start;
  }
  const double c = std::max(0.0, o.log_det_margin * num_meas - min_log_det);
  ceres::Problem problem;
  problem.AddResidualBlock(new LeastSquaresCost<Model, Meas>(objective, c), nullptr, theta.data());
  SetBounds(lower, upper, theta.data(), &problem);
  start.trace = {start.nll_scaled};
  start.trace_theta = {theta};
  auto nll = [&](const double* x) {
    double f = kInf;
    return objective.Value(x, &f) ? f : kInf;
  };
  ProgressCallback progress(o, where, theta.data(), int(theta.size()), nll, &start);
  ceres::Solver::Options so = LevenbergMarquardtOptions(o);
  so.update_state_every_iteration = true;
  so.callbacks.push_back(&progress);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  start.theta_end = theta;
  start.termination = summary.message;
  start.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  start.ok = summary.IsSolutionUsable() && objective.Value(theta.data(), &start.nll_end) &&
             std::isfinite(start.nll_end);
  if (!start.ok) start.nll_end = kInf;
  start.converged = *converged = summary.termination_type == ceres::CONVERGENCE;
  return start;
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNER_DRIVERS_H_
