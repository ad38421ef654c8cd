// The tuner's objective (part of the tuner, adaptive/tuner_impl.h): the NLL of
// adaptive/likelihood.h with its exact gradient, and the least-squares
// residuals with their Jacobian.
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
// Passes in parallel. The passes of one gradient or Jacobian (the double
// run and each chunk's Jet run) are independent runs of the filter that
// write disjoint entries, so with pass_jobs > 1 they are tasks of one pool
// (src/core/task_pool.h): the same numbers for any pass_jobs, about
// min(passes, pass_jobs) times faster (a single tuning uses the cores that
// several starts would). A likelihood with a CVODES process model keeps
// solver state per evaluation and runs its passes in turn.
//
#ifndef ESTLAB_ADAPTIVE_TUNER_OBJECTIVE_H_
#define ESTLAB_ADAPTIVE_TUNER_OBJECTIVE_H_

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "adaptive/likelihood.h"
#include "src/core/task_pool.h"

namespace estlab {
namespace tuner_internal {

constexpr double kInf = std::numeric_limits<double>::infinity();

// NLL and its gradient / the least-squares residuals and their Jacobian, by
// chunked forward AD.
template <class Model, class Meas>
class Objective {
 public:
  static constexpr int kM = Meas::kDim;
  // pass_jobs: threads for the passes of one gradient (see above).
  explicit Objective(const InnovationLikelihood<Model, Meas>& likelihood, int pass_jobs = 1)
      : lik_(likelihood),
        k_(likelihood.NumParams()),
        pass_jobs_(likelihood.UsesCvodes() ? 1 : std::max(1, pass_jobs)) {}

  int NumParams() const { return k_; }
  const InnovationLikelihood<Model, Meas>& likelihood() const { return lik_; }

  bool Value(const double* theta, double* nll) const { return lik_.Nll(theta, nll); }

  // NLL and gradient (gradient may be null). The value is the double run's,
  // the NLL a user gets at theta: the Jets' real part agrees with it only to
  // rounding, and on a model with max/min/abs near its kinks that rounding
  // can flip a branch (1e-7 relative seen on a two-tank model), so every
  // value the optimiser compares and reports is the double one.
  bool ValueAndGradient(const double* theta, double* nll, double* gradient) const {
    if (gradient == nullptr || k_ == 0) return Value(theta, nll);
    // pass 0: the double run's value; pass c >= 1: chunk c - 1's Jets
    bool value_ok = true;
    const bool ok = k_ <= 2 ? ChunkedGradient<2>(theta, nll, &value_ok, gradient)
                            : ChunkedGradient<4>(theta, nll, &value_ok, gradient);
    if (!ok) return false;
    for (int i = 0; i < k_; ++i)
      if (!std::isfinite(gradient[i])) return false;
    return value_ok && std::isfinite(*nll);
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
        theta, [&](const Vec<double, kM>&, const double& ld, int) { lo = std::min(lo, ld); });
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

  // Runs pass(0) .. pass(passes - 1) on pass_jobs_ threads (in turn for
  // one); true when every pass returned true.
  template <class Pass>
  bool ForEachPass(int passes, Pass&& pass) const {
    std::vector<char> ok(size_t(passes), 0);
    if (pass_jobs_ <= 1 || passes <= 1) {
      for (int c = 0; c < passes; ++c)
        if (!(ok[size_t(c)] = pass(c))) return false;
      return true;
    }
    TaskPool pool(pass_jobs_, size_t(passes), [&](size_t c, int) { ok[c] = pass(int(c)); });
    pool.Join();
    for (char o : ok)
      if (!o) return false;
    return true;
  }

  // *nll and *value_ok from the double run; the gradient from the Jets' runs,
  // chunk by chunk (the Jets' real part is not the reported value).
  template <int C>
  bool ChunkedGradient(const double* theta, double* nll, bool* value_ok, double* gradient) const {
    const int chunks = (k_ + C - 1) / C;
    return ForEachPass(chunks + 1, [&](int pass) {
      if (pass == 0) {
        *value_ok = Value(theta, nll);
        return true;  // the caller reports a failed value
      }
      const int first = (pass - 1) * C;
      const std::vector<ceres::Jet<double, C>> th = Seed<C>(theta, first);
      ceres::Jet<double, C> f;
      if (!lik_.Nll(th.data(), &f)) return false;
      for (int i = first; i < std::min(k_, first + C); ++i) gradient[i] = f.v[i - first];
      return true;
    });
  }

  template <class T>
  bool ResidualsT(const T* theta, double c, T* residuals) const {
    long at = 0;
    bool positive = true;
    const bool ok =
        lik_.template Run<T>(theta, [&](const Eigen::Matrix<T, kM, 1>& e, const T& log_det, int) {
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

  // Each chunk's Jets give the residuals (the same real parts in every
  // chunk; the last chunk's are kept) and their columns of the Jacobian.
  template <int C>
  bool ChunkedResiduals(const double* theta, double c, double* residuals, double* jacobian) const {
    const long rows = NumResiduals();
    const int chunks = (k_ + C - 1) / C;
    const bool ok = ForEachPass(chunks, [&](int chunk) {
      const int first = chunk * C;
      std::vector<ceres::Jet<double, C>> r(static_cast<size_t>(rows));
      const std::vector<ceres::Jet<double, C>> th = Seed<C>(theta, first);
      if (!ResidualsT<ceres::Jet<double, C>>(th.data(), c, r.data())) return false;
      for (long row = 0; row < rows; ++row) {
        if (chunk == chunks - 1) residuals[row] = r[size_t(row)].a;
        for (int i = first; i < std::min(k_, first + C); ++i)
          jacobian[row * k_ + i] = r[size_t(row)].v[i - first];
      }
      return true;
    });
    if (!ok) return false;
    for (long row = 0; row < rows; ++row)
      if (!std::isfinite(residuals[row])) return false;
    return true;
  }

  const InnovationLikelihood<Model, Meas>& lik_;
  int k_;
  int pass_jobs_;
};

// The NLL at theta as a plain function (+inf where the filter fails), for
// the verdict's probes (adaptive/tune_verdict.h).
template <class Model, class Meas>
std::function<double(const std::vector<double>&)> NllFunction(
    const Objective<Model, Meas>& objective) {
  return [&objective](const std::vector<double>& theta) {
    double f = kInf;
    return objective.Value(theta.data(), &f) && std::isfinite(f) ? f : kInf;
  };
}

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

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNER_OBJECTIVE_H_
