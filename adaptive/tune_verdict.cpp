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

// The lowest NLL found along +-t S v from theta (clamped into the box),
// and where; NLL_tuned itself when none is lower by more than the margin.
double ProbeDirection(const Eigen::VectorXd& v, const Eigen::VectorXd& scale,
                      const std::vector<double>& lower, const std::vector<double>& upper,
                      const NllAt& nll, const TuneResult& r, std::vector<double>* at) {
  const double margin = 1e-6 * std::max(1.0, std::abs(r.nll_tuned));
  double best = r.nll_tuned;
  for (double t : {1e-3, 1e-2, 3e-2, 0.1, 0.3}) {
    for (double sign : {1.0, -1.0}) {
      std::vector<double> x = r.theta;
      for (size_t i = 0; i < x.size(); ++i)
        x[i] = std::clamp(x[i] + sign * t * scale(int(i)) * v(int(i)), lower[i], upper[i]);
      const double f = nll(x);
      if (f < best - margin) best = f, *at = x;
    }
  }
  return best;
}

std::string NotAMinimumSentence(double lambda, const Eigen::VectorXd& v, double lower_nll,
                                const std::vector<std::string>& names) {
  return "the NLL curves downwards along " + DirectionText(v, names) + " (Hessian eigenvalue " +
         FormatNumber(lambda) + "; NLL " + FormatNumber(lower_nll) +
         " a short step along it): the optimiser stopped at a saddle, not a minimum; start "
         "elsewhere (--starts), or fix one of these parameters";
}

// The first parameter ending against a bound that is not its constraint.
int AgainstSearchBox(const std::vector<bool>& lower_is_constraint, const std::vector<double>& lower,
                     const std::vector<double>& upper, const TuneResult& r) {
  for (size_t i = 0; i < r.theta.size(); ++i) {
    const int side = NearBound(r.theta[i], lower[i], upper[i], r.is_log[i]);
    if (side > 0 || (side < 0 && !lower_is_constraint[i])) return int(i);
  }
  return -1;
}

}  // namespace

void ApplyVerdict(const Eigen::MatrixXd& H, const std::vector<bool>& lower_is_constraint,
                  const std::vector<double>& lower, const std::vector<double>& upper,
                  const NllAt& nll, TuneResult* result) {
  TuneResult& r = *result;
  if (!r.IsSolutionUsable()) return;
  const std::string before = r.message.empty() ? "" : " (" + r.message + ")";
  if (r.nll_tuned > r.nll_initial + 1e-12 * std::abs(r.nll_initial)) {
    r.status = TuneStatus::kWorseThanStart;
    r.message = "the final NLL " + FormatNumber(r.nll_tuned) + " is above the initial guess's " +
                FormatNumber(r.nll_initial) + ": the fit is worse than where it started" + before;
    return;
  }
  if (r.status == TuneStatus::kNoConvergence) return;  // the optimiser's own word stands
  if (H.size() > 0 && !H.allFinite()) {
    r.status = TuneStatus::kUnverified;
    r.message =
        "the Hessian of the NLL is not finite at the end point (the filter fails within one "
        "finite-difference step of it, often a state the model clips with max, min or sqrt "
        "near 0): it cannot be verified as a minimum; start elsewhere (--starts) or closer to "
        "the data" +
        before;
    return;
  }
  std::vector<bool> free(r.theta.size());
  for (size_t i = 0; i < free.size(); ++i) free[i] = !r.at_bound[i];
  double lambda_min = 0.0, lambda_max = 0.0;
  Eigen::VectorXd v;
  const Eigen::VectorXd scale = FisherScale(r.theta, r.is_log, r.theta_initial);
  if (H.size() > 0 && FreeCurvature(H, scale, free, &lambda_min, &lambda_max, &v) &&
      lambda_min < -kNegativeRatio * lambda_max) {
    std::vector<double> at;
    const double lower_nll = ProbeDirection(v, scale, lower, upper, nll, r, &at);
    if (lower_nll < r.nll_tuned) {
      r.status = TuneStatus::kNotAMinimum;
      r.message = NotAMinimumSentence(lambda_min, v, lower_nll, r.names) + before;
      return;
    }
    r.identifiability.push_back(
        "the finite-difference Hessian curves downwards along " + DirectionText(v, r.names) +
        " (eigenvalue " + FormatNumber(lambda_min) +
        "), but no lower NLL lies along it (steps 1e-3 .. 0.3): the NLL is not smooth here "
        "(max, min or abs in the model), so its curvature and the standard errors are "
        "unreliable");
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
