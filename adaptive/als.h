// Autocovariance least squares for Q and R (`estlab tune --estimator als`,
// Estimator::kAls): Odelson, Rajamani & Rawlings, "A new autocovariance
// least-squares method for estimating noise covariances", Automatica 42
// (2006), in its time-varying form, so that the KF's transient and the EKF
// linearised along its own estimates are covered too. Include only through
// adaptive/tuner_impl.h.
//
// The data are the innovations Y_k of one run of a deliberately suboptimal
// filter (the KF or EKF with the initial Q0, R0). With the error
// e_k = x_k - x-_k of its prediction, its gain K_k, its measurement
// Jacobian H_k (C_k in the paper) and its transition Jacobian F_k to the
// next update:
//   Y_k      = H_k e_k + v_k
//   e_{k+1}  = Abar_k e_k + w_k - B_k v_k,   Abar_k = F_k (I - K_k H_k),  B_k = F_k K_k
//   P_{k+1}  = Abar_k P_k Abar_k^T + Q_k + B_k R B_k^T      (P_k = Cov e_k)
// so the lag-j autocovariances are affine in (Q, R):
//   E[Y_k Y_k^T]       = H_k P_k H_k^T + R
//   E[Y_{k+j} Y_k^T]   = H_{k+j} Abar_{k+j-1} ... Abar_{k+1} (Abar_k P_k H_k^T - B_k R),  j >= 1
// (for a stationary gain these are the paper's C_j = C Abar^j P C^T -
// C Abar^{j-1} A L R). Summed over the updates k >= burn_in,
//   S_j(Q, R) = sum_k E[Y_{k+j} Y_k^T],   Shat_j = sum_k Y_{k+j} Y_k^T,
// and ALS minimises
//   sum_{j < lags} || (Shat_j - S_j(Q, R)) / count_j ||_F^2
// over theta, Q and R parameterised as in the likelihood tuner
// (noise_param.h: log-variances, log-Cholesky), which keeps them positive
// (semi)definite; Ceres' Levenberg-Marquardt solves it. Because S is affine
// in the free elements p of Q and R (diagonal entries, Cholesky products,
// qc), S = s0 + J p is built once and every residual is cheap.
//
// F_k and H_k are recovered from the filter's own moments, exact for the KF
// and the EKF: F_k^T = P+_k^-1 Cov(x_k, x-_{k+1}) (Filter::PredictCrossCov)
// and H_k^T = P-_k^-1 K_k S_k (the gain of StepResult). P_b at the first
// update used is the filter's P-; the burn-in lets its error fade.
//
// Identifiability: the columns of J are what the lags can see; a direction
// of p in J's null space (singular value below 1e-9 of the largest, columns
// scaled to unit length) is not identifiable from these lags, and the
// report names it.
//
// WARNING: ALS needs a measurement at every row (a missing one is refused)
// and enough lags: with lags = 1 only H P H^T + R is seen and Q and R are
// not separately identifiable. It gives no standard errors (they need the
// fourth moments of the innovations); its spread is best seen by Monte Carlo.
#ifndef ESTLAB_ADAPTIVE_ALS_H_
#define ESTLAB_ADAPTIVE_ALS_H_

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "adaptive/tune_problem.h"
#include "adaptive/tune_verdict.h"
#include "adaptive/tuner_drivers.h"
#include "adaptive/tuner_result.h"
#include "src/run/filter_run_impl.h"

namespace estlab {
namespace als_internal {

// One update of the suboptimal filter and the step from it to the next.
template <int N, int M>
struct AlsStep {
  Vec<double, M> y = Vec<double, M>::Zero();  // the innovation Y_k
  Mat<M, N> H = Mat<M, N>::Zero();            // H_k
  Mat<N, M> K = Mat<N, M>::Zero();            // K_k
  Mat<N, N> P = Mat<N, N>::Zero();            // the filter's P-_k
  Mat<N, N> F = Mat<N, N>::Identity();        // F_k to the next update (I: none between)
  double dt = 0.0;                            // that prediction's step (Q_k = Q(dt))
  bool predicted = false;                     // whether Q_k enters
  Mat<N, N> a_bar = Mat<N, N>::Zero();        // F_k (I - K_k H_k)
  Mat<N, M> b = Mat<N, M>::Zero();            // F_k K_k
};

// Runs the filter of `spec` (its Q, R) over one dataset and records each
// update. Throws InputError for a row without a measurement and
// NumericalError when the filter fails.
template <class Model, class Meas>
std::vector<AlsStep<Model::kStateDim, Meas::kDim>> RecordFilter(const FilterSpec& spec,
                                                                const FilterData& d) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  using StateCov = Mat<N, N>;
  const typename Model::Params params = ParamsFromVector<Model>(spec.params);
  auto transition = MakeTransition<Model>(params, spec.transition);
  auto filter = MakeFilter<Model, Meas>(spec, params, transition.get());
  filter->SetInput(InputFrom<Model>(InputAtRow(spec, d, 0)));
  const Mat<M, M> R = MatFromVector<M, M>(spec.r);
  if (!d.t.empty()) filter->SetTime(d.t[0]);
  filter->Initialize(PriorMean<Model, Meas>(spec, d), MatFromVector<N, N>(spec.p0));
  std::vector<AlsStep<N, M>> steps;
  auto fail = [&](size_t k, const std::string& what) {
    throw NumericalError("ALS: the filter failed at row " + std::to_string(k) +
                         " (t = " + FormatNumber(d.t[k]) + ") of " + d.path + ": " + what);
  };
  ForEachStep<M>(
      spec, d,
      [&](size_t k, double t0, double t1, const double* u0, const double* u1) {
        const StateCov p_plus = filter->cov();
        filter->SetInputPath(InputFrom<Model>(u0), InputFrom<Model>(u1));
        const StateCov Q =
            spec.q_white_accel ? WhiteAccelQ<Model>(spec.qc, t1 - t0) : MatFromVector<N, N>(spec.q);
        if (filter->Predict(t0, t1, Q) != FilterStatus::kOk) fail(k, filter->last_error());
        StateCov C;
        if (!filter->PredictCrossCov(&C)) fail(k, "no prediction cross-covariance");
        if (steps.empty()) return true;  // from the prior: before the first update
        const Eigen::LLT<StateCov> llt(p_plus);
        if (llt.info() != Eigen::Success)
          fail(k, "the filtered covariance is not positive definite");
        steps.back().F = llt.solve(C).transpose();  // F^T = P+^-1 C
        steps.back().dt = t1 - t0;
        steps.back().predicted = true;
        return true;
      },
      [&](size_t k, const Vec<double, M>* z, const double* u) {
        filter->SetInput(InputFrom<Model>(u));  // u_k, seen by h(t, x, u)
        filter->SetTime(d.t[k]);
        if (z == nullptr || !z->allFinite())  // its lagged covariances need complete rows
          throw InputError("ALS needs a measurement at every row: row " + std::to_string(k) +
                           " (line " + std::to_string(k < d.lines.size() ? d.lines[k] : 0) +
                           ") of " + d.path + " has a missing value");
        const StateCov p_minus = filter->cov();
        const StepResult<M> r = filter->Update(*z, R);
        if (r.status != FilterStatus::kOk) fail(k, r.message);
        AlsStep<N, M> s;
        s.y = r.innovation;
        s.K = r.gain;
        s.P = p_minus;
        const Eigen::LLT<StateCov> llt(p_minus);
        if (llt.info() != Eigen::Success)
          fail(k, "the predicted covariance is not positive definite");
        s.H = llt.solve(s.K * r.innovation_cov).transpose();  // H^T = P-^-1 K S
        steps.push_back(s);
        return true;
      });
  for (AlsStep<N, M>& s : steps) {
    s.a_bar = s.F * (Mat<N, N>::Identity() - s.K * s.H);
    s.b = s.F * s.K;
  }
  return steps;
}

// Adds S_j(Q, R) of one dataset to s (lags blocks of M x M, column-major
// per block): Q_k = q(dt_k) where a prediction follows update k, P at the
// first update used = P_start (the filter's P- there, or 0 for the linear
// part of the map).
template <int N, int M, class QFn>
void AddModelAutocov(const std::vector<AlsStep<N, M>>& steps, int burn_in, int lags, QFn&& q,
                     const Mat<M, M>& R, bool with_initial, Eigen::VectorXd* s) {
  const int count = int(steps.size());
  if (burn_in >= count) return;
  Mat<N, N> P = with_initial ? steps[burn_in].P : Mat<N, N>::Zero();
  for (int k = burn_in; k < count; ++k) {
    const AlsStep<N, M>& sk = steps[k];
    Mat<N, M> V = P * sk.H.transpose();  // E[e_k Y_k^T]
    Eigen::Map<Mat<M, M>>(s->data()) += sk.H * V + R;
    if (k + 1 == count) break;
    V = sk.a_bar * V - sk.b * R;  // E[e_{k+1} Y_k^T]
    for (int j = 1; j < lags && k + j < count; ++j) {
      Eigen::Map<Mat<M, M>>(s->data() + j * M * M) += steps[k + j].H * V;
      V = steps[k + j].a_bar * V;
    }
    P = sk.a_bar * P * sk.a_bar.transpose() + sk.b * R * sk.b.transpose();
    if (sk.predicted) P += q(sk.dt);
    P = 0.5 * (P + P.transpose()).eval();
  }
}

// Adds Shat_j and the counts of one dataset.
template <int N, int M>
void AddDataAutocov(const std::vector<AlsStep<N, M>>& steps, int burn_in, int lags,
                    Eigen::VectorXd* s, std::vector<double>* counts) {
  const int count = int(steps.size());
  for (int j = 0; j < lags; ++j) {
    for (int k = burn_in; k + j < count; ++k) {
      Eigen::Map<Mat<M, M>>(s->data() + j * M * M) += steps[k + j].y * steps[k].y.transpose();
      (*counts)[j] += 1.0;
    }
  }
}

// The free elements p of a covariance and their basis matrices (D = sum_i
// p_i B_i(dt)): diag -> D_ii; full -> D_ij, i <= j (B = E_ij + E_ji);
// scalar -> s (B = I); white-accel -> qc (B = Q_wa(dt)); fixed -> none.
template <int D>
struct FreeElements {
  std::vector<std::string> names;
  std::vector<std::function<Mat<D, D>(double)>> basis;
};

template <int D>
FreeElements<D> FreeElementsOf(const CovarianceParam<D>& param, const std::string& symbol,
                               const std::vector<std::string>& component) {
  FreeElements<D> out;
  auto unit = [](int i, int j) {
    Mat<D, D> B = Mat<D, D>::Zero();
    B(i, j) = B(j, i) = 1.0;
    return B;
  };
  switch (param.kind()) {
    case NoiseParam::kDiag:
      for (int i = 0; i < D; ++i) {
        out.names.push_back(symbol + "_" + component[i]);
        out.basis.push_back([=](double) { return unit(i, i); });
      }
      break;
    case NoiseParam::kFull:
      for (int i = 0; i < D; ++i)
        for (int j = i; j < D; ++j) {
          out.names.push_back(symbol + "(" + component[i] + "," + component[j] + ")");
          out.basis.push_back([=](double) { return unit(i, j); });
        }
      break;
    case NoiseParam::kScalar:
      out.names.push_back(symbol);
      out.basis.push_back([](double) { return Mat<D, D>::Identity().eval(); });
      break;
    case NoiseParam::kWhiteAccel:
      out.names.push_back("qc");
      out.basis.push_back([&param](double dt) { return param.WhiteAccel(1.0, dt); });
      break;
    case NoiseParam::kFixed:
      break;
  }
  return out;
}

// p of theta, in the order of FreeElementsOf, for any scalar.
template <int D, class T>
void FreeValues(const CovarianceParam<D>& param, const T* theta, T* p) {
  using std::exp;
  if (param.kind() == NoiseParam::kWhiteAccel || param.kind() == NoiseParam::kScalar) {
    p[0] = exp(theta[0]);
    return;
  }
  if (param.kind() == NoiseParam::kFixed) return;
  const Eigen::Matrix<T, D, D> m = param.template Matrix<T>(theta, 0.0);
  int at = 0;
  for (int i = 0; i < D; ++i) {
    if (param.kind() == NoiseParam::kDiag) {
      p[at++] = m(i, i);
      continue;
    }
    for (int j = i; j < D; ++j) p[at++] = m(i, j);
  }
}

// The scaled residual (target - J p(theta)); target and J rows already
// divided by count_j.
template <int N, int M>
struct AlsResidual {
  const CovarianceParam<N>* q;
  const CovarianceParam<M>* r;
  int nq;  // Q's free elements come first in p
  const Eigen::MatrixXd* J;
  const Eigen::VectorXd* target;
  template <class T>
  bool operator()(T const* const* parameters, T* residuals) const {
    const T* theta = parameters[0];
    std::vector<T> p(J->cols());
    FreeValues<N, T>(*q, theta, p.data());
    FreeValues<M, T>(*r, theta + q->NumParams(), p.data() + nq);
    for (Eigen::Index i = 0; i < J->rows(); ++i) {
      T v = T((*target)(i));
      for (Eigen::Index c = 0; c < J->cols(); ++c) v -= (*J)(i, c) * p[c];
      residuals[i] = v;
    }
    return true;
  }
};

// What the lags identify: the elements of p with no component in J's null
// space, and the directions they do not see (each written out when there
// are at most two, else counted with the elements they involve).
inline std::vector<std::string> AlsIdentifiability(const Eigen::MatrixXd& J,
                                                   const std::vector<std::string>& names,
                                                   int lags) {
  Eigen::MatrixXd scaled = J;
  for (Eigen::Index c = 0; c < J.cols(); ++c) {
    const double norm = J.col(c).norm();
    if (norm > 0) scaled.col(c) /= norm;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeFullV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const double top = sv.size() ? sv(0) : 0.0;
  std::vector<bool> seen(J.cols(), true);
  std::vector<std::string> directions;
  for (Eigen::Index c = 0; c < J.cols(); ++c) {
    if (c < sv.size() && sv(c) > 1e-9 * top) continue;  // a seen direction
    const Eigen::VectorXd v = svd.matrixV().col(c);
    std::string combination;
    for (Eigen::Index i = 0; i < v.size(); ++i) {
      if (std::abs(v(i)) < 1e-6) continue;
      seen[i] = false;
      combination += (combination.empty() ? ""
                      : v(i) < 0          ? " - "
                                          : " + ") +
                     FormatNumber(combination.empty() ? v(i) : std::abs(v(i))) + " " + names[i];
    }
    directions.push_back(combination);
  }
  const std::string with = "ALS with " + std::to_string(lags) + " lag(s) ";
  std::string identified, blind;
  for (size_t i = 0; i < names.size(); ++i)
    (seen[i] ? identified : blind) +=
        ((seen[i] ? identified : blind).empty() ? "" : ", ") + names[i];
  std::vector<std::string> out{
      with + "identifies " +
      (identified.empty() ? std::string("none of the elements") : identified)};
  if (directions.empty()) return out;
  if (directions.size() <= 2) {
    for (const std::string& d : directions)
      out.push_back(with + "does not see the direction " + d + " (more lags may help)");
  } else {
    out.push_back(with + "does not see " + std::to_string(directions.size()) + " of the " +
                  std::to_string(names.size()) + " directions of (Q, R), involving " + blind +
                  " (more lags may help)");
  }
  return out;
}

}  // namespace als_internal

namespace tuner_internal {

// The linear system of ALS: the innovation autocovariances of the data
// (target, scaled by the lag-0 norm) against their model J theta_free.
struct AlsSystem {
  Eigen::MatrixXd J;
  Eigen::VectorXd target;
  std::vector<std::string> names;
  int nq = 0;  // Q's free elements come first
};

template <class Model, class Meas>
AlsSystem BuildAlsSystem(const InnovationLikelihood<Model, Meas>& lik, const FilterSpec& spec,
                         const TunerOptions& options, const std::vector<FilterData>& datasets) {
  using namespace als_internal;
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const CovarianceParam<N>& qp = lik.q_param();
  const CovarianceParam<M>& rp = lik.r_param();
  const FreeElements<N> fq = FreeElementsOf<N>(qp, "q", likelihood_internal::StateNames<Model>());
  const FreeElements<M> fr = FreeElementsOf<M>(rp, "r", likelihood_internal::OutputNames<Meas>());
  const int nq = int(fq.basis.size()), np = nq + int(fr.basis.size());
  const int lags = options.als_lags;
  const int rows = lags * M * M;

  // s0 (the initial error and the fixed matrices), J, and the data.
  Eigen::VectorXd s0 = Eigen::VectorXd::Zero(rows), data = s0;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, np);
  std::vector<double> counts(lags, 0.0);
  auto q_fixed = [&](double dt) -> Mat<N, N> {  // Matrix() reads no theta when fixed
    if (qp.kind() != NoiseParam::kFixed) return Mat<N, N>::Zero();
    return qp.template Matrix<double>(nullptr, dt);
  };
  const Mat<M, M> r_fixed = rp.kind() == NoiseParam::kFixed
                                ? rp.template Matrix<double>(nullptr, 0.0)
                                : Mat<M, M>::Zero();
  const auto zero_q = [](double) { return Mat<N, N>::Zero().eval(); };
  const Mat<M, M> zero_r = Mat<M, M>::Zero();
  for (const FilterData& d : datasets) {
    const auto steps = RecordFilter<Model, Meas>(spec, d);
    if (int(steps.size()) <= options.burn_in + lags)
      throw InputError("ALS: " + d.path + " has " + std::to_string(steps.size()) +
                       " updates, fewer than burn-in + lags + 1");
    AddDataAutocov(steps, options.burn_in, lags, &data, &counts);
    AddModelAutocov(steps, options.burn_in, lags, q_fixed, r_fixed, true, &s0);
    for (int c = 0; c < np; ++c) {
      Eigen::VectorXd col = Eigen::VectorXd::Zero(rows);
      if (c < nq) {
        AddModelAutocov(steps, options.burn_in, lags, fq.basis[c], zero_r, false, &col);
      } else {
        AddModelAutocov(steps, options.burn_in, lags, zero_q, fr.basis[c - nq](0.0), false, &col);
      }
      J.col(c) += col;
    }
  }
  Eigen::VectorXd target = data - s0;
  for (int j = 0; j < lags; ++j) {
    target.segment(j * M * M, M * M) /= counts[j];
    J.middleRows(j * M * M, M * M) /= counts[j];
  }
  // In covariance units the residuals of a precise sensor (R ~ 1e-9 rad^2)
  // are ~1e-9 and their gradient is below any absolute tolerance at the
  // start: Levenberg-Marquardt would stop there, "converged", without a
  // step. Dividing by the norm of the data's lag-0 autocovariance (the
  // innovation covariance) makes the problem scale-free; the minimiser is
  // the same.
  const double scale = (data.head(M * M) / counts[0]).norm();
  if (scale > 0 && std::isfinite(scale)) {
    target /= scale;
    J /= scale;
  }
  AlsSystem sys{.J = J, .target = target, .names = fq.names, .nq = nq};
  sys.names.insert(sys.names.end(), fr.names.begin(), fr.names.end());
  return sys;
}

template <class Model, class Meas>
void RunAls(const Objective<Model, Meas>& objective, const TuneProblem& tune, TuneResult* out) {
  const FilterSpec& spec = tune.spec;
  const TunerOptions& options = tune.options;
  const std::vector<FilterData>& datasets = tune.datasets;
  const std::vector<double>&lower = tune.lower, &upper = tune.upper;
  using namespace als_internal;
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const InnovationLikelihood<Model, Meas>& lik = objective.likelihood();
  TuneResult& result = *out;
  // The filters it accepts (kf, ekf): its row of adaptive/estimators.h, checked by
  // IsTunable when the likelihood was built.
  const CovarianceParam<N>& qp = lik.q_param();
  const CovarianceParam<M>& rp = lik.r_param();
  const int lags = options.als_lags;
  const int rows = lags * M * M;
  const AlsSystem sys = BuildAlsSystem(lik, spec, options, datasets);
  const Eigen::MatrixXd& J = sys.J;
  const Eigen::VectorXd& target = sys.target;
  const std::vector<std::string>& names = sys.names;
  const int nq = sys.nq;

  // Levenberg-Marquardt on theta from the initial guess.
  std::vector<double> theta = result.theta_initial;
  const int k = int(theta.size());
  ceres::Problem problem;
  if (k > 0) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<AlsResidual<N, M>, 4>(
        new AlsResidual<N, M>{&qp, &rp, nq, &J, &target});
    cost->AddParameterBlock(k);
    cost->SetNumResiduals(rows);
    problem.AddResidualBlock(cost, nullptr, theta.data());
    SetBounds(lower, upper, theta.data(), &problem);
  }
  ceres::Solver::Summary summary;
  if (k > 0) ceres::Solve(LevenbergMarquardtOptions(options), &problem, &summary);
  TuneStart start;
  start.theta_start = result.theta_initial;
  start.theta_end = theta;
  start.nll_start = result.nll_initial;
  start.iterations = k > 0 ? summary.num_successful_steps + summary.num_unsuccessful_steps : 0;
  start.termination = k > 0 ? summary.message : "nothing to tune (Q and R fixed)";
  start.ok = (k == 0 || summary.IsSolutionUsable()) && lik.Nll(theta.data(), &start.nll_end) &&
             std::isfinite(start.nll_end);
  if (!start.ok) start.nll_end = kInf;
  result.starts.push_back(start);
  result.iterations = start.iterations;
  result.termination = start.termination;
  result.best_start = 0;
  result.theta = theta;
  result.nll_tuned = start.nll_end;
  result.status = (k == 0 || summary.termination_type == ceres::CONVERGENCE)
                      ? TuneStatus::kConverged
                      : TuneStatus::kNoConvergence;
  result.message = "ALS over " + std::to_string(lags) +
                   " lag(s), final cost (in units of the innovation covariance) " +
                   FormatNumber(k > 0 ? summary.final_cost : 0.0) +
                   (start.ok ? "" : "; the filter fails at the ALS estimate (NLL infinite)");
  TunerOptions no_se = options;
  no_se.compute_std_errors = false;
  FinishTune(objective, spec, no_se, lower, upper, &result);
  result.identifiability = AlsIdentifiability(J, names, lags);
  result.identifiability.push_back(
      "ALS gives no standard errors (they need the innovations' fourth moments): the SEs are "
      "infinite; estimate the spread by repeating the fit on independent data");
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_ALS_H_
