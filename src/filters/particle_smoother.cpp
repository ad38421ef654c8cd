#include "src/filters/particle_smoother.h"

#include <limits>

namespace estlab {

bool BackwardWeights(const ParticleCloud& means, const std::vector<double>& weights,
                     const Eigen::MatrixXd& L, const Eigen::VectorXd& x_next,
                     std::vector<double>* v) {
  const Eigen::Index n = means.cols();
  v->resize(size_t(n));
  // log v_i = log w_i - |L^-1 (x' - m_i)|^2 / 2 (the Gaussian's constant cancels)
  // d = L^-1 (x' - m_i) for all i. Called M K times per smoothing: the
  // buffer is kept per thread so that only the first call allocates.
  thread_local Eigen::MatrixXd d;
  d.resize(means.rows(), n);
  d = (-means).colwise() + x_next;
  L.triangularView<Eigen::Lower>().solveInPlace(d);
  double max_log = -std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < n; ++i) {
    const double log_v = weights[size_t(i)] > 0.0
                             ? std::log(weights[size_t(i)]) - 0.5 * d.col(i).squaredNorm()
                             : -std::numeric_limits<double>::infinity();
    (*v)[size_t(i)] = log_v;
    max_log = std::max(max_log, log_v);
  }
  if (!std::isfinite(max_log)) return false;
  double sum = 0.0;
  for (double& x : *v) {
    x = std::exp(x - max_log);
    sum += x;
  }
  for (double& x : *v) x /= sum;
  return true;
}

size_t SampleIndex(const std::vector<double>& p, double u) {
  double c = 0.0;
  size_t last_positive = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    if (p[i] <= 0.0) continue;
    last_positive = i;
    c += p[i];
    if (u < c) return i;
  }
  return last_positive;  // rounding: the sum fell short of u
}

}  // namespace estlab
