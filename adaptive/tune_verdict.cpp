// The checks behind TuneStatus; the rules are in tune_verdict.h.
#include "adaptive/tune_verdict.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "adaptive/identifiability.h"
#include "src/core/types.h"

namespace estlab {

int NearBound(double theta, double lower, double upper, bool is_log) {
  const double width = upper - lower;
  const double tol = is_log                 ? 0.1
                     : std::isfinite(width) ? 1e-3 * width
                                            : 1e-6 * std::max(1.0, std::abs(theta));
  if (std::abs(theta - lower) <= tol) return -1;
  if (std::abs(theta - upper) <= tol) return 1;
  return 0;
}

bool FreeCurvature(const Eigen::MatrixXd& H, const Eigen::VectorXd& scale,
                   const std::vector<bool>& free, double* lambda_min, double* lambda_max_abs,
                   Eigen::VectorXd* direction) {
  std::vector<int> idx;
  for (int i = 0; i < int(free.size()); ++i)
    if (free[i]) idx.push_back(i);
  if (idx.empty() || H.rows() != int(free.size()) || !H.allFinite()) return false;
  const int f = int(idx.size());
  Eigen::MatrixXd Hf(f, f);
  for (int a = 0; a < f; ++a)
    for (int b = 0; b < f; ++b)
      Hf(a, b) = 0.5 * (H(idx[a], idx[b]) + H(idx[b], idx[a])) * scale(idx[a]) * scale(idx[b]);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Hf);
  if (eig.info() != Eigen::Success) return false;
  *lambda_min = eig.eigenvalues()(0);
  *lambda_max_abs = eig.eigenvalues().cwiseAbs().maxCoeff();
  direction->setZero(int(free.size()));
  for (int a = 0; a < f; ++a) (*direction)(idx[a]) = eig.eigenvectors()(a, 0);
  return true;
}

namespace {

std::string NotAMinimumSentence(double lambda, const Eigen::VectorXd& v,
                                const std::vector<std::string>& names) {
  return "the NLL curves downwards along " + DirectionText(v, names) + " (Hessian eigenvalue " +
         FormatNumber(lambda) +
         "): the optimiser stopped at a saddle, not a minimum; start elsewhere (--starts), "
         "or fix one of these parameters";
}

// The first parameter ending against a bound that is not its constraint.
int AgainstSearchBox(const std::vector<bool>& lower_is_constraint,
                     const std::vector<double>& lower, const std::vector<double>& upper,
                     const TuneResult& r) {
  for (size_t i = 0; i < r.theta.size(); ++i) {
    const int side = NearBound(r.theta[i], lower[i], upper[i], r.is_log[i]);
    if (side > 0 || (side < 0 && !lower_is_constraint[i])) return int(i);
  }
  return -1;
}

}  // namespace

void ApplyVerdict(const Eigen::MatrixXd& H, const std::vector<bool>& lower_is_constraint,
                  const std::vector<double>& lower, const std::vector<double>& upper,
                  TuneResult* result) {
  TuneResult& r = *result;
  if (!r.IsSolutionUsable()) return;
  const std::string before = r.message.empty() ? "" : " (" + r.message + ")";
  if (r.nll_tuned > r.nll_initial + 1e-12 * std::abs(r.nll_initial)) {
    r.status = TuneStatus::kWorseThanStart;
    r.message = "the final NLL " + FormatNumber(r.nll_tuned) + " is above the initial guess's " +
                FormatNumber(r.nll_initial) + ": the fit is worse than where it started" + before;
    return;
  }
  std::vector<bool> free(r.theta.size());
  for (size_t i = 0; i < free.size(); ++i) free[i] = !r.at_bound[i];
  double lambda_min = 0.0, lambda_max = 0.0;
  Eigen::VectorXd v;
  if (H.size() > 0 &&
      FreeCurvature(H, FisherScale(r.theta, r.is_log), free, &lambda_min, &lambda_max, &v) &&
      lambda_min < -kNegativeRatio * lambda_max) {
    r.status = TuneStatus::kNotAMinimum;
    r.message = NotAMinimumSentence(lambda_min, v, r.names) + before;
    return;
  }
  const int i = AgainstSearchBox(lower_is_constraint, lower, upper, r);
  if (i >= 0) {
    const bool up = NearBound(r.theta[i], lower[i], upper[i], r.is_log[i]) > 0;
    r.status = TuneStatus::kAtBound;
    r.message = r.names[i] + " ended at its " + (up ? "upper" : "lower") + " search bound " +
                FormatNumber(up ? upper[i] : lower[i]) +
                ": the data push it further, so the estimate is the box's, not the data's; "
                "widen the box (--bound-width, --log-lower/--log-upper, --param-bounds) or fix "
                "the parameter" +
                before;
  }
}

}  // namespace estlab
