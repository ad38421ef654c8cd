#include "adaptive/identifiability.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "src/core/types.h"

namespace estlab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A component of an eigenvector counts when |v_i| >= this * max |v|.
constexpr double kSignificant = 0.05;

std::string Plain(const std::string& name, bool is_log) {
  return is_log && name.rfind("log ", 0) == 0 ? name.substr(4) : name;
}

// p^e as text: "L", "/L" style is left to the caller; here "L^2", "L^0.5".
std::string Power(const std::string& name, double e) {
  const double a = std::abs(e);
  if (std::abs(a - 1.0) < 0.02) return name;
  return name + "^" + FormatNumber(std::round(a * 100.0) / 100.0);
}

// The combination left determined by the flat direction v over two log
// parameters i, j: p_i * p_j^(-v_i / v_j), its value and SE.
std::string TwoLogSentence(const Eigen::VectorXd& v, int i, int j, const std::vector<double>& theta,
                           const std::vector<std::string>& plain, const Eigen::MatrixXd& cov) {
  const double e = -v(i) / v(j);  // exponent of p_j in p_i * p_j^e
  Eigen::VectorXd w = Eigen::VectorXd::Zero(v.size());
  w(i) = 1.0;
  w(j) = e;
  const double log_value = theta[i] + e * theta[j];
  const double value = std::exp(log_value);
  const double se_log = std::sqrt(std::max(0.0, w.dot(cov * w)));
  const std::string combo = plain[i] + (e < 0 ? "/" : "*") + Power(plain[j], e);
  return plain[i] + " and " + plain[j] +
         " are not separately identifiable: the data pin down only " + combo + " = " +
         FormatNumber(value) + " (SE " + FormatNumber(value * se_log) +
         "); fix one of them (--param) to estimate the other";
}

}  // namespace

std::vector<int> SignificantComponents(const Eigen::VectorXd& v) {
  const double vmax = v.cwiseAbs().maxCoeff();
  std::vector<int> involved;
  for (int i = 0; i < int(v.size()); ++i)
    if (vmax > 0 && std::abs(v(i)) >= kSignificant * vmax) involved.push_back(i);
  return involved;
}

std::string DirectionText(const Eigen::VectorXd& v, const std::vector<std::string>& names) {
  Eigen::Index top = 0;
  v.cwiseAbs().maxCoeff(&top);
  const double sign = v(top) < 0 ? -1.0 : 1.0;
  std::string out;
  for (int i : SignificantComponents(v)) {
    const double c = std::round(sign * v(i) * 100.0) / 100.0;
    out += (out.empty() ? (c < 0 ? "-" : "") : (c < 0 ? " - " : " + ")) +
           FormatNumber(std::abs(c)) + " " + names[i];
  }
  return out;
}

Eigen::VectorXd FisherScale(const std::vector<double>& theta, const std::vector<bool>& is_log,
                            const std::vector<double>& start) {
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(int(theta.size()));
  for (size_t i = 0; i < theta.size(); ++i) {
    const double from = i < start.size() ? std::abs(start[i]) : 0.0;
    // Ended at 0 relative to its start: the start's units (a parameter that
    // moved far but stayed away from 0 keeps its own, or its curvature in
    // the start's units would make every other direction look flat).
    const double s = std::abs(theta[i]) < kAtZero * from ? from : std::abs(theta[i]);
    if (!is_log[i] && s > 0.0) scale(int(i)) = s;
  }
  return scale;
}

// The sentence for flat (or downward) eigen-direction v with eigenvalue
// `value` of the Fisher matrix, over the parameters `involved` in it.
std::string FlatSentence(const Eigen::VectorXd& v, double value, bool downwards,
                         const std::vector<int>& involved, const std::vector<std::string>& names,
                         const std::vector<std::string>& plain, const std::vector<bool>& is_log,
                         const std::vector<double>& theta, const Eigen::MatrixXd& cov) {
  if (downwards)
    return "the NLL curves downwards along " + DirectionText(v, names) + " (eigenvalue " +
           FormatNumber(value) +
           "): not a minimum (the optimiser stopped on a ridge or in a curved flat "
           "valley); fix one of these parameters or restart from here, no "
           "standard errors for them";
  if (involved.size() == 1)
    return "the data do not determine " + plain[involved[0]] +
           ": the NLL is flat along it (no standard error)";
  if (involved.size() == 2 && is_log[involved[0]] && is_log[involved[1]])
    return TwoLogSentence(v, involved[0], involved[1], theta, plain, cov);
  std::string list;
  for (size_t a = 0; a < involved.size(); ++a)
    list += (a ? (a + 1 == involved.size() ? " and " : ", ") : "") + plain[involved[a]];
  return list + " are not separately identifiable: the NLL is flat along " +
         DirectionText(v, names) + " (no standard errors for them)";
}

FisherReport AnalyseFisher(const Eigen::MatrixXd& H, const std::vector<double>& theta,
                           const std::vector<std::string>& names, const std::vector<bool>& is_log,
                           const std::vector<double>& start) {
  const int k = int(H.rows());
  FisherReport r;
  r.std_errors.assign(k, kInf);
  r.correlation.assign(size_t(k) * k, std::numeric_limits<double>::quiet_NaN());
  if (k == 0) {
    r.positive_definite = true;
    return r;
  }
  const Eigen::MatrixXd Hs = 0.5 * (H + H.transpose());
  if (!Hs.allFinite()) {
    r.sentences.push_back(
        "no standard errors: the Hessian of the NLL is not finite at the optimum (the filter "
        "fails within one finite-difference step of it)");
    return r;
  }
  // Relative units for the parameters optimised on their natural scale (a
  // friction of 5e-5 N m s next to log variances): theta_i = s_i u_i with
  // s_i = |theta_i| (|start_i| for one that ended at 0, 1 for log
  // parameters and zeros), so that the flatness test compares like with
  // like, and a parameter at 0 is not flat for being small. cov = S cov_u S.
  const Eigen::VectorXd scale = FisherScale(theta, is_log, start);
  const Eigen::MatrixXd Hu = scale.asDiagonal() * Hs * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Hu);
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const Eigen::MatrixXd& V = eig.eigenvectors();
  for (int j = 0; j < k; ++j) r.eigenvalues.push_back(lambda(j));
  const double top = lambda.cwiseAbs().maxCoeff();
  std::vector<std::string> plain;
  for (int i = 0; i < k; ++i) plain.push_back(Plain(names[i], is_log[i]));

  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(k, k);
  std::vector<bool> unidentified(k, false);
  std::vector<int> flat;
  for (int j = 0; j < k; ++j) {
    if (lambda(j) > kFlatRatio * top) {
      cov += V.col(j) * V.col(j).transpose() / lambda(j);
    } else {
      flat.push_back(j);
    }
  }
  r.positive_definite = flat.empty();
  for (int j : flat) {
    const Eigen::VectorXd v = V.col(j);
    const std::vector<int> involved = SignificantComponents(v);
    for (int i : involved) unidentified[i] = true;
    r.sentences.push_back(FlatSentence(v, lambda(j), lambda(j) < -kFlatRatio * top, involved, names,
                                       plain, is_log, theta, cov));
  }
  cov = scale.asDiagonal() * cov * scale.asDiagonal();
  for (int i = 0; i < k; ++i)
    if (!unidentified[i] && cov(i, i) > 0) r.std_errors[i] = std::sqrt(cov(i, i));
  for (int i = 0; i < k; ++i) {
    for (int l = 0; l < k; ++l) {
      if (!std::isfinite(r.std_errors[i]) || !std::isfinite(r.std_errors[l])) continue;
      // The diagonal is 1 by definition, not cov_ii / sqrt(cov_ii)^2 rounded.
      r.correlation[size_t(i) * k + l] =
          i == l ? 1.0 : cov(i, l) / (r.std_errors[i] * r.std_errors[l]);
    }
  }
  return r;
}

}  // namespace estlab
