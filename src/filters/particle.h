// Bootstrap particle filter (Gordon, Salmond & Smith 1993): particles moved by
// the process model plus Gaussian process noise, weighted by the Gaussian
// measurement likelihood, resampled when the effective sample size drops.
//
// Usage:
//   auto transition = MakeTransition<models::Pendulum>(params, transition_options);
//   ParticleOptions options;
//   options.num_particles = 1000;
//   options.resample = ResampleScheme::kResidual;   // paper 002
//   ParticleFilter<models::Pendulum, models::Pendulum::Sin> pf(transition.get(), params,
//                                                              options);
//   pf.Initialize(x0, P0);          // draws x_i ~ N(x0, P0), seeded by options.seed
//                                   // (normals by the ziggurat, ziggurat.h)
//   pf.Predict(t0, t1, Q);
//   StepResult<1> r = pf.Update(z, R);
//
// Predict:  x_i <- Phi(x_i) + L_Q e_i,  e_i ~ N(0, I),  L_Q L_Q^T = Q
//           (Q may be singular or zero: L_Q from an eigendecomposition then)
// Update (w_i the normalised weights before the update):
//   log p_i = log N(wrap(z - h(x_i)); 0, R)   (the observed components of z
//                                               only, R's block: missing.h)
//   log_likelihood = log sum_i w_i p_i              (log-sum-exp; the exps in
//                                                    packets for every model, packet.h)
//   w_i <- w_i p_i / sum_j w_j p_j,  ESS = 1 / sum_i w_i^2
//   resample (options.resample) when ESS < ess_threshold N; weights -> 1/N
//   z^ = sum_i w_i h(x_i) (before the update),
//   innovation = wrap(z - z^), innovation_cov = sum_i w_i dh_i dh_i^T + R
// Estimate (after Predict and Update, from the weighted particles before any
// resampling): mean = sum_i w_i x_i, cov = sum_i w_i d_i d_i^T,
// d_i = x_i - mean. Particles are never wrapped, so these are plain weighted
// moments for angle states too, as in the Gaussian filters (filter_util.h,
// WeightedMean): a circular mean would be another estimator, and wrapping
// inside the cloud breaks wide priors.
//
// WARNING: Initialize() restarts the generator from options.seed, so two runs
// with the same seed and data give identical results; use a different seed
// per Monte Carlo run. The filter does not own the transition.
#ifndef ESTLAB_FILTERS_PARTICLE_H_
#define ESTLAB_FILTERS_PARTICLE_H_

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "src/core/packet.h"
#include "src/core/random.h"
#include "src/filters/filter.h"
#include "src/filters/filter_options.h"
#include "src/filters/filter_util.h"
#include "src/filters/ziggurat.h"
#include "src/ode/packet_propagate.h"
#include "src/ode/transition.h"

namespace estlab {

// Draws N = weights.size() ancestor indices (ascending) with
// E[number of copies of i] = N w_i. `weights` must be non-negative and sum to
// 1 (the last cumulative sum is taken as exactly 1). Schemes (Douc, Cappe &
// Moulines 2005):
//   multinomial: N independent draws (sorted uniforms by exponential spacings)
//   systematic:  u_k = (k + U) / N, one U           copies in {floor, ceil}(N w_i)
//   stratified:  u_k = (k + U_k) / N                 |copies - N w_i| < 2
//   residual:    floor(N w_i) copies, the rest multinomial on the remainders
// *indices is resized to N (no allocation when it already has that size).
void Resample(const std::vector<double>& weights, ResampleScheme scheme, Rng& rng,
              std::vector<int>* indices);

// log(sum_i exp(v_i)), -inf for an empty or all -inf input.
double LogSumExp(const Eigen::VectorXd& v);

template <class Model, class Meas>
class ParticleFilter final : public FilterCommon<Model, Meas> {
 public:
  using Base = FilterCommon<Model, Meas>;
  using Base::kM;
  using Base::kN;
  using typename Base::Measurement;
  using typename Base::MeasurementCov;
  using typename Base::State;
  using typename Base::StateCov;
  using Params = typename Model::Params;

  // Throws InputError for a null transition or invalid options. All particle
  // storage is allocated here, once.
  ParticleFilter(Transition<Model>* transition, const Params& params,
                 const ParticleOptions& options)
      : transition_(transition),
        params_(params),
        options_(options),
        rng_(options.seed),
        normal_(&ZigguratNormal::Get()) {
    std::string error;
    if (transition_ == nullptr) throw InputError("ParticleFilter needs a transition");
    if (!options.IsValid(&error)) throw InputError(error);
    const int n = options.num_particles;
    particles_.resize(kN, n);
    scratch_.resize(kN, n);
    predicted_measurements_.resize(kM, n);
    log_weights_.setConstant(n, -std::log(double(n)));
    log_likelihoods_.resize(n);
    weights_.assign(n, 1.0 / n);
    indices_.resize(n);
  }

  std::string Name() const override { return "pf"; }
  void SetInputPath(const InputOf<Model>& u0, const InputOf<Model>& u1) override {
    transition_->SetInput(u0, u1);
  }

  // Draws x_i = x0 + L0 e_i, L0 L0^T = P0 (P0 may be singular), uniform weights.
  void Initialize(const State& mean, const StateCov& cov) override {
    this->SetPrior(mean, cov);
    rng_ = Rng(options_.seed);
    StateCov L;
    if (this->CheckReady() != FilterStatus::kOk || !CovarianceSqrt<kN>(cov, &L, nullptr)) return;
    for (Eigen::Index i = 0; i < particles_.cols(); ++i)
      particles_.col(i) = mean + L * StandardNormal();
    SetUniformWeights();
    ComputeMoments();
  }

  FilterStatus Predict(double t0, double t1, const StateCov& Q) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk) return ready;
    StateCov LQ;
    std::string why;
    if (!CovarianceSqrt<kN>(Q, &LQ, &why))
      return Fail(FilterStatus::kFactorizationFailed, "process noise Q: " + why);
    const bool noisy = !Q.isZero(0.0);
    // x_i <- Phi(x_i) + L_Q e_i: all particles in one transition call (no
    // virtual call per particle; kPacketWidth per model call for a packet
    // model, src/core/packet.h), then the noise in particle order.
    try {
      transition_->StepCloud(particles_, t0, t1, &scratch_);
    } catch (const std::exception& e) {
      return Fail(FilterStatus::kTransitionFailed, std::string("transition failed: ") + e.what());
    }
    particles_.swap(scratch_);
    if (noisy)
      for (Eigen::Index i = 0; i < particles_.cols(); ++i)
        particles_.col(i).noalias() += LQ * StandardNormal();
    ComputeMoments();
    if (!BeliefFinite(x_, P_))
      return Fail(FilterStatus::kNonFinite, "particle mean or covariance is not finite");
    return FilterStatus::kOk;
  }

  StepResult<kM> Update(const Measurement& z, const MeasurementCov& R) override {
    if (const FilterStatus ready = this->CheckReady(); ready != FilterStatus::kOk)
      return FailResult(ready, error_);
    // the observed components of z only (missing.h): R's observed block,
    // the missing components' residuals zero
    const MissingMask<kM> missing(z);
    MeasurementCov r_scratch;
    const MeasurementCov& Ru = missing.Noise(R, &r_scratch);
    const Eigen::LLT<MeasurementCov> r_llt(Ru);
    if (r_llt.info() != Eigen::Success || !R.allFinite())
      return FailResult(FilterStatus::kFactorizationFailed,
                        "Cholesky of the measurement noise R failed (not positive definite)");
    // log p_i = log N(wrap(z - h(x_i)); 0, R) = c - |L^-1 nu_i|^2 / 2 with
    // R = L L^T and c = -(log det R + m log 2 pi) / 2 computed once.
    const Eigen::Index n = particles_.cols();
    const MeasurementCov r_lower = r_llt.matrixL();
    Measurement zero_whitened;
    double log_det_r;
    Whiten<kM>(r_lower, Measurement(Measurement::Zero()), &zero_whitened, &log_det_r);
    const double log_norm = GaussianLogLikelihood<kM>(zero_whitened, log_det_r, missing.Observed());
    EvalMeasurements();
    if (kM > 1 && missing.Observed() == 1) {
      // One component j observed (one sensor of several reported): the
      // masked rows whiten to zero, so |L^-1 nu_i|^2 = (nu_ij / L_jj)^2.
      const int j = missing.FirstObserved();
      const double l_jj = r_lower(j, j);
      for (Eigen::Index i = 0; i < n; ++i) {
        const double e = WrapResidual<1>(Vec<double, 1>(z(j) - predicted_measurements_(j, i)),
                                         std::array<bool, 1>{Meas::kAngleOutputs[size_t(j)]})(0) /
                         l_jj;
        log_likelihoods_(i) = log_norm - 0.5 * (e * e);
      }
    } else {
      for (Eigen::Index i = 0; i < n; ++i) {
        Measurement nu_i =
            WrapResidual<kM>(z - predicted_measurements_.col(i), Meas::kAngleOutputs);
        if (missing.Any()) missing.MaskRows(&nu_i);
        const Measurement whitened =
            r_lower.template triangularView<Eigen::Lower>().solve(nu_i);  // L^-1 nu_i
        log_likelihoods_(i) = log_norm - 0.5 * whitened.squaredNorm();
      }
    }
    // Predicted-measurement moments with the prior weights:
    // z^ = sum_i w_i h(x_i), S = sum_i w_i dh_i dh_i^T + R, innovation = wrap(z - z^)
    const Measurement z_pred = Mean<kM>(predicted_measurements_);
    MeasurementCov S = WeightedCov<kM>(predicted_measurements_, z_pred, weight_vector());
    S += Ru;
    Symmetrize(&S);
    Measurement nu = WrapResidual<kM>(z - z_pred, Meas::kAngleOutputs);
    if (missing.Any()) missing.MaskCov(&S), missing.MaskRows(&nu);
    const Eigen::LLT<MeasurementCov> s_llt(S);
    if (s_llt.info() != Eigen::Success)
      return FailResult(FilterStatus::kFactorizationFailed,
                        "Cholesky of the predicted-measurement covariance failed");
    StepResult<kM> result;
    SetInnovation<kM>(nu, S, MeasurementCov(s_llt.matrixL()), missing, &result);
    // log_likelihood = log sum_i w_i p_i = m + log sum_i exp(l_i - m) with
    // l_i = log w_i + log p_i, m = max_i l_i (log-sum-exp; one exp per
    // particle, reused for the weights):
    // w_i <- exp(l_i - m) / sum_j exp(l_j - m),  log w_i <- l_i - log_likelihood
    log_likelihoods_ += log_weights_;
    const double max_l =
        n > 0 ? log_likelihoods_.maxCoeff() : -std::numeric_limits<double>::infinity();
    if (!std::isfinite(max_l))
      return FailResult(FilterStatus::kNonFinite,
                        "all particle likelihoods underflowed (the measurement is far from "
                        "every particle)");
    ExpWeights(max_l);
    double sum = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) sum += weights_[i];
    const double log_lik = max_l + std::log(sum);
    result.log_likelihood = log_lik;
    log_weights_ = log_likelihoods_.array() - log_lik;
    const double inv_sum = 1.0 / sum;
    double sum_sq = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      weights_[i] *= inv_sum;
      sum_sq += weights_[i] * weights_[i];
    }
    ess_ = 1.0 / sum_sq;  // ESS = 1 / sum_i w_i^2
    ComputeMoments();
    if (!BeliefFinite(x_, P_))
      return FailResult(FilterStatus::kNonFinite, "particle mean or covariance is not finite");
    if (this->post_fit_residual())
      result.residual = WrapResidual<kM>(
          z - EvalMeasurement<Model, Meas, double>(this->time(), x_, transition_->input(), params_),
          Meas::kAngleOutputs);
    resampled_ = ess_ < options_.ess_threshold * double(n);
    if (resampled_) ResampleParticles();
    return result;
  }

  // Effective sample size 1 / sum_i w_i^2 after the last Update, and whether
  // it resampled.
  double effective_sample_size() const { return ess_; }
  bool EffectiveSampleSize(double* ess, int* particles) const override {
    if (!(ess_ > 0.0)) return false;  // no Update yet
    *ess = ess_;
    *particles = int(particles_.cols());
    return true;
  }
  bool resampled() const { return resampled_; }
  const Eigen::Matrix<double, kN, Eigen::Dynamic>& particles() const { return particles_; }
  const std::vector<double>& weights() const { return weights_; }

 private:
  using Base::error_;
  using Base::Fail;
  using Base::FailResult;
  using Base::P_;
  using Base::x_;

  State StandardNormal() {
    State e;
    for (int j = 0; j < kN; ++j) e(j) = (*normal_)(rng_);
    return e;
  }

  // predicted_measurements_.col(i) = h(t, x_i, u); kPacketWidth particles per
  // call for a packet model (src/core/packet.h).
  void EvalMeasurements() {
    const InputOf<Model>& u = transition_->input();
    const double t = this->time();
    if constexpr (kPacketModel<Model>) {
      for (Eigen::Index first = 0; first < particles_.cols(); first += kPacketWidth)
        ScatterColumns<kM>(EvalMeasurement<Model, Meas, Packet>(
                               t, GatherColumns<kN>(particles_, first), u, params_),
                           first, &predicted_measurements_);
    } else {
      for (Eigen::Index i = 0; i < particles_.cols(); ++i)
        predicted_measurements_.col(i) =
            EvalMeasurement<Model, Meas, double>(t, State(particles_.col(i)), u, params_);
    }
  }

  // weights_[i] = exp(log_likelihoods_(i) - shift), kPacketWidth at a time
  // (packet exp, src/core/packet.h; the last packet repeats the last value).
  void ExpWeights(double shift) {
    const Eigen::Index n = log_likelihoods_.size();
    for (Eigen::Index first = 0; first < n; first += kPacketWidth) {
      Packet l;
      for (int k = 0; k < kPacketWidth; ++k)
        l.Set(k, log_likelihoods_(std::min<Eigen::Index>(first + k, n - 1)));
      const Packet w = exp(l - Packet(shift));
      for (int k = 0; k < kPacketWidth && first + k < n; ++k) weights_[first + k] = w[k];
    }
  }

  Eigen::Map<const Eigen::VectorXd> weight_vector() const {
    return Eigen::Map<const Eigen::VectorXd>(weights_.data(), Eigen::Index(weights_.size()));
  }

  void SetUniformWeights() {
    const double n = double(particles_.cols());
    std::fill(weights_.begin(), weights_.end(), 1.0 / n);
    log_weights_.setConstant(-std::log(n));
  }

  // m = sum_i w_i X_i with the current weights (no wrapping: see the header).
  template <int D, class Points>
  Vec<double, D> Mean(const Points& points) const {
    Vec<double, D> m = Vec<double, D>::Zero();
    for (Eigen::Index i = 0; i < points.cols(); ++i) m += weights_[i] * points.col(i);
    return m;
  }

  void ComputeMoments() {
    x_ = Mean<kN>(particles_);
    P_ = WeightedCov<kN>(particles_, x_, weight_vector());
    Symmetrize<kN>(&P_);
  }

  void ResampleParticles() {
    Resample(weights_, options_.resample, rng_, &indices_);
    for (Eigen::Index i = 0; i < particles_.cols(); ++i)
      scratch_.col(i) = particles_.col(indices_[i]);
    particles_.swap(scratch_);
    SetUniformWeights();
  }

  Transition<Model>* transition_;
  Params params_;
  ParticleOptions options_;
  Rng rng_;
  const ZigguratNormal* normal_;  // shared tables
  Eigen::Matrix<double, kN, Eigen::Dynamic> particles_;
  Eigen::Matrix<double, kN, Eigen::Dynamic> scratch_;
  Eigen::Matrix<double, kM, Eigen::Dynamic> predicted_measurements_;
  Eigen::VectorXd log_weights_;
  Eigen::VectorXd log_likelihoods_;
  std::vector<double> weights_;
  std::vector<int> indices_;
  double ess_ = 0.0;
  bool resampled_ = false;
};

// The filter that FilterSpec::filter = ParticleOptions runs (MakeFilter,
// src/run/filter_run_impl.h, visits the options with this overload).
template <class Model, class Meas>
std::unique_ptr<Filter<Model, Meas>> MakeFilterFor(const ParticleOptions& options,
                                                   Transition<Model>* transition,
                                                   const typename Model::Params& params) {
  return std::make_unique<ParticleFilter<Model, Meas>>(transition, params, options);
}

}  // namespace estlab

#endif  // ESTLAB_FILTERS_PARTICLE_H_
