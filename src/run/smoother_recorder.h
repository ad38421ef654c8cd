// What `estlab smooth` adds to a filter run: it records the forward pass for
// the smoother of the filter's kind and, at the end, replaces each row's
// filtered belief by the smoothed one. Gaussian filters go to the RTS
// smoother (rts_smoother.h: kf -> rts, ekf -> erts, ukf -> urts, ckf ->
// ckf-rts, ghkf -> ghkf-rts), the particle filter to FFBSi
// (particle_smoother.h: pf -> pf-bs, spec.smoother_trajectories
// trajectories). Include only from filter_run_impl.h.
//
// Step bookkeeping: the prior is step 0; each prediction opens a new step,
// whose filtered belief is the next row's; a row at the time of the previous
// one (no prediction between) replaces that step's belief, so rows at one
// time share the smoothed belief that conditions on all of them.
#ifndef ESTLAB_RUN_SMOOTHER_RECORDER_H_
#define ESTLAB_RUN_SMOOTHER_RECORDER_H_

#include <optional>
#include <string>

#include "src/core/random.h"
#include "src/filters/particle.h"
#include "src/filters/particle_smoother.h"
#include "src/filters/rts_smoother.h"
#include "src/ode/transition.h"
#include "src/run/filter_spec.h"

namespace estlab {

template <class Model, class Meas>
class SmootherRecorder {
 public:
  static constexpr int N = Model::kStateDim;
  using StateCov = Mat<N, N>;

  SmootherRecorder(const FilterSpec& spec, Filter<Model, Meas>* filter,
                   Transition<Model>* transition)
      : spec_(spec), filter_(filter), transition_(transition) {
    pf_ = dynamic_cast<ParticleFilter<Model, Meas>*>(filter);
  }

  // After Initialize: the prior is step 0.
  void OnPrior() {
    if (pf_ != nullptr) {
      ps_.AddFiltered(pf_->particles(), pf_->weights());
    } else {
      rts_.AddFiltered(filter_->mean(), filter_->cov());
    }
    pending_ = false;
  }
  // Before filter->Predict(t0, t1, Q) with input u set: the particle
  // smoother's propagated means of the current cloud. False with *why.
  bool BeforePredict(double t0, double t1, const StateCov& Q, std::string* why) {
    if (pf_ == nullptr) return true;
    means_.resize(N, pf_->particles().cols());  // StepCloud writes, never resizes
    try {
      transition_->StepCloud(pf_->particles(), t0, t1, &means_);  // as the PF moves them
    } catch (const std::exception& e) {
      *why = std::string("particle smoother: transition failed: ") + e.what();
      return false;
    }
    return ps_.AddPredicted(means_, Q, why);
  }
  // After a successful Predict. False with *why.
  bool AfterPredict(std::string* why) {
    pending_ = true;
    if (pf_ != nullptr) return true;
    StateCov C = StateCov::Zero();
    if (!filter_->PredictCrossCov(&C)) {
      *why = "filter " + filter_->Name() + " has no prediction cross-covariance to smooth with";
      return false;
    }
    rts_.AddPredicted(filter_->mean(), filter_->cov(), C);
    return true;
  }
  // After a row's update (or none); returns the row's step index.
  size_t OnRow() {
    if (pf_ != nullptr) {
      if (pending_)
        ps_.AddFiltered(pf_->particles(), pf_->weights());
      else
        ps_.ReplaceFiltered(pf_->particles(), pf_->weights());
    } else {
      if (pending_)
        rts_.AddFiltered(filter_->mean(), filter_->cov());
      else
        rts_.ReplaceFiltered(filter_->mean(), filter_->cov());
    }
    pending_ = false;
    return (pf_ != nullptr ? ps_.filtered_steps() : rts_.filtered_steps()) - 1;
  }

  // The backward pass over the steps recorded (a prediction without its row,
  // when the forward pass stopped, is dropped). False with *why.
  bool Smooth(bool lag_one, std::string* why) {
    if (pf_ != nullptr) {
      ps_.DropUnfinishedStep();
      const auto* options = std::get_if<ParticleOptions>(&spec_.filter);
      const uint64_t seed = DeriveSeed({options ? options->seed : 0, kSmootherStream});
      return ps_.Smooth(spec_.smoother_trajectories, seed, why);
    }
    rts_.DropUnfinishedStep();
    return rts_.Smooth(why, lag_one ? LagOne::kCompute : LagOne::kSkip);
  }
  // The smoothed mean and covariance of step k (the particle smoother's is
  // the diagonal of its trajectories' sample variances).
  Vec<double, N> mean(size_t k) const { return pf_ ? ps_.mean(k) : rts_.mean(k); }
  StateCov cov(size_t k) const { return pf_ ? StateCov(ps_.var(k).asDiagonal()) : rts_.cov(k); }
  size_t steps() const { return pf_ ? ps_.size() : rts_.size(); }
  // Cov(x_k, x_{k+1} | all data) (RTS with lag_one only).
  const StateCov* lag_one(size_t k) const {
    return pf_ == nullptr && k + 1 < rts_.size() ? &rts_.lag_one_cov(k) : nullptr;
  }

 private:
  static constexpr uint64_t kSmootherStream = 0x5e0;  // the backward draws' own stream
  const FilterSpec& spec_;
  Filter<Model, Meas>* filter_;
  Transition<Model>* transition_;
  ParticleFilter<Model, Meas>* pf_ = nullptr;
  RtsSmoother<N> rts_;
  ParticleSmoother<N> ps_;
  Eigen::Matrix<double, N, Eigen::Dynamic> means_;
  bool pending_ = false;
};

}  // namespace estlab

#endif  // ESTLAB_RUN_SMOOTHER_RECORDER_H_
