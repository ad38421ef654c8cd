// The tuner's result once the optimum is known (part of the tuner,
// adaptive/tuner_impl.h): the tuned Q, R and spec, standard errors and
// identifiability, the poorly-identified and at-bound flags, and the
// Hessian the verdict (adaptive/tune_verdict.h) reads.
#ifndef ESTLAB_ADAPTIVE_TUNER_RESULT_H_
#define ESTLAB_ADAPTIVE_TUNER_RESULT_H_

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <vector>

#include "adaptive/tune_verdict.h"
#include "adaptive/tuner.h"
#include "adaptive/tuner_information.h"
#include "adaptive/tuner_objective.h"

namespace estlab {
namespace tuner_internal {

// Whether theta ends at or near one of its bounds (NearBound).
inline bool AtBound(double theta, double lower, double upper, bool is_log) {
  return NearBound(theta, lower, upper, is_log) != 0;
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
// at-bound flags. Returns the Hessian H (NaN when the filter fails near the
// optimum), which the verdict reads.
template <class Model, class Meas>
Eigen::MatrixXd FinishTune(const Objective<Model, Meas>& objective, const FilterSpec& spec,
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

  // The Hessian (for the verdict, always), standard errors, identifiability.
  Eigen::MatrixXd H;
  if (!ObservedFisher(objective, result.theta, options.hessian_step, lower, upper, &H))
    H.setConstant(k, k, std::numeric_limits<double>::quiet_NaN());
  FillUncertainty(objective, options, H, &result);
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
  return H;
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNER_RESULT_H_
