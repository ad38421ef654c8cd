// Point rules of the sigma-point filters, as unit points of N(0, I): a filter
// maps them to N(m, P) by X_i = m + L xi_i with P = L L^T (Cholesky), and
// forms moments with the mean and covariance weights.
//
// Usage:
//   SigmaPointOptions options;
//   options.rule = SigmaRule::kGaussHermite;
//   options.gh_order = 3;
//   UnitSigmaPoints unit = MakeUnitSigmaPoints(2, options);   // 9 points
//   // E[g(x)] ~= sum_i unit.mean_weights(i) g(m + L unit.points.col(i))
//
// Rules (n = state dimension):
//   unscented (scaled, Julier 2002; Wan & van der Merwe 2000), 2n+1 points:
//     lambda = alpha^2 (n + kappa) - n,  gamma = sqrt(n + lambda)
//     xi_0 = 0, xi_i = gamma e_i, xi_{n+i} = -gamma e_i
//     Wm_0 = lambda / (n + lambda),  Wc_0 = Wm_0 + 1 - alpha^2 + beta,
//     Wm_i = Wc_i = 1 / (2 (n + lambda))
//     exact mean for polynomials of degree <= 3.
//   cubature (spherical-radial, Arasaratnam & Haykin 2009), 2n points:
//     xi = +-sqrt(n) e_i, W = 1 / (2n); exact for degree <= 3.
//   Gauss-Hermite of order p (Ito & Xiong 2000), p^n points: tensor product
//     of the 1-D probabilists' rule (nodes = eigenvalues of the Jacobi matrix
//     of He_k, J_{k,k+1} = sqrt(k), weights = squared first eigenvector
//     components; Golub & Welsch 1969); exact for degree <= 2p - 1 in each
//     coordinate.
//
// WARNING: with small alpha the unscented weights are huge and of both signs
// (alpha = 1e-3, n = 4: Wm_0 ~ -1e6); form means in the centred form
// X_0 + sum_i W_i (X_i - X_0) (WeightedMean in filter_util.h) to keep the
// rounding error down. Gauss-Hermite grows as p^n: n = 6, p = 3 is 729 points.
#ifndef ESTLAB_FILTERS_SIGMA_RULES_H_
#define ESTLAB_FILTERS_SIGMA_RULES_H_

#include <Eigen/Core>
#include <string>
#include <vector>

namespace estlab {

enum class SigmaRule { kUnscented, kCubature, kGaussHermite };

// Parses "unscented" (or "ukf"), "cubature" ("ckf"), "gauss-hermite"
// ("ghkf"); throws InputError.
SigmaRule ParseSigmaRule(const std::string& name);
const char* SigmaRuleName(SigmaRule rule);

struct SigmaPointOptions {
  SigmaRule rule = SigmaRule::kUnscented;
  // Scaled unscented parameters.
  double alpha = 1e-3;
  double beta = 2.0;
  double kappa = 0.0;
  // Gauss-Hermite order p (points per dimension).
  int gh_order = 3;
  // How the measurement update gets its points:
  //   kRedraw:    new points from (x-, P-) (Saerkkae 2013) - includes Q.
  //   kPropagate: the propagated points Phi(X_i) of the last Predict (Wan &
  //               van der Merwe 2000 additive form, FilterPy, paper 003's
  //               code). Their spread does NOT contain Q, so S and the cross
  //               covariance miss Q; equal to the Kalman filter on a linear
  //               model only when Q = 0. (An Update not preceded by a Predict
  //               draws new points either way.)
  enum class Update { kPropagate, kRedraw } update = Update::kRedraw;
  // Added times I to P before drawing points, to P- and to S (paper 003: 1e-3).
  double jitter = 0.0;

  // Messages start with the option key ("alpha: must be > 0 ...").
  bool IsValid(std::string* error) const;
  // IsValid, and usable in n dimensions (n + kappa > 0 for the unscented
  // rule, at most kMaxSigmaPoints points).
  bool IsValidFor(int n, std::string* error) const;
};

// The points of N(0, I_n) (n x L) and their weights (length L).
struct UnitSigmaPoints {
  Eigen::MatrixXd points;
  Eigen::VectorXd mean_weights;
  Eigen::VectorXd cov_weights;
};

// Largest Gauss-Hermite point set accepted (p^n).
// The unit points of a rule with what drawing them needs, made once per
// filter (and per likelihood): the points xi_i, weights Wm_i, Wc_i, the
// jitter, and whether every xi_i lies on an axis (unscented and cubature:
// xi_i = s_i e_k, so L xi_i = s_i L e_k, a scaled column of L instead of a
// matrix-vector product; the same numbers: the other terms are exact zeros).
struct SigmaPointSet {
  Eigen::MatrixXd unit_points;  // n x count
  Eigen::VectorXd mean_weights, cov_weights;
  double jitter = 0.0;
  bool axis_aligned = false;
  std::vector<int> axis_index;  // -1: xi_i = 0
  Eigen::VectorXd axis_scale;
};
// Throws InputError for invalid options.
SigmaPointSet MakeSigmaPointSet(int n, const SigmaPointOptions& options);

inline constexpr long kMaxSigmaPoints = 200000;

// Number of points of the rule in n dimensions (p^n may exceed int; long).
long NumSigmaPoints(int n, const SigmaPointOptions& options);

// Throws InputError for invalid options, n < 1, n + kappa <= 0 (unscented),
// or more than kMaxSigmaPoints points.
UnitSigmaPoints MakeUnitSigmaPoints(int n, const SigmaPointOptions& options);

// 1-D probabilists' Gauss-Hermite rule of `order` points for N(0, 1), nodes
// ascending, weights summing to 1, symmetrised (x_k = -x_{p-1-k}).
void GaussHermite1D(int order, Eigen::VectorXd* nodes, Eigen::VectorXd* weights);

}  // namespace estlab

#endif  // ESTLAB_FILTERS_SIGMA_RULES_H_
