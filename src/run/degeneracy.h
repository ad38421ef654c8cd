// The degeneracy check of particle-filter runs. A particle filter whose
// weights pile onto one particle at every update still produces finite
// numbers (its mean is that particle), so without this check a collapsed
// filter reports `status ok` (P0 = diag(4, 100), R = 1.4e-9: RMSE 1.4 rad,
// mean NIS 1e9).
//
//   update k collapsed:  ESS_k < max(kMinEss, kMinEssFraction * N),
//                        ESS_k = 1 / sum_i w_i^2 before resampling
//   run degenerate:      kDegenerateRun consecutive collapsed updates
//
// Usage:
//   DegeneracyMonitor monitor;
//   for each update k: monitor.Observe(ess_k, N, k);
//   if (monitor.degenerate()) ... monitor.onset_step() ...
#ifndef ESTLAB_RUN_DEGENERACY_H_
#define ESTLAB_RUN_DEGENERACY_H_

#include <algorithm>
#include <cstddef>
#include <string>

namespace estlab {

class DegeneracyMonitor {
 public:
  // Fewer than two effective particles, or under 1 % of them.
  static constexpr double kMinEss = 2.0;
  static constexpr double kMinEssFraction = 0.01;
  // Ten updates in a row: one collapsed update after an informative
  // measurement is normal (resampling recovers); ten are a filter that
  // tracks with one particle.
  static constexpr long kDegenerateRun = 10;

  static double Threshold(int particles) {
    return std::max(kMinEss, kMinEssFraction * double(particles));
  }

  void Observe(double ess, int particles, std::size_t step) {
    particles_ = particles;
    ++updates_;
    ess_sum_ += ess;
    min_ess_ = updates_ == 1 ? ess : std::min(min_ess_, ess);
    if (ess < Threshold(particles)) {
      ++collapsed_;
      if (++run_ == kDegenerateRun && !degenerate_) {
        degenerate_ = true;
        onset_step_ = step;
      }
    } else {
      run_ = 0;
    }
  }

  bool observed() const { return updates_ > 0; }
  bool degenerate() const { return degenerate_; }
  // The step at which the first run of kDegenerateRun collapsed updates
  // was complete.
  std::size_t onset_step() const { return onset_step_; }
  int particles() const { return particles_; }
  double min_ess() const { return min_ess_; }
  double mean_ess() const { return updates_ ? ess_sum_ / double(updates_) : 0.0; }
  long collapsed_updates() const { return collapsed_; }

 private:
  int particles_ = 0;
  long updates_ = 0, collapsed_ = 0, run_ = 0;
  double ess_sum_ = 0.0, min_ess_ = 0.0;
  bool degenerate_ = false;
  std::size_t onset_step_ = 0;
};

}  // namespace estlab

#endif  // ESTLAB_RUN_DEGENERACY_H_
