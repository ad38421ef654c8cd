// Standard errors, correlations and identifiability from the observed Fisher
// information H (the Hessian of the NLL at the optimum, on the tuner's theta
// scale), in plain types: compiled once, not per model.
//
//   theta_i = s_i u_i, s_i = |theta_i| for a parameter on its natural scale
//   (relative units), |start_i| for one that ended at 0 relative to its
//   start (|theta_i| < kAtZero |start_i|: a laminar outflow at its >= 0
//   bound), 1 for a log parameter and where both are 0
//   S H S = V diag(lambda) V^T   (ascending lambda)
//   a direction v_j is flat when lambda_j <= kFlatRatio * max |lambda|
//   (the data do not determine theta along it); negative curvature there
//   means the optimiser stopped off a minimum
//   cov = S (sum over the other directions of v_j v_j^T / lambda_j) S
//   SE_i = sqrt(cov_ii), +inf when theta_i has a component in a flat direction
//
// A flat direction is described by the parameters it involves. On two log
// parameters, v = (a, b) leaves p1^b p2^-a determined: v = (1, 1)/sqrt 2 over
// (log g, log L) is "only g/L is determined", with that combination's value
// and its SE sqrt(w^T cov w) (finite: w is orthogonal to v).
//
// Usage:
//   FisherReport r = AnalyseFisher(H, theta, names, is_log, theta_initial);
//   for (const std::string& s : r.sentences) std::cout << s << "\n";
#ifndef ESTLAB_ADAPTIVE_IDENTIFIABILITY_H_
#define ESTLAB_ADAPTIVE_IDENTIFIABILITY_H_

#include <Eigen/Core>
#include <string>
#include <vector>

namespace estlab {

struct FisherReport {
  std::vector<double> std_errors;   // theta scale, +inf where not identifiable
  std::vector<double> correlation;  // k x k row-major, NaN where not identifiable
  std::vector<double> eigenvalues;  // of H, ascending
  std::vector<std::string> sentences;
  bool positive_definite = false;  // no flat or negative direction
};

// Relative eigenvalue below which a direction of H counts as flat.
inline constexpr double kFlatRatio = 1e-9;

// A natural-scale parameter below this fraction of its start has ended at 0.
inline constexpr double kAtZero = 1e-6;

// The relative units above (1 for log parameters and where theta and start
// are 0). start: the optimiser's start (theta_initial), or empty.
Eigen::VectorXd FisherScale(const std::vector<double>& theta, const std::vector<bool>& is_log,
                            const std::vector<double>& start = {});

// The components of v of at least 5 % of its largest, in order.
std::vector<int> SignificantComponents(const Eigen::VectorXd& v);

// v in parameter names, its largest component positive, two decimals:
// "0.71 log l1 - 0.7 log q_h1".
std::string DirectionText(const Eigen::VectorXd& v, const std::vector<std::string>& names);

// names: the parameters as in the report ("L", "qc", "r_theta"); is_log:
// whether theta_i is the log of that parameter; start: where the optimiser
// started (the units of a parameter that ended at 0), or empty.
FisherReport AnalyseFisher(const Eigen::MatrixXd& H, const std::vector<double>& theta,
                           const std::vector<std::string>& names, const std::vector<bool>& is_log,
                           const std::vector<double>& start = {});

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_IDENTIFIABILITY_H_
