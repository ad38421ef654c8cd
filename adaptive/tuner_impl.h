// The likelihood tuner: Ceres on the innovation NLL of adaptive/likelihood.h,
// multi-start, bounds, standard errors. Include only from the per-model
// instantiation units adaptive/tune_<model>.cpp and from tests; everything
// else reaches it through ModelEntry::tune (adaptive/tuner.h).
//
// Usage (what ModelEntry::tune does):
//   TuneResult r = TuneWith<models::Pendulum, models::Pendulum::Sin>(spec, options, data);
//
// Gradients. The L-BFGS form (ceres::GradientProblemSolver) gets the exact
// gradient of the NLL by forward-mode AD: the recursion runs on
// ceres::Jet<double, C> with C = 2 (K <= 2) or 4 directions per pass; more
// than 4 parameters are done in ceil(K / 4) passes (chunking, as
// ceres::DynamicAutoDiffCostFunction does), so only two Jet sizes are
// instantiated per model and measurement (compile time on 2 cores). C = 4
// rather than 8: the single-pendulum joint fit (K = 4, EKF) took 5.3 s with
// one Jet<8> pass and 1.3 s with one Jet<4> pass (the nested Jets of the EKF
// grow with C times the state dimension). The EKF's Jacobians of the
// fixed-step map need second derivatives for that and use NestedJet
// (src/ode/nested_jet.h). With a CVODES process model the same Jets run
// through CVODES forward sensitivities in theta (src/ode/cvodes_theta_flow.h).
//
// The least-squares form (Levenberg-Marquardt, ceres::Solver with bounds)
// minimises 1/2 sum r^2 over the residuals
//   e_k = L_k^-1 nu_k   (m per update)   and   sqrt(log det S_k + c)  (one per update),
// which is NLL + const. c = log_det_margin * m - min_k log det S_k at the
// start point, kept while that start runs; a trial point where
// log det S_k + c <= 0 is infeasible. Its Jacobian uses the same chunked Jets.
//
// Infeasible points. Evaluate() returns false (Ceres backs off) when the
// filter fails (Cholesky failure, non-finite value, trace(P) too large).
// Bounds: the least-squares form has native bounds; for L-BFGS
// (GradientProblemSolver has none) the NLL is continued outside the box by a
// C^1 linear-plus-quadratic penalty and the result clamped (NllFunction). A
// parameter that ends at or near a bound is flagged at_bound (AtBound).
//
// Standard errors: H = central differences of the exact gradient at the
// optimum (step options.hessian_step), symmetrised; cov = H^-1 by Cholesky
// solve; SE_i = sqrt(cov_ii), +inf for all when H is not positive definite.
#ifndef ESTLAB_ADAPTIVE_TUNER_IMPL_H_
#define ESTLAB_ADAPTIVE_TUNER_IMPL_H_

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "adaptive/identifiability.h"
#include "adaptive/likelihood.h"
#include "adaptive/tuner.h"
#include "src/core/random.h"

namespace estlab {

namespace tuner_internal {

constexpr double kInf = std::numeric_limits<double>::infinity();

// NLL and its gradient / the least-squares residuals and their Jacobian, by
// chunked forward AD.
template <class Model, class Meas>
class Objective {
 public:
  static constexpr int kM = Meas::kDim;
  explicit Objective(const InnovationLikelihood<Model, Meas>& likelihood)
      : lik_(likelihood), k_(likelihood.NumParams()) {}

  int NumParams() const { return k_; }
  const InnovationLikelihood<Model, Meas>& likelihood() const { return lik_; }

  bool Value(const double* theta, double* nll) const { return lik_.Nll(theta, nll); }

  // NLL and gradient (gradient may be null).
  bool ValueAndGradient(const double* theta, double* nll, double* gradient) const {
    if (gradient == nullptr || k_ == 0) return Value(theta, nll);
    bool ok;
    if (k_ <= 2) {
      ok = ChunkedGradient<2>(theta, nll, gradient);
    } else {
      ok = ChunkedGradient<4>(theta, nll, gradient);
    }
    if (!ok) return false;
    for (int i = 0; i < k_; ++i)
      if (!std::isfinite(gradient[i])) return false;
    return std::isfinite(*nll);
  }

  // (m + 1) per update, then one per prior of a physical parameter.
  long NumResiduals() const { return lik_.NumTerms() * (kM + 1) + lik_.physical().NumPriors(); }

  // The least-squares residuals; jacobian (row-major NumResiduals x K) may be
  // null.
  bool Residuals(const double* theta, double c, double* residuals, double* jacobian) const {
    if (jacobian == nullptr || k_ == 0) return ResidualsT<double>(theta, c, residuals);
    if (k_ <= 2) return ChunkedResiduals<2>(theta, c, residuals, jacobian);
    return ChunkedResiduals<4>(theta, c, residuals, jacobian);
  }

  // min_k log det S_k at theta (for the constant c), false if the filter fails.
  bool MinLogDet(const double* theta, double* min_log_det) const {
    double lo = kInf;
    const bool ok = lik_.template Run<double>(
        theta, [&](const Vec<double, kM>&, const double& ld) { lo = std::min(lo, ld); });
    *min_log_det = lo;
    return ok && std::isfinite(lo);
  }

 private:
  template <int C>
  std::vector<ceres::Jet<double, C>> Seed(const double* theta, int first) const {
    std::vector<ceres::Jet<double, C>> th(k_);
    for (int i = 0; i < k_; ++i) {
      th[i] = ceres::Jet<double, C>(theta[i]);
      if (i >= first && i < first + C) th[i].v[i - first] = 1.0;
    }
    return th;
  }

  template <int C>
  bool ChunkedGradient(const double* theta, double* nll, double* gradient) const {
    for (int first = 0; first < k_; first += C) {
      const std::vector<ceres::Jet<double, C>> th = Seed<C>(theta, first);
      ceres::Jet<double, C> f;
      if (!lik_.Nll(th.data(), &f)) return false;
      *nll = f.a;
      for (int i = first; i < std::min(k_, first + C); ++i) gradient[i] = f.v[i - first];
    }
    return true;
  }

  template <class T>
  bool ResidualsT(const T* theta, double c, T* residuals) const {
    long at = 0;
    bool positive = true;
    const bool ok =
        lik_.template Run<T>(theta, [&](const Eigen::Matrix<T, kM, 1>& e, const T& log_det) {
          using std::sqrt;
          for (int j = 0; j < kM; ++j) residuals[at++] = e(j);
          const T arg = log_det + c;
          if (!(ScalarPart(arg) > 0)) positive = false;
          residuals[at++] = positive ? sqrt(arg) : T(0.0);
        });
    lik_.physical().ForEachPriorResidual(theta + lik_.NumNoiseParams(),
                                         [&](const T& r) { residuals[at++] = r; });
    return ok && positive && at == NumResiduals();
  }

  template <int C>
  bool ChunkedResiduals(const double* theta, double c, double* residuals, double* jacobian) const {
    const long rows = NumResiduals();
    std::vector<ceres::Jet<double, C>> r(rows);
    for (int first = 0; first < k_; first += C) {
      const std::vector<ceres::Jet<double, C>> th = Seed<C>(theta, first);
      if (!ResidualsT<ceres::Jet<double, C>>(th.data(), c, r.data())) return false;
      for (long row = 0; row < rows; ++row) {
        residuals[row] = r[row].a;
        for (int i = first; i < std::min(k_, first + C); ++i)
          jacobian[row * k_ + i] = r[row].v[i - first];
      }
    }
    for (long row = 0; row < rows; ++row)
      if (!std::isfinite(residuals[row])) return false;
    return true;
  }

  const InnovationLikelihood<Model, Meas>& lik_;
  int k_;
};

// L-BFGS objective. GradientProblemSolver has no bounds, so outside the box
// the NLL is continued C^1 from the nearest point theta_c = clamp(theta):
//   f(theta) = NLL(theta_c) + g(theta_c)^T d + mu/2 |d|^2,  d = theta - theta_c,
// whose minimiser lies at most |g| / mu outside the box; the result is then
// clamped. (Treating the box as infeasible instead stalls the line search on
// the first bound it meets.)
template <class Model, class Meas>
class NllFunction final : public ceres::FirstOrderFunction {
 public:
  static constexpr double kPenalty = 1e4;  // mu, NLL units per (log unit)^2
  NllFunction(const Objective<Model, Meas>& objective, const std::vector<double>& lower,
              const std::vector<double>& upper)
      : objective_(objective), lower_(lower), upper_(upper) {}
  bool Evaluate(const double* theta, double* cost, double* gradient) const override {
    const int k = NumParameters();
    std::vector<double> clamped(theta, theta + k);
    bool inside = true;
    for (int i = 0; i < k; ++i) {
      clamped[i] = std::clamp(theta[i], lower_[i], upper_[i]);
      inside = inside && clamped[i] == theta[i];
    }
    if (inside) return objective_.ValueAndGradient(theta, cost, gradient);
    std::vector<double> g(k);
    if (!objective_.ValueAndGradient(clamped.data(), cost, g.data())) return false;
    for (int i = 0; i < k; ++i) {
      const double d = theta[i] - clamped[i];
      *cost += g[i] * d + 0.5 * kPenalty * d * d;
      if (gradient != nullptr) gradient[i] = g[i] + kPenalty * d;
    }
    return true;
  }
  int NumParameters() const override { return objective_.NumParams(); }

 private:
  const Objective<Model, Meas>& objective_;
  std::vector<double> lower_, upper_;
};

// Levenberg-Marquardt cost: whitened innovations and log-det residuals.
template <class Model, class Meas>
class LeastSquaresCost final : public ceres::CostFunction {
 public:
  LeastSquaresCost(const Objective<Model, Meas>& objective, double c)
      : objective_(objective), c_(c) {
    set_num_residuals(int(objective.NumResiduals()));
    mutable_parameter_block_sizes()->push_back(objective.NumParams());
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    return objective_.Residuals(parameters[0], c_, residuals,
                                jacobians != nullptr ? jacobians[0] : nullptr);
  }

 private:
  const Objective<Model, Meas>& objective_;
  double c_;
};

// Resolves the bounds (see TunerOptions); throws InputError.
inline void ResolveBounds(const TunerOptions& o, const std::vector<double>& theta0,
                          const std::vector<bool>& is_log, std::vector<double>* lower,
                          std::vector<double>* upper) {
  const size_t k = theta0.size();
  auto pick = [&](const std::vector<double>& given, const char* which) {
    if (!given.empty() && given.size() != 1 && given.size() != k) {
      throw InputError(std::string(which) + " bounds: expected 1 or " + std::to_string(k) +
                       " values (one per tuned parameter), got " + std::to_string(given.size()));
    }
  };
  pick(o.log_lower, "lower");
  pick(o.log_upper, "upper");
  lower->assign(k, -kInf);
  upper->assign(k, kInf);
  for (size_t i = 0; i < k; ++i) {
    if (o.log_lower.size() == k) {
      (*lower)[i] = o.log_lower[i];
    } else if (is_log[i]) {
      (*lower)[i] = o.log_lower.size() == 1 ? o.log_lower[0] : theta0[i] - o.bound_width;
    }
    if (o.log_upper.size() == k) {
      (*upper)[i] = o.log_upper[i];
    } else if (is_log[i]) {
      (*upper)[i] = o.log_upper.size() == 1 ? o.log_upper[0] : theta0[i] + o.bound_width;
    }
    if ((*lower)[i] > (*upper)[i]) {
      throw InputError("bounds of parameter " + std::to_string(i + 1) + ": lower " +
                       FormatNumber((*lower)[i]) + " is above upper " + FormatNumber((*upper)[i]));
    }
  }
}

// Start points: theta0, then a Latin hypercube in theta0 +- spread on the log
// parameters, clamped into the bounds.
inline std::vector<std::vector<double>> StartPoints(const TunerOptions& o,
                                                    const std::vector<double>& theta0,
                                                    const std::vector<bool>& is_log,
                                                    const std::vector<double>& lower,
                                                    const std::vector<double>& upper) {
  const int k = int(theta0.size());
  std::vector<std::vector<double>> points(o.starts, theta0);
  const int extra = o.starts - 1;
  Rng rng(DeriveSeed({o.seed, uint64_t(k), 0x4c48u}));
  for (int d = 0; d < k && extra > 0; ++d) {
    std::vector<int> strata(extra);
    std::iota(strata.begin(), strata.end(), 0);
    for (int i = extra - 1; i > 0; --i) {  // Fisher-Yates
      const int j = int(rng.Uniform() * (i + 1));
      std::swap(strata[i], strata[std::min(j, i)]);
    }
    for (int s = 0; s < extra; ++s) {
      const double u = (strata[s] + rng.Uniform()) / extra;
      if (is_log[d]) points[s + 1][d] = theta0[d] - o.start_spread + 2.0 * o.start_spread * u;
    }
  }
  for (auto& p : points)
    for (int d = 0; d < k; ++d) p[d] = std::clamp(p[d], lower[d], upper[d]);
  return points;
}

// theta with Q and R (its first `noise` entries) scaled by e^s: log
// parameters + s, off-diagonal Cholesky entries * e^(s/2). The physical
// parameters after them stay.
inline std::vector<double> ScaleShifted(const std::vector<double>& theta,
                                        const std::vector<bool>& is_log, int noise, double s) {
  std::vector<double> out(theta);
  for (int i = 0; i < noise; ++i) out[i] = is_log[i] ? out[i] + s : out[i] * std::exp(0.5 * s);
  return out;
}

// The common-scale pre-search (TunerOptions::scale_search): returns the s in
// [-8, 8] (within the bounds) minimising NLL(ScaleShifted(theta, s)), 0 when
// no shifted point is better than theta itself.
template <class Model, class Meas>
double ScaleSearch(const Objective<Model, Meas>& objective, const std::vector<double>& theta,
                   const std::vector<bool>& is_log, int noise, const std::vector<double>& lower,
                   const std::vector<double>& upper) {
  double lo = -8.0, hi = 8.0;
  bool any_log = false;
  for (int i = 0; i < noise; ++i) {
    if (!is_log[i]) continue;
    any_log = true;
    lo = std::max(lo, lower[i] - theta[i]);
    hi = std::min(hi, upper[i] - theta[i]);
  }
  if (!any_log || !(lo < hi)) return 0.0;
  auto nll = [&](double s) {
    const std::vector<double> t = ScaleShifted(theta, is_log, noise, s);
    double f = kInf;
    return objective.Value(t.data(), &f) && std::isfinite(f) ? f : kInf;
  };
  double best_s = 0.0, best_f = (lo <= 0.0 && 0.0 <= hi) ? nll(0.0) : kInf;
  for (double s = std::ceil(lo); s <= hi; s += 1.0) {
    const double f = nll(s);
    if (f < best_f) best_f = f, best_s = s;
  }
  if (!std::isfinite(best_f)) return 0.0;
  // Golden section on [best_s - 1, best_s + 1].
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = std::max(lo, best_s - 1.0), b = std::min(hi, best_s + 1.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = nll(c), fd = nll(d);
  for (int it = 0; it < 30 && b - a > 1e-4; ++it) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - g * (b - a), fc = nll(c);
    } else {
      a = c, c = d, fc = fd, d = a + g * (b - a), fd = nll(d);
    }
  }
  const double s = fc < fd ? c : d;
  return std::min(fc, fd) < best_f ? s : best_s;
}

// Forwards every Ceres iteration (after the zeroth, the start point) to
// TunerOptions::progress, with `where` saying which start it is.
class ProgressCallback final : public ceres::IterationCallback {
 public:
  ProgressCallback(const TunerOptions& o, const TuneProgress& where) : o_(o), where_(where) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& it) override {
    if (it.iteration > 0 && o_.progress) {
      where_.iteration = it.iteration;
      where_.value = it.cost;
      where_.change = -it.cost_change;
      o_.progress(where_);
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const TunerOptions& o_;
  TuneProgress where_;
};

template <class Model, class Meas>
TuneStart RunLbfgs(const Objective<Model, Meas>& objective, const TunerOptions& o,
                   const std::vector<double>& lower, const std::vector<double>& upper,
                   std::vector<double> theta, bool* converged, const TuneProgress& where) {
  TuneStart start;
  start.theta_start = theta;
  ceres::GradientProblem problem(new NllFunction<Model, Meas>(objective, lower, upper));
  ProgressCallback progress(o, where);
  ceres::GradientProblemSolver::Options so;
  so.callbacks.push_back(&progress);
  so.line_search_direction_type = ceres::LBFGS;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = o.function_tolerance;
  so.gradient_tolerance = o.gradient_tolerance;
  so.parameter_tolerance = o.parameter_tolerance;
  so.logging_type = ceres::SILENT;
  ceres::GradientProblemSolver::Summary summary;
  ceres::Solve(so, problem, theta.data(), &summary);
  for (size_t i = 0; i < theta.size(); ++i) theta[i] = std::clamp(theta[i], lower[i], upper[i]);
  start.theta_end = theta;
  start.termination = summary.message;
  start.iterations = summary.iterations.empty() ? 0 : int(summary.iterations.size()) - 1;
  start.nll_start = summary.initial_cost;
  start.ok = summary.IsSolutionUsable() && objective.Value(theta.data(), &start.nll_end) &&
             std::isfinite(start.nll_end);
  if (!start.ok) start.nll_end = kInf;
  *converged = summary.termination_type == ceres::CONVERGENCE;
  return start;
}

// Whether theta ends at or near one of its bounds: within 0.1 on the log
// scale (a factor e^0.1 = 1.105 on the natural scale), within 1e-3 of the
// box width on the natural scale. An optimiser stopping by its tolerances
// lands short of a bound the likelihood pushes against (log q ending at
// -38.37 against -38.42), so "on the bound" alone misses it.
inline bool AtBound(double theta, double lower, double upper, bool is_log) {
  const double width = upper - lower;
  const double tol = is_log                 ? 0.1
                     : std::isfinite(width) ? 1e-3 * width
                                            : 1e-6 * std::max(1.0, std::abs(theta));
  return std::abs(theta - lower) <= tol || std::abs(theta - upper) <= tol;
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
      !objective.Value(theta.data(), &start.nll_start)) {
    start.nll_start = start.nll_end = kInf;
    start.theta_end = theta;
    start.termination = "the filter failed at the start point";
    return start;
  }
  const double c = std::max(0.0, o.log_det_margin * num_meas - min_log_det);
  ceres::Problem problem;
  problem.AddResidualBlock(new LeastSquaresCost<Model, Meas>(objective, c), nullptr, theta.data());
  SetBounds(lower, upper, theta.data(), &problem);
  ProgressCallback progress(o, where);
  ceres::Solver::Options so = LevenbergMarquardtOptions(o);
  so.callbacks.push_back(&progress);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  start.theta_end = theta;
  start.termination = summary.message;
  start.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  start.ok = summary.IsSolutionUsable() && objective.Value(theta.data(), &start.nll_end) &&
             std::isfinite(start.nll_end);
  if (!start.ok) start.nll_end = kInf;
  *converged = summary.termination_type == ceres::CONVERGENCE;
  return start;
}

// The observed Fisher information: H_ij = d g_j / d theta_i by central
// differences of the exact gradient g; false when the filter fails within a
// step of theta.
template <class Model, class Meas>
bool ObservedFisher(const Objective<Model, Meas>& objective, const std::vector<double>& theta,
                    double step, Eigen::MatrixXd* fisher) {
  const int k = objective.NumParams();
  Eigen::MatrixXd& H = *fisher;
  H.setZero(k, k);
  std::vector<double> plus(k), minus(k), x(theta);
  double f = 0.0;
  for (int i = 0; i < k; ++i) {
    x[i] = theta[i] + step;
    if (!objective.ValueAndGradient(x.data(), &f, plus.data())) return false;
    x[i] = theta[i] - step;
    if (!objective.ValueAndGradient(x.data(), &f, minus.data())) return false;
    x[i] = theta[i];
    for (int j = 0; j < k; ++j) H(i, j) = (plus[j] - minus[j]) / (2.0 * step);
  }
  return H.allFinite();
}

// Standard errors, correlations and the identifiability sentences
// (adaptive/identifiability.h), and the physical parameters on their
// natural scale.
template <class Model, class Meas>
void FillUncertainty(const Objective<Model, Meas>& objective, const TunerOptions& options,
                     TuneResult* result) {
  const int k = objective.NumParams();
  if (!options.compute_std_errors) {
    result->std_errors.assign(k, kInf);
    result->identifiability.push_back("standard errors not computed (compute_std_errors off)");
  } else {
    Eigen::MatrixXd H;
    if (!ObservedFisher(objective, result->theta, options.hessian_step, &H))
      H.setConstant(k, k, std::numeric_limits<double>::quiet_NaN());
    FisherReport report = AnalyseFisher(H, result->theta, result->names, result->is_log);
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
}

// The bounds of every parameter: Q's and R's (ResolveBounds about the
// initial guess), then the physical parameters'.
template <class Model, class Meas>
void LikelihoodBounds(const InnovationLikelihood<Model, Meas>& lik, const TunerOptions& options,
                      std::vector<double>* lower, std::vector<double>* upper) {
  const int noise = lik.NumNoiseParams();
  const std::vector<double> theta0 = lik.InitialTheta();
  const std::vector<bool> is_log = lik.ParamIsLog();
  ResolveBounds(options, std::vector<double>(theta0.begin(), theta0.begin() + noise),
                std::vector<bool>(is_log.begin(), is_log.begin() + noise), lower, upper);
  lik.physical().Bounds(lower, upper);
}

// `spec` with its Q (q, or q_white_accel and qc) and R replaced by those of
// theta; Q of a white-accel kind is qc Q_wa(dt) per step, the others are
// shown at dt_ref.
template <class Model, class Meas>
FilterSpec SpecAt(const InnovationLikelihood<Model, Meas>& lik, const FilterSpec& spec,
                  const double* theta) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const double* theta_q = theta;
  const double* theta_r = theta + lik.q_param().NumParams();
  const Mat<N, N> Q = lik.q_param().template Matrix<double>(theta_q, lik.dt_ref());
  const Mat<M, M> R = lik.r_param().template Matrix<double>(theta_r, 0.0);
  FilterSpec out = spec;
  out.q_white_accel = lik.q_param().IsWhiteAccel();
  out.qc = lik.q_param().Qc(theta_q);
  out.q.clear();
  if (!out.q_white_accel)
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) out.q.push_back(Q(i, j));
  out.r.clear();
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) out.r.push_back(R(i, j));
  return out;
}

// Everything after the optimum result->theta is known: the tuned Q, R and
// spec, the standard errors and identifiability, the poorly-identified and
// at-bound flags.
template <class Model, class Meas>
void FinishTune(const Objective<Model, Meas>& objective, const FilterSpec& spec,
                const TunerOptions& options, const std::vector<double>& lower,
                const std::vector<double>& upper, TuneResult* out) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const InnovationLikelihood<Model, Meas>& lik = objective.likelihood();
  const int k = lik.NumParams();
  TuneResult& result = *out;
  const double* theta_q = result.theta.data();
  const double* theta_r = result.theta.data() + lik.q_param().NumParams();
  const Mat<N, N> Q = lik.q_param().template Matrix<double>(theta_q, result.dt_ref);
  const Mat<M, M> R = lik.r_param().template Matrix<double>(theta_r, 0.0);
  result.q.assign(N * N, 0.0);
  result.r.assign(M * M, 0.0);
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) result.q[i * N + j] = Q(i, j);
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) result.r[i * M + j] = R(i, j);
  result.q_white_accel = lik.q_param().IsWhiteAccel();
  result.qc = lik.q_param().Qc(theta_q);
  result.tuned_spec = SpecAt(lik, spec, result.theta.data());

  // Standard errors and identifiability.
  FillUncertainty(objective, options, &result);
  std::vector<int> off_row = lik.q_param().OffDiagonalRow();
  for (int row : lik.r_param().OffDiagonalRow()) off_row.push_back(row);
  off_row.resize(k, -1);  // the physical parameters
  for (int i = 0; i < k; ++i) {
    double limit = options.poorly_identified_se;
    if (result.is_physical[i] && !result.is_log[i]) limit = std::abs(result.theta[i]);
    if (off_row[i] >= 0) {
      const bool in_q = i < lik.q_param().NumParams();
      limit = std::sqrt(in_q ? Q(off_row[i], off_row[i]) : R(off_row[i], off_row[i]));
    }
    result.poorly_identified.push_back(!(result.std_errors[i] <= limit));
    result.at_bound.push_back(AtBound(result.theta[i], lower[i], upper[i], result.is_log[i]));
  }
}

// EM (TunerForm::kEm), from the initial guess in result->theta_initial;
// defined in adaptive/em.h (included at the end of this file).
template <class Model, class Meas>
void RunEm(const Objective<Model, Meas>& objective, const FilterSpec& spec,
           const TunerOptions& options, const std::vector<FilterData>& datasets,
           const std::vector<double>& lower, const std::vector<double>& upper, TuneResult* result);
// ALS (TunerForm::kAls); defined in adaptive/als.h.
template <class Model, class Meas>
void RunAls(const Objective<Model, Meas>& objective, const FilterSpec& spec,
            const TunerOptions& options, const std::vector<FilterData>& datasets,
            const std::vector<double>& lower, const std::vector<double>& upper, TuneResult* result);

}  // namespace tuner_internal

template <class Model, class Meas>
TuneResult TuneWith(const FilterSpec& spec, const TunerOptions& options,
                    const std::vector<FilterData>& datasets) {
  using namespace tuner_internal;
  constexpr int M = Meas::kDim;
  const auto clock_start = std::chrono::steady_clock::now();
  const InnovationLikelihood<Model, Meas> lik(spec, options, datasets);
  const Objective<Model, Meas> objective(lik);
  const int k = lik.NumParams();

  TuneResult result;
  result.form = TunerFormName(options.form);
  result.names = lik.ParamNames();
  result.is_log = lik.ParamIsLog();
  result.theta_initial = lik.InitialTheta();
  result.q_param = options.q_param;
  result.r_param = options.r_param;
  result.dt_ref = lik.dt_ref();
  result.updates = lik.NumTerms();
  // Q's and R's log parameters take the common-scale search and the start
  // spread; the physical parameters keep their initial values there.
  const int noise = lik.NumNoiseParams();
  std::vector<bool> scaled(result.is_log);
  for (int i = 0; i < k; ++i) {
    result.is_physical.push_back(i >= noise);
    if (i >= noise) scaled[i] = false;
  }
  std::vector<double> lower, upper;
  LikelihoodBounds(lik, options, &lower, &upper);
  if (!lik.Nll(result.theta_initial.data(), &result.nll_initial) ||
      !std::isfinite(result.nll_initial))
    result.nll_initial = kInf;
  auto finish = [&]() {
    result.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
    return result;
  };
  if (options.form == TunerForm::kEm || options.form == TunerForm::kAls) {
    if (options.form == TunerForm::kEm) {
      RunEm(objective, spec, options, datasets, lower, upper, &result);
    } else {
      RunAls(objective, spec, options, datasets, lower, upper, &result);
    }
    return finish();
  }

  // Multi-start.
  const auto points = StartPoints(options, result.theta_initial, scaled, lower, upper);
  std::vector<bool> converged(points.size(), false);
  for (size_t s = 0; s < points.size(); ++s) {
    bool conv = false;
    std::vector<double> from = points[s];
    double shift = 0.0;
    if (k > 0 && options.scale_search) {
      shift = ScaleSearch(objective, from, result.is_log, noise, lower, upper);
      from = ScaleShifted(from, result.is_log, noise, shift);
    }
    if (k == 0) {
      TuneStart st;
      st.theta_start = st.theta_end = points[s];
      st.ok = std::isfinite(result.nll_initial);
      st.nll_start = st.nll_end = result.nll_initial;
      st.termination = "nothing to tune (Q and R fixed)";
      conv = st.ok;
      result.starts.push_back(st);
    } else if (options.form == TunerForm::kLbfgs) {
      const TuneProgress where{.phase = "start", .start = int(s) + 1, .starts = int(points.size())};
      result.starts.push_back(RunLbfgs(objective, options, lower, upper, from, &conv, where));
    } else {
      const TuneProgress where{
          .phase = "start", .start = int(s) + 1, .starts = int(points.size()), .objective = "cost"};
      result.starts.push_back(
          RunLeastSquares(objective, options, lower, upper, from, M, &conv, where));
    }
    result.starts.back().theta_start = points[s];
    result.starts.back().scale_shift = shift;
    if (!result.starts.back().ok && k > 0) {  // say why the filter failed there
      double nll = 0.0;
      std::string why;
      if (!lik.Nll(from.data(), &nll, &why) && !why.empty())
        result.starts.back().termination += " The filter at this start: " + why + ".";
    }
    converged[s] = conv;
    const TuneStart& st = result.starts.back();
    if (st.ok && (result.best_start < 0 || st.nll_end < result.starts[result.best_start].nll_end))
      result.best_start = int(s);
  }

  if (result.best_start < 0) {
    result.status = TuneStatus::kAllStartsFailed;
    result.message = "the filter diverged at every one of the " + std::to_string(points.size()) +
                     " start points (" + result.starts.front().termination + ")";
    result.nll_tuned = kInf;
    return finish();
  }
  const TuneStart& best = result.starts[result.best_start];
  result.status =
      converged[result.best_start] ? TuneStatus::kConverged : TuneStatus::kNoConvergence;
  result.theta = best.theta_end;
  result.nll_tuned = best.nll_end;
  result.iterations = best.iterations;
  result.termination = best.termination;
  int failed = 0;
  for (const auto& st : result.starts) failed += !st.ok;
  // Starts are numbered from 1 here as in 'estlab tune' (start 1 = the
  // initial guess); best_start is the 0-based index into starts.
  result.message = "best of " + std::to_string(result.starts.size()) + " start(s): start " +
                   std::to_string(result.best_start + 1) +
                   (failed ? " (" + std::to_string(failed) + " diverged)" : "");

  FinishTune(objective, spec, options, lower, upper, &result);
  return finish();
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

#include "adaptive/als.h"  // RunAls
#include "adaptive/em.h"   // RunEm

#endif  // ESTLAB_ADAPTIVE_TUNER_IMPL_H_
