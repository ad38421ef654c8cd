#include "src/filters/sigma_rules.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <string>
#include <utility>

#include "src/core/types.h"

namespace estlab {

SigmaRule ParseSigmaRule(const std::string& name) {
  if (name == "unscented" || name == "ukf") return SigmaRule::kUnscented;
  if (name == "cubature" || name == "ckf") return SigmaRule::kCubature;
  if (name == "gauss-hermite" || name == "ghkf") return SigmaRule::kGaussHermite;
  throw InputError("unknown sigma-point rule '" + name +
                   "' (expected unscented, cubature or gauss-hermite)");
}

const char* SigmaRuleName(SigmaRule rule) {
  switch (rule) {
    case SigmaRule::kUnscented:
      return "unscented";
    case SigmaRule::kCubature:
      return "cubature";
    case SigmaRule::kGaussHermite:
      return "gauss-hermite";
  }
  return "?";
}

bool SigmaPointOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(std::isfinite(alpha) && alpha > 0))
    return fail("alpha: must be > 0 and finite, got " + FormatNumber(alpha));
  if (!std::isfinite(beta)) return fail("beta: must be finite");
  if (!std::isfinite(kappa)) return fail("kappa: must be finite");
  if (gh_order < 1 || gh_order > 20)
    return fail("gh-order: must be in [1, 20], got " + std::to_string(gh_order));
  if (!(std::isfinite(jitter) && jitter >= 0))
    return fail("jitter: must be >= 0 and finite, got " + FormatNumber(jitter));
  return true;
}

long NumSigmaPoints(int n, const SigmaPointOptions& options) {
  switch (options.rule) {
    case SigmaRule::kUnscented:
      return 2L * n + 1;
    case SigmaRule::kCubature:
      return 2L * n;
    case SigmaRule::kGaussHermite: {
      long count = 1;
      for (int i = 0; i < n; ++i) {
        count *= options.gh_order;
        if (count > kMaxSigmaPoints) return kMaxSigmaPoints + 1;
      }
      return count;
    }
  }
  return 0;
}

void GaussHermite1D(int order, Eigen::VectorXd* nodes, Eigen::VectorXd* weights) {
  // Jacobi matrix of the monic probabilists' Hermite polynomials,
  // x He_k = He_{k+1} + k He_{k-1}:  J_{k-1,k} = J_{k,k-1} = sqrt(k).
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(order, order);
  for (int k = 1; k < order; ++k) J(k - 1, k) = J(k, k - 1) = std::sqrt(double(k));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(J);
  // nodes = eigenvalues (ascending); w_k = mu_0 v_k(0)^2 with mu_0 = 1.
  Eigen::VectorXd x = eig.eigenvalues();
  Eigen::VectorXd w = eig.eigenvectors().row(0).transpose().array().square();
  // The rule is symmetric; enforce it so odd moments vanish exactly.
  nodes->resize(order);
  weights->resize(order);
  for (int k = 0; k < order; ++k) {
    (*nodes)(k) = 0.5 * (x(k) - x(order - 1 - k));
    (*weights)(k) = 0.5 * (w(k) + w(order - 1 - k));
  }
  *weights /= weights->sum();
}

bool SigmaPointOptions::IsValidFor(int n, std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!IsValid(error)) return false;
  if (n < 1) return fail("sigma points need a state dimension >= 1");
  if (rule == SigmaRule::kUnscented && !(n + kappa > 0))
    return fail("kappa: the unscented rule needs n + kappa > 0, got n = " + std::to_string(n) +
                ", kappa = " + FormatNumber(kappa));
  // The unscented points lie alpha sqrt(n + kappa) standard deviations from
  // the mean; beyond 1000 their weights cancel to rounding and the estimate
  // stops moving.
  if (rule == SigmaRule::kUnscented && !(alpha * std::sqrt(n + kappa) <= 1000.0))
    return fail("alpha, kappa: the unscented points would lie alpha sqrt(n + kappa) = " +
                FormatNumber(alpha * std::sqrt(n + kappa)) +
                " standard deviations from the mean; at most 1000");
  if (!(std::abs(beta) <= 1e6))
    return fail("beta: must be in [-1e6, 1e6], got " + FormatNumber(beta));
  if (NumSigmaPoints(n, *this) > kMaxSigmaPoints)
    return fail("gh-order: Gauss-Hermite order " + std::to_string(gh_order) + " in " +
                std::to_string(n) + " dimensions needs more than " +
                std::to_string(kMaxSigmaPoints) + " points");
  return true;
}

UnitSigmaPoints MakeUnitSigmaPoints(int n, const SigmaPointOptions& options) {
  std::string error;
  if (!options.IsValidFor(n, &error)) throw InputError(error);
  const long count = NumSigmaPoints(n, options);
  UnitSigmaPoints unit;
  unit.points = Eigen::MatrixXd::Zero(n, count);
  unit.mean_weights.resize(count);
  switch (options.rule) {
    case SigmaRule::kUnscented: {
      const double a2 = options.alpha * options.alpha;
      const double lambda = a2 * (n + options.kappa) - n;  // lambda = alpha^2 (n + kappa) - n
      const double gamma = std::sqrt(n + lambda);          // gamma = sqrt(n + lambda)
      unit.mean_weights.setConstant(1.0 / (2.0 * (n + lambda)));
      unit.mean_weights(0) = lambda / (n + lambda);
      for (int i = 0; i < n; ++i) {
        unit.points(i, 1 + i) = gamma;
        unit.points(i, 1 + n + i) = -gamma;
      }
      unit.cov_weights = unit.mean_weights;
      unit.cov_weights(0) += 1.0 - a2 + options.beta;  // Wc_0 = Wm_0 + 1 - alpha^2 + beta
      break;
    }
    case SigmaRule::kCubature: {
      const double r = std::sqrt(double(n));
      for (int i = 0; i < n; ++i) {
        unit.points(i, i) = r;
        unit.points(i, n + i) = -r;
      }
      unit.mean_weights.setConstant(1.0 / (2.0 * n));
      unit.cov_weights = unit.mean_weights;
      break;
    }
    case SigmaRule::kGaussHermite: {
      Eigen::VectorXd nodes, weights;
      GaussHermite1D(options.gh_order, &nodes, &weights);
      const int p = options.gh_order;
      // Point j: coordinate i takes node digit_i(j), j written in base p.
      for (long j = 0; j < count; ++j) {
        long rest = j;
        double w = 1.0;
        for (int i = 0; i < n; ++i) {
          const int digit = int(rest % p);
          rest /= p;
          unit.points(i, j) = nodes(digit);
          w *= weights(digit);
        }
        unit.mean_weights(j) = w;
      }
      unit.mean_weights /= unit.mean_weights.sum();
      unit.cov_weights = unit.mean_weights;
      break;
    }
  }
  return unit;
}

SigmaPointSet MakeSigmaPointSet(int n, const SigmaPointOptions& options) {
  UnitSigmaPoints unit = MakeUnitSigmaPoints(n, options);
  SigmaPointSet set;
  set.unit_points = std::move(unit.points);
  set.mean_weights = std::move(unit.mean_weights);
  set.cov_weights = std::move(unit.cov_weights);
  set.jitter = options.jitter;
  const Eigen::Index count = set.unit_points.cols();
  set.axis_index.assign(count, -1);
  set.axis_scale.setZero(count);
  set.axis_aligned = true;
  for (Eigen::Index i = 0; i < count && set.axis_aligned; ++i) {
    for (int k = 0; k < n; ++k) {
      if (set.unit_points(k, i) == 0.0) continue;
      if (set.axis_index[i] >= 0) set.axis_aligned = false;
      set.axis_index[i] = k;
      set.axis_scale(i) = set.unit_points(k, i);
    }
  }
  return set;
}

}  // namespace estlab
