#include "src/filters/particle.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace estlab {

double LogSumExp(const Eigen::VectorXd& v) {
  if (v.size() == 0) return -std::numeric_limits<double>::infinity();
  const double m = v.maxCoeff();
  if (!std::isfinite(m)) return m;  // all -inf (or a +inf / NaN present)
  // log sum exp(v_i) = m + log sum exp(v_i - m)
  return m + std::log((v.array() - m).exp().sum());
}

namespace {

// Walks the cumulative weights c_i = w_0 + ... + w_i with ascending points
// u_0 <= u_1 <= ... in [0, 1): u_k goes to the first i with u_k < c_i. Writes
// indices[start + k]; the last c is taken as 1 so rounding cannot run off the end.
template <class Points>
void InvertCdf(const std::vector<double>& weights, int count, Points&& point, int start,
               std::vector<int>* indices) {
  const int n = int(weights.size());
  int i = 0;
  double cumulative = weights[0];
  for (int k = 0; k < count; ++k) {
    const double u = point(k);
    while (i < n - 1 && u >= cumulative) cumulative += weights[++i];
    (*indices)[start + k] = i;
  }
}

// `count` sorted uniforms on [0, 1): u_(k) = E_1 + ... + E_{k+1} over
// E_1 + ... + E_{count+1} with E_j standard exponentials (order statistics).
// Streams them through InvertCdf without storing them.
void MultinomialDraws(const std::vector<double>& weights, int count, Rng& rng, int start,
                      std::vector<int>* indices) {
  if (count <= 0) return;
  // Partial sums E_1 + ... + E_{k+1} (count doubles), then the total of
  // count + 1 exponentials normalises them.
  std::vector<double> sums(count);
  double total = 0.0;
  for (int k = 0; k < count; ++k) {
    total += -std::log1p(-rng.Uniform());  // E = -log(1 - U), U in [0, 1)
    sums[k] = total;
  }
  total += -std::log1p(-rng.Uniform());
  InvertCdf(
      weights, count, [&](int k) { return sums[k] / total; }, start, indices);
}

// indices[0, split) and indices[split, N) are each ascending; sorts the
// whole vector by merging them from the back in O(N) (what std::sort gave,
// in O(N log N)). The second run is parked in `scratch` (N doubles, exact for
// indices), so nothing is allocated.
void MergeAscendingRuns(int split, std::vector<double>* scratch, std::vector<int>* indices) {
  std::vector<int>& x = *indices;
  const int n = int(x.size());
  for (int k = split; k < n; ++k) (*scratch)[k - split] = x[k];
  int a = split - 1, b = n - split - 1;
  for (int out = n - 1; b >= 0; --out) {
    const int from_b = int((*scratch)[b]);
    x[out] = (a >= 0 && x[a] > from_b) ? x[a--] : (--b, from_b);
  }
}

}  // namespace

void Resample(const std::vector<double>& weights, ResampleScheme scheme, Rng& rng,
              std::vector<int>* indices) {
  const int n = int(weights.size());
  indices->resize(n);
  if (n == 0) return;
  switch (scheme) {
    case ResampleScheme::kMultinomial:
      MultinomialDraws(weights, n, rng, 0, indices);
      return;
    case ResampleScheme::kSystematic: {
      // u_k = (k + U) / N
      const double u0 = rng.Uniform();
      InvertCdf(
          weights, n, [&](int k) { return (k + u0) / n; }, 0, indices);
      return;
    }
    case ResampleScheme::kStratified:
      // u_k = (k + U_k) / N; the lambda is called once per k, in order.
      InvertCdf(
          weights, n, [&](int k) { return (k + rng.Uniform()) / n; }, 0, indices);
      return;
    case ResampleScheme::kResidual: {
      // floor(N w_i) deterministic copies; the R = N - sum floor(N w_i)
      // others multinomial with weights proportional to N w_i - floor(N w_i).
      int filled = 0;
      std::vector<double> residual(n);
      double residual_sum = 0.0;
      for (int i = 0; i < n; ++i) {
        const double nw = n * weights[i];
        const int copies = std::min(int(std::floor(nw)), n - filled);
        for (int c = 0; c < copies; ++c) (*indices)[filled++] = i;
        residual[i] = std::max(0.0, nw - copies);
        residual_sum += residual[i];
      }
      const int rest = n - filled;
      if (rest > 0) {
        for (double& r : residual) r /= residual_sum;
        MultinomialDraws(residual, rest, rng, filled, indices);
        MergeAscendingRuns(filled, &residual, indices);
      }
      return;
    }
  }
}

}  // namespace estlab
