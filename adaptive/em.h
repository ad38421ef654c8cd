// Expectation-maximisation for Q and R (`estlab tune --estimator em`,
// Estimator::kEm), with the filter's own smoother as the E-step
// (Shumway & Stoffer 1982; Saerkkae & Svensson, Bayesian Filtering and
// Smoothing, 2nd ed., 2023, ch. 16). Include only through
// adaptive/tuner_impl.h.
//
// One iteration at the current Q, R:
//   E-step  run the filter and its RTS smoother over every dataset
//           (RunFilterWith with smooth, returning its typed SmoothedMoments:
//           the numbers `estlab smooth --full-cov` writes), giving for each row k the
//           smoothed x^s_k, P^s_k and Cov(x_k, x_{k+1} | all data) = C^s_k;
//   M-step  with f the filter's noise-free process map and h its
//           measurement (InnovationLikelihood::PointTransition,
//           MeasurementResidual: the KF's linearised, discretised model, the
//           model itself for the others),
//             A_k = E[(x_{k+1} - f(x_k)) (x_{k+1} - f(x_k))^T]
//             B_k = E[wrap(z_k - h(x_k)) wrap(z_k - h(x_k))^T]
//           under the smoothed Gaussians N([x^s_k; x^s_{k+1}],
//           [[P^s_k, C^s_k], [C^s_k^T, P^s_{k+1}]]) and N(x^s_k, P^s_k), by
//           the third-degree cubature rule (exact when f and h are linear,
//           hence EM is exact for the KF; the sigma-point approximation of
//           Saerkkae's ch. 16 otherwise), and Q, R maximise
//             -1/2 sum_k [log det Q_k + tr(Q_k^-1 A_k)]   (K transitions)
//             -1/2 sum_k [log det R + tr(R^-1 B_k)]       (K_z measurements)
//           in closed form for each parameterisation:
//             full         Q = 1/K sum_k A_k
//             diag         Q = diag(1/K sum_k A_k)
//             scalar       Q = tr(sum_k A_k) / (n K) I
//             white-accel  Q_k = qc W(dt_k): qc = sum_k tr(W_k^-1 A_k) / (n_w K)
//                          over the n_w states of the position/rate pairs
//             fixed        unchanged
//           (the same for R with B_k).
// Rows with some components missing (the filters' subset update,
// src/filters/missing.h): the missing z_U are latent too (Shumway &
// Stoffer, Time Series Analysis and Its Applications, 4th ed., 2017,
// sec. 6.4). Given x and the observed z_O, at the current R,
//   z_U - h_U(x) ~ N(G e_O, R_UU - G R_OU),   G = R_UO R_OO^-1,
//   e_O = wrap(z_O - h_O(x)),
// so with T the M x M map T(:, O) = [I; G], T(:, U) = 0 and e the
// residual with e_U = 0,
//   B_k = T E[e e^T] T^T + [0 0; 0 R_UU - G R_OU]   (U block last),
// which for a diagonal R keeps the observed block's residuals and carries
// R_UU over. EM stays EM: the NLL still never rises for the KF, and a
// fixed point is a stationary point of the likelihood over the observed
// components. A row with no component observed is not a measurement and
// adds nothing.
// The transition from the prior to the first row (spec.t0 before it) is not
// in the M-step, and P0 is not re-estimated.
//
// Initial states (--estimate-x0, TunerOptions::estimate_x0): with the prior
// x(t_0) ~ N(mu, P0) at the first row, the x0 term of the expected
// complete-data log-likelihood is -1/2 E[(x_0 - mu)^T P0^-1 (x_0 - mu)];
// over the estimated entries S of mu (the others, S', held), with
// L = P0^-1 and x^s_0 the smoothed first row,
//   mu_S = x^s_0,S + L_SS^-1 L_SS' (x^s_0,S' - mu_S')   (= x^s_0,S for a diagonal P0),
// averaged over the datasets for a shared x0, each dataset's own with
// --x0-per-file (Shumway & Stoffer 1982, eq. 13). The E-step runs each
// dataset from its own mu. The prior must sit at the first row's time.
//
// Monitoring: after every M-step the exact innovation NLL (the ML tuner's
// objective, adaptive/likelihood.h) is evaluated. On a linear model with
// the KF it never increases (EM's monotonicity); otherwise an increase
// (above 1e-12 |NLL|, the rounding of the sum) is counted in
// TuneResult::nll_increases, and the result is the iterate with
// the lowest NLL. Stops when |NLL_i - NLL_{i-1}| <= em_tolerance |NLL_i| or
// after max_iterations. Then, with em_compare_ml, the L-BFGS form starts
// from EM's solution and its NLL is reported beside EM's.
//
// WARNING: EM converges linearly; on weakly identified directions (a full R
// against a diagonal Q, say) it may need hundreds of iterations where the
// L-BFGS tuner needs tens.
#ifndef ESTLAB_ADAPTIVE_EM_H_
#define ESTLAB_ADAPTIVE_EM_H_

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "adaptive/tune_problem.h"
#include "adaptive/tune_verdict.h"
#include "adaptive/tuner_drivers.h"
#include "adaptive/tuner_result.h"
#include "src/filters/missing.h"
#include "src/run/filter_run_impl.h"

namespace estlab {
namespace em_internal {

// The M-step's sums over every dataset.
template <int N, int M>
struct EmSums {
  Mat<N, N> a = Mat<N, N>::Zero();    // sum_k A_k
  long transitions = 0;               // K
  double white = 0.0;                 // sum_k tr(W_k^-1 A_k) on the paired states
  long white_dims = 0;                // n_w K
  Mat<M, M> b = Mat<M, M>::Zero();    // sum_k B_k
  long measurements = 0;              // K_z
  std::vector<Vec<double, N>> first;  // x^s_0 of each dataset
};

// Cubature points of N(mean, cov): the rule's own DrawSigmaPoints, with a
// jitter of 1e-12 of the mean variance when cov is only semidefinite.
template <int D>
bool CubaturePoints(const SigmaPointSet& set, const Vec<double, D>& mean, const Mat<D, D>& cov,
                    PointsT<double, D>* points) {
  if (DrawSigmaPoints<D>(set, mean, cov, /*add_jitter=*/false, points)) return true;
  Mat<D, D> jittered = cov;
  jittered.diagonal().array() += 1e-12 * std::max(cov.trace() / D, 1e-300);
  return DrawSigmaPoints<D>(set, mean, jittered, false, points);
}

// Adds A_k of the transition from row a to row b (times t0 -> t1, input u
// over the step).
template <class Model, class Meas>
bool AddTransition(const InnovationLikelihood<Model, Meas>& lik, const SigmaPointSet& joint,
                   const SmoothedMoments<Model::kStateDim>& a,
                   const SmoothedMoments<Model::kStateDim>& b, double t0, double t1,
                   const InputPath<Model>& u, EmSums<Model::kStateDim, Meas::kDim>* sums) {
  constexpr int N = Model::kStateDim;
  Vec<double, 2 * N> mean;
  mean << a.x, b.x;
  Mat<2 * N, 2 * N> cov;
  cov << a.P, a.lag_one, a.lag_one.transpose(), b.P;
  PointsT<double, 2 * N> points(2 * N, joint.unit_points.cols());
  if (!cov.allFinite() || !CubaturePoints<2 * N>(joint, mean, cov, &points)) return false;
  Mat<N, N> A = Mat<N, N>::Zero();
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    const Vec<double, N> x_a = points.col(i).template head<N>();
    const Vec<double, N> d = points.col(i).template tail<N>() - lik.PointTransition(x_a, t0, t1, u);
    A.noalias() += joint.mean_weights(i) * d * d.transpose();
  }
  sums->a += A;
  ++sums->transitions;
  if (lik.q_param().kind() == NoiseParam::kWhiteAccel) {  // tr(W_k^-1 A_k) on the pairs
    const Mat<N, N> W = lik.q_param().WhiteAccel(1.0, t1 - t0);
    std::vector<int> paired;
    for (int i = 0; i < N; ++i)
      if (W(i, i) > 0) paired.push_back(i);
    const int n_w = int(paired.size());
    Eigen::MatrixXd Wb(n_w, n_w), Ab(n_w, n_w);
    for (int i = 0; i < n_w; ++i)
      for (int j = 0; j < n_w; ++j) {
        Wb(i, j) = W(paired[i], paired[j]);
        Ab(i, j) = A(paired[i], paired[j]);
      }
    const Eigen::LLT<Eigen::MatrixXd> llt(Wb);
    if (llt.info() != Eigen::Success) return false;
    sums->white += llt.solve(Ab).trace();
    sums->white_dims += n_w;
  }
  return true;
}

// The expected residual map T and the carried covariance of a row with
// some components missing (see the header comment): *T (M x M) and *carried
// from the current R and the missing components of `missing`.
template <int M>
void MissingRowMap(const Mat<M, M>& r_now, const MissingMask<M>& missing, Mat<M, M>* T,
                   Mat<M, M>* carried) {
  std::vector<int> o, u;
  for (int j = 0; j < M; ++j) (missing.Missing(j) ? u : o).push_back(j);
  const auto no = Eigen::Index(o.size()), nu = Eigen::Index(u.size());
  Eigen::MatrixXd r_oo(no, no), r_ou(no, nu), r_uu(nu, nu);
  for (Eigen::Index a = 0; a < no; ++a) {
    for (Eigen::Index b = 0; b < no; ++b) r_oo(a, b) = r_now(o[size_t(a)], o[size_t(b)]);
    for (Eigen::Index b = 0; b < nu; ++b) r_ou(a, b) = r_now(o[size_t(a)], u[size_t(b)]);
  }
  for (Eigen::Index a = 0; a < nu; ++a)
    for (Eigen::Index b = 0; b < nu; ++b) r_uu(a, b) = r_now(u[size_t(a)], u[size_t(b)]);
  const Eigen::LDLT<Eigen::MatrixXd> r_oo_solve(r_oo);
  const Eigen::MatrixXd g_t = r_oo_solve.solve(r_ou);  // G^T = R_OO^-1 R_OU
  const Eigen::MatrixXd r_uu_o = r_uu - g_t.transpose() * r_ou;
  T->setZero();
  carried->setZero();
  for (Eigen::Index a = 0; a < no; ++a) {
    (*T)(o[size_t(a)], o[size_t(a)]) = 1.0;
    for (Eigen::Index b = 0; b < nu; ++b) (*T)(u[size_t(b)], o[size_t(a)]) = g_t(a, b);
  }
  for (Eigen::Index a = 0; a < nu; ++a)
    for (Eigen::Index b = 0; b < nu; ++b) (*carried)(u[size_t(a)], u[size_t(b)]) = r_uu_o(a, b);
}

// Adds B_k of a measured row at time t (input u there); r_now is the
// current R, for the components of z that are missing (NaN).
template <class Model, class Meas>
bool AddMeasurement(const InnovationLikelihood<Model, Meas>& lik, const SigmaPointSet& state,
                    const SmoothedMoments<Model::kStateDim>& row, const Vec<double, Meas::kDim>& z,
                    double t, const InputOf<Model>& u, const Mat<Meas::kDim, Meas::kDim>& r_now,
                    EmSums<Model::kStateDim, Meas::kDim>* sums) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  PointsT<double, N> points(N, state.unit_points.cols());
  if (!row.P.allFinite() || !CubaturePoints<N>(state, row.x, row.P, &points)) return false;
  const MissingMask<M> missing(z);
  const Vec<double, M> z_seen = z.array().isFinite().select(z, 0.0);
  Mat<M, M> b = Mat<M, M>::Zero();
  for (Eigen::Index i = 0; i < points.cols(); ++i) {
    Vec<double, M> e = lik.MeasurementResidual(z_seen, t, points.col(i), u);
    missing.MaskRows(&e);  // e_U = 0, whatever h_U(x) is
    b.noalias() += state.mean_weights(i) * e * e.transpose();
  }
  if (missing.Any()) {
    Mat<M, M> T, carried;
    MissingRowMap<M>(r_now, missing, &T, &carried);
    b = T * b * T.transpose() + carried;
  }
  sums->b += b;
  ++sums->measurements;
  return true;
}

// The E-step over every dataset at theta's Q, R and x0 (`spec` = SpecAt
// theta). False with *why.
template <class Model, class Meas>
bool EStep(const InnovationLikelihood<Model, Meas>& lik, const FilterSpec& spec,
           const double* theta, const std::vector<FilterData>& datasets,
           EmSums<Model::kStateDim, Meas::kDim>* sums, std::string* why) {
  constexpr int N = Model::kStateDim;
  SigmaPointOptions cubature;
  cubature.rule = SigmaRule::kCubature;
  static thread_local const SigmaPointSet joint = MakeSigmaPointSet(2 * N, cubature);
  static thread_local const SigmaPointSet state = MakeSigmaPointSet(N, cubature);
  FilterSpec smooth = spec;
  smooth.smooth = true;
  const Mat<Meas::kDim, Meas::kDim> r_now =
      lik.r_param().template Matrix<double>(theta + lik.q_param().NumParams(), 0.0);
  std::vector<SmoothedMoments<N>> rows;
  for (size_t set = 0; set < datasets.size(); ++set) {
    const FilterData& d = datasets[set];
    if (!lik.initial_states().empty()) {  // this dataset's prior mean
      const Vec<double, N> x0 = lik.PriorMeanAt(theta, set);
      smooth.x0.assign(x0.data(), x0.data() + N);
      smooth.x0_first_sample = false;
    }
    const FilterRunOutput out = RunFilterWith<Model, Meas>(smooth, d, &rows);
    if (!out.summary.ok) {
      *why = out.summary.message;
      return false;
    }
    if (!rows.empty()) sums->first.push_back(rows.front().x);
    const std::string where = d.path.empty() ? "" : " of " + d.path;
    const bool complete = ForEachStep<Meas::kDim>(
        spec, d,
        [&](size_t k, double t0, double t1, const double* u0, const double* u1) {
          if (k == 0) return true;  // from the prior: not re-estimated
          const InputPath<Model> u(InputFrom<Model>(u0), InputFrom<Model>(u1), t0, t1);
          if (AddTransition(lik, joint, rows[k - 1], rows[k], t0, t1, u, sums)) return true;
          *why = "the smoothed joint covariance of rows " + std::to_string(k - 1) + " and " +
                 std::to_string(k) + where + " (t = " + FormatNumber(t0) + " to " +
                 FormatNumber(t1) + ") is not positive semidefinite";
          return false;
        },
        [&](size_t k, const Vec<double, Meas::kDim>* z, const double* u) {
          if (z == nullptr ||
              AddMeasurement(lik, state, rows[k], *z, d.t[k], InputFrom<Model>(u), r_now, sums))
            return true;
          *why = "the smoothed covariance of row " + std::to_string(k) + where +
                 " (t = " + FormatNumber(d.t[k]) + ") is not positive semidefinite";
          return false;
        });
    if (!complete) return false;
  }
  return true;
}

// The closed-form maximiser of one covariance (see the header comment).
template <int D>
InitialCovariance<D> MStep(NoiseParam kind, const Mat<D, D>& sum, long count, double white,
                           long white_dims, const InitialCovariance<D>& current) {
  InitialCovariance<D> next;
  const Mat<D, D> mean = 0.5 * (sum + sum.transpose()) / double(std::max(count, 1L));
  switch (kind) {
    case NoiseParam::kFull:
      next.matrix = mean;
      break;
    case NoiseParam::kDiag:
      next.matrix = Mat<D, D>(mean.diagonal().asDiagonal());
      break;
    case NoiseParam::kScalar:
      next.matrix = (mean.trace() / D) * Mat<D, D>::Identity();
      break;
    case NoiseParam::kWhiteAccel:
      next.white_accel = true;
      next.qc = white / double(std::max(white_dims, 1L));
      break;
    case NoiseParam::kFixed:
      next = current;
      break;
  }
  return next;
}

// The x0 rows of theta after one M-step (see the header comment), appended
// to *next; p0 is the prior covariance.
template <class Model, class Meas>
void MStepX0(const InnovationLikelihood<Model, Meas>& lik, const double* theta,
             const EmSums<Model::kStateDim, Meas::kDim>& sums,
             const Mat<Model::kStateDim, Model::kStateDim>& p0, std::vector<double>* next) {
  constexpr int N = Model::kStateDim;
  const InitialStates& x0s = lik.initial_states();
  const Mat<N, N> L = p0.inverse();
  std::vector<bool> estimated(N, false);
  for (int i : x0s.index) estimated[size_t(i)] = true;
  const auto k = Eigen::Index(x0s.index.size());
  Eigen::MatrixXd l_ss(k, k), l_sh(k, N);  // L_SS and L_SS' (zero columns on S)
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b) l_ss(a, b) = L(x0s.index[a], x0s.index[b]);
    for (int j = 0; j < N; ++j) l_sh(a, j) = estimated[size_t(j)] ? 0.0 : L(x0s.index[a], j);
  }
  const Eigen::LDLT<Eigen::MatrixXd> solve(l_ss);
  std::vector<Eigen::VectorXd> rows(size_t(x0s.rows), Eigen::VectorXd::Zero(k));
  for (size_t set = 0; set < sums.first.size(); ++set) {
    const Vec<double, N> held = sums.first[set] - lik.PriorMeanAt(theta, set);  // S' entries
    Eigen::VectorXd mu = solve.solve(l_sh * held);
    for (Eigen::Index a = 0; a < k; ++a) mu(a) += sums.first[set](x0s.index[a]);
    rows[size_t(x0s.RowOf(set))] += mu / double(x0s.rows > 1 ? 1 : sums.first.size());
  }
  for (const Eigen::VectorXd& row : rows) next->insert(next->end(), row.data(), row.data() + k);
}

// theta of Q, R (and x0) after one M-step; throws InputError when a matrix
// is not positive definite (the parameterisation has no theta for it).
template <class Model, class Meas>
std::vector<double> MStepTheta(const InnovationLikelihood<Model, Meas>& lik,
                               const std::vector<double>& theta,
                               const EmSums<Model::kStateDim, Meas::kDim>& sums,
                               const Mat<Model::kStateDim, Model::kStateDim>& p0) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  const auto& qp = lik.q_param();
  const auto& rp = lik.r_param();
  InitialCovariance<N> q_now;
  q_now.matrix = qp.template Matrix<double>(theta.data(), lik.dt_ref());
  q_now.white_accel = qp.IsWhiteAccel();
  q_now.qc = qp.Qc(theta.data());
  InitialCovariance<M> r_now;
  r_now.matrix = rp.template Matrix<double>(theta.data() + qp.NumParams(), 0.0);
  const CovarianceParam<N> q_next(
      qp.kind(), "q", likelihood_internal::StateNames<Model>(), likelihood_internal::Pairs<Model>(),
      MStep<N>(qp.kind(), sums.a, sums.transitions, sums.white, sums.white_dims, q_now),
      lik.dt_ref());
  const CovarianceParam<M> r_next(rp.kind(), "r", likelihood_internal::OutputNames<Meas>(), {},
                                  MStep<M>(rp.kind(), sums.b, sums.measurements, 0.0, 0, r_now),
                                  0.0);
  std::vector<double> next = q_next.InitialTheta();
  const std::vector<double>& r = r_next.InitialTheta();
  next.insert(next.end(), r.begin(), r.end());
  if (!lik.initial_states().empty()) MStepX0(lik, theta.data(), sums, p0, &next);
  return next;
}

}  // namespace em_internal

namespace tuner_internal {

// The EM iterations from result->theta_initial (its history, wall times
// and rises in *result); *start gets the iterations and the best iterate in
// theta_end / nll_end, *why the reason it stopped early. True when the
// relative NLL change met em_tolerance.
template <class Model, class Meas>
bool EmIterations(const InnovationLikelihood<Model, Meas>& lik, const FilterSpec& spec,
                  const TunerOptions& options, const std::vector<FilterData>& datasets,
                  TuneResult* out, TuneStart* start, std::string* why) {
  using namespace em_internal;
  using Clock = std::chrono::steady_clock;
  TuneResult& result = *out;
  const Mat<Model::kStateDim, Model::kStateDim> p0 =
      likelihood_internal::InitialFromVector<Model::kStateDim>(spec.p0, "P0").matrix;
  std::vector<double> theta = result.theta_initial;
  double nll = result.nll_initial;
  start->theta_end = theta, start->nll_end = nll;
  result.nll_history.push_back(nll);
  if (!std::isfinite(nll)) {  // run it again for the step and time where it failed
    std::string reason;
    double again = kInf;
    lik.Nll(theta.data(), &again, &reason);
    *why = "the filter failed at the initial guess";
    if (!reason.empty()) *why += ": " + reason;
  }
  while (why->empty() && start->iterations < options.max_iterations) {
    const auto t_it = Clock::now();
    EmSums<Model::kStateDim, Meas::kDim> sums;
    std::vector<double> next;
    try {
      if (!EStep(lik, SpecAt(lik, spec, theta.data()), theta.data(), datasets, &sums, why)) break;
      next = MStepTheta(lik, theta, sums, p0);
    } catch (const std::exception& e) {  // InputError from the M-step, NumericalError
      *why = std::string("M-step: ") + e.what();
      break;
    }
    double nll_next = kInf;
    if (!lik.Nll(next.data(), &nll_next, why) || !std::isfinite(nll_next)) {
      *why = "the filter failed at the M-step's Q and R: " + *why;
      break;
    }
    ++start->iterations;
    const double change = nll_next - nll;
    // A rise counts above the rounding of a sum of many terms.
    result.nll_increases += change > 1e-12 * std::abs(nll_next);
    result.nll_history.push_back(nll_next);
    result.iteration_wall_s.push_back(std::chrono::duration<double>(Clock::now() - t_it).count());
    if (options.progress)
      options.progress(
          {.phase = "em", .iteration = start->iterations, .value = nll_next, .change = change});
    theta = next;
    nll = nll_next;
    if (nll < start->nll_end) start->theta_end = theta, start->nll_end = nll;
    if (std::abs(change) <= options.em_tolerance * std::abs(nll)) return true;
  }
  return false;
}

template <class Model, class Meas>
void RunEm(const Objective<Model, Meas>& objective, const TuneProblem& problem, TuneResult* out) {
  const FilterSpec& spec = problem.spec;
  const TunerOptions& options = problem.options;
  const std::vector<double>&lower = problem.lower, &upper = problem.upper;
  const InnovationLikelihood<Model, Meas>& lik = objective.likelihood();
  TuneResult& result = *out;
  if (!lik.initial_states().empty() && spec.has_t0)  // x^s_0 must be x(t_0)
    for (const FilterData& d : problem.datasets)
      if (!d.t.empty() && d.t.front() > spec.t0)
        throw InputError(
            "--estimate-x0 with the em estimator needs the prior at the first row (t0 " +
            FormatNumber(spec.t0) + " is before the first row" +
            (d.path.empty() ? "" : " of " + d.path) + ", t = " + FormatNumber(d.t.front()) + ")");
  TuneStart start;
  start.theta_start = result.theta_initial;
  start.nll_start = result.nll_initial;
  std::string why;
  const bool converged = EmIterations(lik, spec, options, problem.datasets, &result, &start, &why);
  const std::vector<double> best = start.theta_end;
  const double best_nll = start.nll_end;
  result.trace = result.nll_history;
  start.ok = std::isfinite(best_nll);
  start.theta_end = best;
  start.nll_end = start.ok ? best_nll : kInf;
  start.termination =
      converged     ? "relative NLL change below " + FormatNumber(options.em_tolerance)
      : why.empty() ? "iteration limit (" + std::to_string(options.max_iterations) + ") reached"
                    : "stopped at iteration " + std::to_string(start.iterations + 1) + ": " + why;
  result.starts.push_back(start);
  result.iterations = start.iterations;
  result.termination = start.termination;
  if (!start.ok) {
    result.status = TuneStatus::kAllStartsFailed;
    result.message = "EM: " + start.termination;
    result.nll_tuned = kInf;
    return;
  }
  result.best_start = 0;
  result.status = converged ? TuneStatus::kConverged : TuneStatus::kNoConvergence;
  result.theta = best;
  result.nll_tuned = best_nll;
  result.message =
      "EM, " + std::to_string(start.iterations) + " iteration(s)" +
      (result.nll_increases ? ", the NLL rose at " + std::to_string(result.nll_increases) +
                                  " (the E-step is approximate for this filter)"
                            : "");
  if (options.em_compare_ml && !best.empty()) {
    bool ml_converged = false;
    const TuneStart ml = RunLbfgs(objective, options, lower, upper, best, &ml_converged,
                                  {.phase = "ml from EM's solution"});
    if (ml.ok) result.nll_ml_from_em = ml.nll_end;
  }
  // The same verdict as the ml form's (adaptive/tune_verdict.h): Q's and R's
  // log parameters have their constraint's 0 as lower bound.
  const Eigen::MatrixXd H = FinishTune(objective, spec, options, lower, upper, &result);
  ApplyVerdict(H, result.is_log, lower, upper, NllFunction(objective), &result);
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_EM_H_
