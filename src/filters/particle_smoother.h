// The forward-filtering backward-simulation particle smoother (FFBSi;
// Godsill, Doucet & West 2004; Saerkkae & Svensson 2023, ch. 15) on the
// bootstrap particle filter's recorded clouds. The forward pass records, for
// each step k, the filtered particles x_k^i with their weights w_k^i, and for
// the prediction to step k + 1 the propagated means m_k^i = Phi(x_k^i) and the
// process noise Q_k (the filter's own model: x_{k+1} = Phi(x_k) + q_k,
// q_k ~ N(0, Q_k)). No model is evaluated in the backward pass.
//
// Backward simulation of one trajectory:
//   b_K ~ Categorical(w_K^1..n)
//   for k = K-1, ..., 0:
//     v_k^i = w_k^i N(x_{k+1}^{b_{k+1}}; m_k^i, Q_k)          (backward weights)
//     b_k ~ Categorical(v_k / sum_i v_k^i)
//   trajectory x_{0:K} = (x_0^{b_0}, ..., x_K^{b_K})
// computed in logs: log v_k^i = log w_k^i - |L_k^-1 (x' - m_k^i)|^2 / 2 with
// L_k L_k^T = Q_k (the normalising constant cancels). The smoothed mean and
// variance of each step are the sample mean and (M - 1)-variance of M
// trajectories; their Monte Carlo standard error is sqrt(var / M) when the
// trajectories are independent given the clouds.
//
// Usage:
//   ParticleSmoother<2> ps;
//   ps.AddFiltered(pf.particles(), pf.weights());                  // step 0
//   for k = 1..K:
//     transition.StepCloud(pf.particles(), t0, t1, &means);        // m = Phi(x)
//     if (!ps.AddPredicted(means, Q, &why)) ...;                   // Q must be SPD
//     pf.Predict(t0, t1, Q); pf.Update(z, R);
//     ps.AddFiltered(pf.particles(), pf.weights());
//   ps.Smooth(100, seed, &why);   ps.mean(k), ps.var(k), ps.trajectory(j, k)
//
// WARNING: it stores 2 n N_p doubles per step (clouds and means): 10^4
// particles, 2 states and 1000 steps are 320 MB. Cost: M N_p n^2 per step.
#ifndef ESTLAB_FILTERS_PARTICLE_SMOOTHER_H_
#define ESTLAB_FILTERS_PARTICLE_SMOOTHER_H_

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "src/core/random.h"
#include "src/core/types.h"

namespace estlab {

using ParticleCloud = Eigen::MatrixXd;  // n x N_p, one particle per column

// v_i proportional to w_i N(x_next; m_i, L L^T), normalised to sum 1 (the
// backward weights of FFBSi), computed in logs so that a x_next far from every
// m_i still gives the nearest its weight. `weights` sum to 1; L is lower
// triangular. False when no v_i is positive and finite (no positive weight,
// or a non-finite particle).
bool BackwardWeights(const ParticleCloud& means, const std::vector<double>& weights,
                     const Eigen::MatrixXd& L, const Eigen::VectorXd& x_next,
                     std::vector<double>* v);

// The index i with cumulative sum_{j <= i} p_j > u (u in [0, 1)), clamped
// to the last index with a positive p.
size_t SampleIndex(const std::vector<double>& p, double u);

template <int N>
class ParticleSmoother {
 public:
  void Clear() { steps_.clear(); }
  // Step k's filtered cloud; the first call is step 0.
  void AddFiltered(const ParticleCloud& particles, const std::vector<double>& weights) {
    if (steps_.empty() || steps_.back().has_filtered) steps_.emplace_back();
    Step& s = steps_.back();
    s.particles = particles;
    s.weights = weights;
    s.has_filtered = true;
  }
  // A second measurement at the same time replaces the newest cloud.
  void ReplaceFiltered(const ParticleCloud& particles, const std::vector<double>& weights) {
    steps_.back().particles = particles;
    steps_.back().weights = weights;
  }
  // The prediction from the newest filtered step: m_i = Phi(x_i) and Q. False
  // with the reason when Q is not positive definite (the backward weights
  // need the transition density).
  bool AddPredicted(const ParticleCloud& means, const Mat<N, N>& Q, std::string* why) {
    const Eigen::LLT<Mat<N, N>> llt(Q);
    if (llt.info() != Eigen::Success || !Q.allFinite()) {
      *why =
          "the particle smoother needs a positive definite process noise Q (the density of "
          "the transition); give every state some noise, e.g. --q-white-accel or a Q "
          "diagonal with no zero";
      return false;
    }
    steps_.back().means = means;
    steps_.back().L = llt.matrixL();
    steps_.emplace_back();  // step k + 1, its cloud to come
    return true;
  }
  // Forgets a prediction whose filtered cloud never came.
  void DropUnfinishedStep() {
    if (!steps_.empty() && !steps_.back().has_filtered) steps_.pop_back();
  }
  size_t filtered_steps() const { return steps_.size(); }

  // Draws M trajectories (one Rng stream from `seed`) and their moments.
  // False with the step in *why when no backward weight is usable.
  bool Smooth(int trajectories, uint64_t seed, std::string* why);

  size_t size() const { return mean_.size(); }
  int trajectories() const { return M_; }
  const Vec<double, N>& mean(size_t k) const { return mean_[k]; }
  const Vec<double, N>& var(size_t k) const { return var_[k]; }
  // Trajectory j at step k.
  Vec<double, N> trajectory(int j, size_t k) const {
    return steps_[k].particles.col(Eigen::Index(index_[size_t(j) * steps_.size() + k]));
  }

 private:
  struct Step {
    ParticleCloud particles, means;  // means: Phi of particles (the prediction to k + 1)
    std::vector<double> weights;
    Eigen::MatrixXd L;  // chol(Q) of the prediction to k + 1
    bool has_filtered = false;
  };
  std::vector<Step> steps_;
  int M_ = 0;
  std::vector<uint32_t> index_;  // M x K ancestor indices b_k of each trajectory
  std::vector<Vec<double, N>> mean_, var_;
};

template <int N>
bool ParticleSmoother<N>::Smooth(int trajectories, uint64_t seed, std::string* why) {
  const size_t K = steps_.size();
  if (K == 0 || !steps_.back().has_filtered || trajectories < 2) {
    *why = K == 0 ? "particle smoother: no filtered step recorded"
           : trajectories < 2
               ? "particle smoother: --smoother-trajectories must be at least 2, got " +
                     std::to_string(trajectories)
               : "particle smoother: the last prediction has no filtered cloud";
    return false;
  }
  M_ = trajectories;
  index_.assign(size_t(M_) * K, 0);
  Rng rng(seed);
  std::vector<double> v;
  for (int j = 0; j < M_; ++j) {
    uint32_t* b = &index_[size_t(j) * K];
    b[K - 1] = uint32_t(SampleIndex(steps_[K - 1].weights, rng.Uniform()));
    for (size_t k = K - 1; k-- > 0;) {
      const Step& s = steps_[k];
      const Eigen::VectorXd x_next = steps_[k + 1].particles.col(b[k + 1]);
      if (!BackwardWeights(s.means, s.weights, s.L, x_next, &v)) {
        *why = "particle smoother: no backward weight is positive and finite at step " +
               std::to_string(k);
        return false;
      }
      b[k] = uint32_t(SampleIndex(v, rng.Uniform()));
    }
  }
  mean_.assign(K, Vec<double, N>::Zero());
  var_.assign(K, Vec<double, N>::Zero());
  for (size_t k = 0; k < K; ++k) {
    for (int j = 0; j < M_; ++j) mean_[k] += trajectory(j, k);
    mean_[k] /= double(M_);
    for (int j = 0; j < M_; ++j) var_[k] += (trajectory(j, k) - mean_[k]).cwiseAbs2();
    var_[k] /= double(M_ - 1);
  }
  return true;
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_PARTICLE_SMOOTHER_H_
