// The innovation likelihood of a filter run, templated on the scalar type so
// that ceres::Jet gives its exact gradient in the noise parameters theta.
//
//   NLL(theta) = 1/2 sum_datasets sum_{k >= burn_in}
//                [ log det S_k + nu_k^T S_k^-1 nu_k + m_k log 2 pi ]  (m_k observed)
//
// The filter starts each dataset from the prior mean x0 (the spec's, or
// its first sample) with covariance P0; the initial states named in
// TunerOptions::estimate_x0 are parameters too (adaptive/initial_states.h:
// their entries of x0 come from theta, one row shared or one per dataset),
// so the gradient in them is the AD through the whole run as for the rest.
//
// There is no second copy of the filters here: every predict and update is
// the filter's own scalar-generic step (src/filters/ekf_step.h,
// sigma_point_step.h, kalman_step.h), run with T = double or ceres::Jet, and
// the time loop is the filter runs' own (src/run/step_loop.h). This file
// only supplies what differs for a Jet: the transition Phi(x) (and its
// Jacobian F for the EKF) through the fixed-step integrators, with Q(theta),
// R(theta) of scalar T (noise_param.h).
//
//   KF    the model linearised once about x* (KfOptions::operating_point, else the
//         prior mean; h per update time when it sees t, KfLinAt) and discretised
//         exactly over each step length (LinearizedKf, once, in double).
//
// Per update the recursion hands the whitened innovation e_k = L_k^-1 nu_k
// (S_k = L_k L_k^T) and log det S_k = 2 sum log (L_k)_ii to a sink (Whiten,
// filter_util.h); the NLL term is -GaussianLogLikelihood(e_k, log det S_k),
// the same function the filters' StepResult::log_likelihood comes from.
//
// Gradients (the tuner's choice, see adaptive/tuner_impl.h): T =
// ceres::Jet<double, C>. For the sigma-point filters that is all. The EKF's F
// and H are Jacobians at a state that depends on theta, so with T = Jet they
// are computed with NestedJet (src/ode/nested_jet.h): a Jet over the state of
// Jets over theta, giving dF/dtheta exactly (second-order forward AD).
//
// Usage:
//   InnovationLikelihood<models::Pendulum, models::Pendulum::Sin> lik(spec, options, data);
//   std::vector<double> theta = lik.InitialTheta();
//   double nll = NegLogLikelihood(lik, theta.data());    // NaN if the filter fails
//   ceres::Jet<double, 2> th[2] = {...};                  // gradient by AD
//   ceres::Jet<double, 2> g = NegLogLikelihood(lik, th);
//
// CVODES. With spec.transition.integrator = cvodes, Run<double> steps a
// Cvodes transition (src/ode/cvodes.h; its flow Jacobian from forward
// sensitivities in x0 for the EKF) and Run<Jet> a CvodesThetaFlow
// (src/ode/cvodes_theta_flow.h): forward sensitivities in theta of the state
// and, for the EKF, of the flow Jacobian (the variational system integrated
// with the state), so the gradient is exact to the integration tolerance.
// Both at rtol <= kCvodesRtol, atol <= kCvodesAtol: tighter than the
// filter's default, so that the NLL is smooth in theta to well below the
// tuner's tolerances.
//
// WARNING: a Cvodes transition is not thread-safe, so neither is an
// InnovationLikelihood with integrator cvodes: one per thread. With a
// fixed-step or discrete process model Run() writes nothing of the object, so
// several threads may run one likelihood at once (the tuner's gradient
// passes, adaptive/tuner_objective.h). A failed Cholesky,
// a non-finite value or trace(P) above spec.max_cov_trace makes Run() return
// false (the tuner treats that trial point as infeasible).
#ifndef ESTLAB_ADAPTIVE_LIKELIHOOD_H_
#define ESTLAB_ADAPTIVE_LIKELIHOOD_H_

#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "adaptive/initial_states.h"
#include "adaptive/likelihood_setup.h"
#include "adaptive/noise_param.h"
#include "adaptive/physical_params.h"
#include "adaptive/tuner.h"
#include "models/model_traits.h"
#include "src/filters/ekf_step.h"
#include "src/filters/filter_util.h"
#include "src/filters/gaussian_update.h"
#include "src/filters/kalman.h"
#include "src/filters/kalman_step.h"
#include "src/filters/sigma_point_step.h"
#include "src/filters/sigma_rules.h"
#include "src/ode/cvodes_theta_flow.h"
#include "src/ode/fixed_step.h"
#include "src/ode/nested_jet.h"
#include "src/ode/transition.h"
#include "src/run/filter_spec.h"
#include "src/run/first_sample.h"
#include "src/run/step_loop.h"

namespace estlab {

template <class Model, class Meas>
class InnovationLikelihood {
 public:
  static constexpr int kN = Model::kStateDim;
  static constexpr int kM = Meas::kDim;
  static constexpr int kU = kInputCols<Model>;
  using Params = typename Model::Params;
  template <class T>
  using StateT = Eigen::Matrix<T, kN, 1>;
  template <class T>
  using StateCovT = Eigen::Matrix<T, kN, kN>;
  template <class T>
  using MeasT = Eigen::Matrix<T, kM, 1>;
  template <class T>
  using MeasCovT = Eigen::Matrix<T, kM, kM>;

  // Validates and keeps pointers to `datasets` (they must outlive this).
  // Throws InputError for bad input.
  InnovationLikelihood(const FilterSpec& spec, const TunerOptions& options,
                       const std::vector<FilterData>& datasets);

  // theta = [Q's | R's | the physical parameters' (physical_params.h) |
  //          the initial states' (initial_states.h)].
  int NumNoiseParams() const { return q_.NumParams() + r_.NumParams(); }
  int FirstX0Param() const { return NumNoiseParams() + phys_.NumParams(); }
  int NumParams() const { return FirstX0Param() + x0s_.NumParams(); }
  std::vector<double> InitialTheta() const;
  std::vector<std::string> ParamNames() const;
  std::vector<bool> ParamIsLog() const;
  const PhysicalParams<Model>& physical() const { return phys_; }
  const InitialStates& initial_states() const { return x0s_; }
  // The prior mean of dataset `dataset` before any x0 is estimated: the
  // spec's x0, or its first sample (x0 = first-sample).
  Vec<double, kN> StartMean(std::size_t dataset) const {
    return spec_.x0_first_sample ? PriorMean<Model, Meas>(spec_, *datasets_[dataset]) : x0_;
  }
  // The whole prior mean of dataset `dataset` at theta.
  Vec<double, kN> PriorMeanAt(const double* theta, std::size_t dataset) const {
    Vec<double, kN> x = StartMean(dataset);
    x0s_.Apply(theta + FirstX0Param(), dataset, &x);
    return x;
  }
  const CovarianceParam<kN>& q_param() const { return q_; }
  const CovarianceParam<kM>& r_param() const { return r_; }
  long NumTerms() const { return terms_; }  // updates after burn-in, all datasets
  double dt_ref() const { return dt_ref_; }
  // True when the process model is CVODES.
  bool UsesCvodes() const { return cvodes_ != nullptr; }

  // EM's M-step (adaptive/em.h) evaluates the filter's own model at single
  // points: the noise-free process map x -> x- (the KF's linearised,
  // discretised map; else Phi, fixed-step or CVODES) and the measurement
  // residual wrap(z - h(x)) (the KF's linearised h).
  Vec<double, kN> PointTransition(const Vec<double, kN>& x, double t0, double t1,
                                  const InputPath<Model>& u) const {
    if (!kf_) return Propagate<double>(x, t0, t1, u, params_, nullptr);
    const KfDiscretization<kN, kU>* step = FindKfStep(t1 - t0);
    if (step == nullptr)  // SetUpKf saw every step of the data
      throw NumericalError("no KF discretisation for the step " + FormatNumber(t1 - t0));
    Vec<double, kN> next = x;
    Mat<kN, kN> P = Mat<kN, kN>::Zero();
    const Mat<kN, kN> no_noise = Mat<kN, kN>::Zero();
    KfPredict<Model, kM>(kf_lin_, *step, u.u0, u.u1, no_noise, &next, &P);
    return next;
  }
  Vec<double, kM> MeasurementResidual(const Vec<double, kM>& z, double t, const Vec<double, kN>& x,
                                      const InputOf<Model>& u) const {
    Vec<double, kM> z_pred;
    if (kf_) {  // h(t, x*, u*) + H wrap(x - x*) + D (u - u*), as KfUpdate
      const KfLin& lin = KfLinAt(t);
      z_pred = lin.h_star + lin.H * WrapResidual<kN>(x - lin.x_star, Model::kAngleStates) +
               lin.D * (InputColumn<Model>(u) - lin.u_star);
    } else {
      z_pred = EvalMeasurement<Model, Meas, double>(t, x, u, params_);
    }
    return WrapResidual<kM>(z - z_pred, Meas::kAngleOutputs);
  }

  // "" while the CVODES work of the running evaluation is within its bound
  // (TunerOptions::max_integrator_steps), else why this trial point is
  // infeasible.
  std::string WorkBoundMessage() const {
    const long allowed = 10000 + StepsPerInterval() * integrated_intervals_;
    if (integrator_steps_ <= allowed) return "";
    return "CVODES took " + std::to_string(integrator_steps_) + " steps for " +
           std::to_string(integrated_intervals_) + " intervals, more than 10^4 + " +
           std::to_string(StepsPerInterval()) + " (max integrator steps" +
           (Model::kStiff ? " x 5, a stiff model" : "") +
           ") per interval: the noise or parameters of this trial point make the model too hard "
           "to integrate";
  }
  // The average bound per interval: TunerOptions::max_integrator_steps, five
  // times that for a stiff model.
  long StepsPerInterval() const { return options_.max_integrator_steps * (Model::kStiff ? 5 : 1); }
  // What a CV_TOO_MUCH_WORK failure means here: the bound on one interval.
  std::string OneIntervalBoundNote(const char* what) const {
    if (std::string(what).find("CV_TOO_MUCH_WORK") == std::string::npos) return "";
    return " (more than 100 x " + std::to_string(StepsPerInterval()) +
           " steps in one interval (max integrator steps" +
           (Model::kStiff ? " x 5, a stiff model" : "") +
           "): the noise or parameters of this trial point make the model too hard to "
           "integrate)";
  }

  // CVODES tolerances of the likelihood (the spec's, if tighter).
  static constexpr double kCvodesRtol = 1e-10;
  static constexpr double kCvodesAtol = 1e-12;

  // Runs the filter over every dataset with Q(theta), R(theta); calls
  // sink(e_k, log det S_k) for every update after burn-in. Returns false
  // (with *why set when non-null) when the filter fails.
  // (The sink is a std::function so that the recursion is compiled once per
  // scalar type, not once per caller.)
  // observed: the components of z_k the update used (missing.h; the
  // whitened innovation is 0 in the others).
  template <class T>
  using Sink = std::function<void(const MeasT<T>& whitened, const T& log_det, int observed)>;
  template <class T>
  bool Run(const T* theta, const Sink<T>& sink, std::string* why = nullptr) const {
    if constexpr (EstimableParams<Model>) {
      if (!phys_.empty())
        return RunWith<T>(theta, phys_.template At<T>(theta + NumNoiseParams()), sink, why);
    }
    return RunWith<T>(theta, params_, sink, why);
  }

  // NLL(theta) (+ the physical parameters' prior terms); false when the
  // filter fails.
  template <class T>
  bool Nll(const T* theta, T* nll, std::string* why = nullptr) const {
    T sum(0.0);
    const bool ok = Run<T>(
        theta,
        [&](const MeasT<T>& e, const T& log_det, int observed) {
          sum -= GaussianLogLikelihood<kM, T>(e, log_det, observed);
        },
        why);
    phys_.ForEachPriorResidual(theta + NumNoiseParams(), [&](const T& r) { sum += 0.5 * r * r; });
    *nll = sum;
    return ok && std::isfinite(ScalarPart(sum));
  }

 private:
  // KF: one discretisation per distinct step length of the data.
  const KfDiscretization<kN, kU>* FindKfStep(double dt) const {
    for (const auto& [step_dt, step] : kf_steps_)
      if (step_dt == dt) return &step;
    return nullptr;
  }
  void SetUpKf(const KfOptions& options, const std::vector<FilterData>& datasets);
  void SetUpCvodes(TransitionOptions o);

  // Run() with the model parameters p: Params, or ParamsT<T> when physical
  // parameters are estimated.
  template <class T, class P>
  bool RunWith(const T* theta, const P& p, const Sink<T>& sink, std::string* why) const;

  // The belief of one run, of scalar T, and the sigma points' storage.
  template <class T>
  struct Belief {
    StateT<T> x;
    StateCovT<T> P;
    PointsT<T, kN> points, propagated;
    PointsT<T, kM> measurement_points;
    bool have_propagated = false;
  };
  template <class T, class P>
  bool Predict(Belief<T>* b, double t0, double t1, const InputPath<Model>& u, const StateCovT<T>& Q,
               const P& p, std::string* why) const;
  template <class T, class P>
  bool Update(Belief<T>* b, const Vec<double, kM>& z, double t, const InputOf<Model>& u,
              const MeasCovT<T>& R, const P& p, MeasT<T>* whitened, T* log_det,
              std::string* why) const;
  // The KF's linearisation for an update at time t: kf_lin_ (a reference),
  // or for a measurement h(t, x, u) a copy with h*, H, D at t
  // (KfLinearizeMeasurement; a copy, so that concurrent starts may share
  // this object).
  using KfLin = KfLinearization<kN, kM, kU>;
  decltype(auto) KfLinAt(double t) const {
    if constexpr (MeasurementSeesTime<Meas, Model>) {
      KfLin lin = kf_lin_;
      KfLinearizeMeasurement<Model, Meas>(t, params_, &lin);
      return lin;
    } else {
      (void)t;
      return (kf_lin_);
    }
  }
  // x- = Phi(x) (and F = dPhi/dx when F is not null) for scalar T: the
  // CVODES transition for double, AD through the fixed-step integrator
  // otherwise (a nested Jet for F when T is a Jet).
  template <class T, class P>
  StateT<T> Propagate(const StateT<T>& x, double t0, double t1, const InputPath<Model>& u,
                      const P& p, StateCovT<T>* F) const;
  // The CVODES flow differentiated in C directions, made on first use (one
  // per Jet size the tuner runs).
  template <int C>
  CvodesThetaFlow<Model, C>& ThetaFlow() const;

  FilterSpec spec_;
  TunerOptions options_;
  Params params_;
  PhysicalParams<Model> phys_;
  InitialStates x0s_;
  std::vector<const FilterData*> datasets_;
  Vec<double, kN> x0_;
  Mat<kN, kN> p0_;
  double dt_ref_ = 0.0;
  CovarianceParam<kN> q_;
  CovarianceParam<kM> r_;
  long terms_ = 0;
  int iterations_ = 1;  // EKF iterations (> 1: IEKF)
  // Sigma-point rule (src/filters/sigma_rules.h).
  bool sigma_ = false;
  bool sigma_redraw_ = true;
  SigmaPointSet sigma_set_;
  // KF: the linearisation, and Phi, Gamma, d per step length of the data.
  bool kf_ = false;
  KfLinearization<kN, kM, kU> kf_lin_;
  std::vector<std::pair<double, KfDiscretization<kN, kU>>> kf_steps_;
  // CVODES process model (null for the fixed-step ones), made anew for every
  // dataset of every Run(): CVODES carries step-size history from call to
  // call, and the NLL must be a function of theta alone for the central
  // differences. Step() is not const, hence mutable.
  TransitionOptions cvodes_options_;
  mutable std::unique_ptr<Transition<Model>> cvodes_;
  mutable std::map<int, std::shared_ptr<void>> theta_flows_;  // by C
  // CVODES steps and integrated intervals of the running evaluation, for
  // the work bound (TunerOptions::max_integrator_steps).
  mutable long integrator_steps_ = 0, integrated_intervals_ = 0;
};

// NLL(theta), quiet NaN when the filter fails.
template <class Model, class Meas, class T>
T NegLogLikelihood(const InnovationLikelihood<Model, Meas>& likelihood, const T* theta) {
  T nll(0.0);
  if (!likelihood.Nll(theta, &nll)) return T(std::numeric_limits<double>::quiet_NaN());
  return nll;
}

// ---------------------------------------------------------------------------
// Implementation.

template <class Model, class Meas>
InnovationLikelihood<Model, Meas>::InnovationLikelihood(const FilterSpec& spec,
                                                        const TunerOptions& options,
                                                        const std::vector<FilterData>& datasets)
    : spec_(likelihood_internal::CheckSpec<Model, Meas>(spec, options, datasets)),
      options_(options),
      params_(ParamsFromVector<Model>(spec.params)),
      phys_(options.estimate, spec.params, options.bound_width),
      dt_ref_(likelihood_internal::MedianStep(datasets.front())),
      q_(options.q_param, "q", likelihood_internal::StateNames<Model>(),
         likelihood_internal::Pairs<Model>(), likelihood_internal::InitialQ<Model>(spec),
         likelihood_internal::MedianStep(datasets.front())),
      r_(options.r_param, "r", likelihood_internal::OutputNames<Meas>(), {},
         likelihood_internal::InitialFromVector<kM>(spec.r, "R"), 0.0,
         likelihood_internal::RBlocks<Meas>(options)) {
  for (const FilterData& d : datasets) datasets_.push_back(&d);
  x0s_ = ResolveInitialStates(options.estimate_x0, options.x0_per_file, datasets.size(),
                              likelihood_internal::StateNames<Model>(), Model::kName);
  x0_ = ToVec<kN>(spec.x0);
  p0_ = likelihood_internal::InitialFromVector<kN>(spec.p0, "P0").matrix;
  if (!x0_.allFinite() || !p0_.allFinite()) throw InputError("x0 or P0 is not finite");
  if (Eigen::LLT<Mat<kN, kN>>(p0_).info() != Eigen::Success)
    throw InputError("P0 is not positive definite");
  if (r_.kind() == NoiseParam::kFixed &&
      Eigen::LLT<Mat<kM, kM>>(r_.template Matrix<double>(nullptr, 0.0)).info() != Eigen::Success)
    throw InputError("a fixed R must be positive definite");
  for (const FilterData& d : datasets) {
    long updates = 0;
    for (size_t k = 0; k < d.t.size(); ++k) updates += RowUpdates(d, k);
    terms_ += updates - options.burn_in;
  }
  // Each tunable kind's set-up; a kind missing here does not compile.
  std::visit(
      [&](const auto& o) {
        using O = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<O, KfOptions>) {
          SetUpKf(o, datasets);
          return;
        } else if constexpr (std::is_same_v<O, EkfOptions>) {
          iterations_ = o.iterations;
        } else if constexpr (std::is_same_v<O, SigmaPointOptions>) {
          sigma_ = true;
          sigma_redraw_ = o.update == SigmaPointOptions::Update::kRedraw;
          sigma_set_ = MakeSigmaPointSet(kN, o);
        } else {
          static_assert(std::is_same_v<O, ParticleOptions>,
                        "a new filter kind needs its case here, or tunable = false");
          return;  // not tunable: rejected by CheckSpec
        }
        if (spec.transition.integrator == Integrator::kCvodes) SetUpCvodes(spec.transition);
      },
      spec.filter);
}

template <class Model, class Meas>
void InnovationLikelihood<Model, Meas>::SetUpCvodes(TransitionOptions o) {
  o.rtol = std::min(o.rtol, kCvodesRtol);
  o.atol = std::min(o.atol, kCvodesAtol);
  o.max_steps = std::min(o.max_steps, 100 * StepsPerInterval());  // one interval
  std::string error;
  if (!o.IsValid(&error)) throw InputError(error);
  cvodes_options_ = o;
  cvodes_ = MakeTransition<Model>(params_, o);
}

template <class Model, class Meas>
std::vector<double> InnovationLikelihood<Model, Meas>::InitialTheta() const {
  std::vector<double> theta = q_.InitialTheta();
  const auto& r = r_.InitialTheta();
  theta.insert(theta.end(), r.begin(), r.end());
  const auto& phys = phys_.InitialTheta();
  theta.insert(theta.end(), phys.begin(), phys.end());
  for (int row = 0; row < x0s_.rows; ++row) {
    const Vec<double, kN> x = StartMean(size_t(row));  // row = dataset when per file
    for (int i : x0s_.index) theta.push_back(x(i));
  }
  return theta;
}

template <class Model, class Meas>
std::vector<std::string> InnovationLikelihood<Model, Meas>::ParamNames() const {
  std::vector<std::string> names = q_.Names();
  const auto& r = r_.Names();
  names.insert(names.end(), r.begin(), r.end());
  const auto& phys = phys_.Names();
  names.insert(names.end(), phys.begin(), phys.end());
  const auto& x0 = x0s_.Names(likelihood_internal::StateNames<Model>());
  names.insert(names.end(), x0.begin(), x0.end());
  return names;
}

template <class Model, class Meas>
std::vector<bool> InnovationLikelihood<Model, Meas>::ParamIsLog() const {
  std::vector<bool> out = q_.IsLog();
  const auto& r = r_.IsLog();
  out.insert(out.end(), r.begin(), r.end());
  for (int j = 0; j < phys_.NumParams(); ++j) out.push_back(phys_.IsLog(j));
  out.resize(size_t(NumParams()), false);  // the initial states
  return out;
}

template <class Model, class Meas>
template <class T, class P>
bool InnovationLikelihood<Model, Meas>::RunWith(const T* theta, const P& p, const Sink<T>& sink,
                                                std::string* why) const {
  std::string reason;
  auto fail = [&](const FilterData& d, size_t k, const std::string& what) {
    if (why != nullptr) {
      *why = what + " at step " + std::to_string(k) + (d.path.empty() ? "" : " of " + d.path) +
             " (t = " + FormatNumber(d.t[k]) + ")";
    }
    return false;
  };
  const T* theta_q = theta;
  const T* theta_r = theta + q_.NumParams();
  const MeasCovT<T> R = r_.template Matrix<T>(theta_r, 0.0);
  StateCovT<T> Q = q_.template Matrix<T>(theta_q, dt_ref_);
  double q_dt = dt_ref_;
  if (UsesCvodes()) integrator_steps_ = integrated_intervals_ = 0;  // fixed-step: no writes
  Belief<T> b;
  if (sigma_) {
    const Eigen::Index count = sigma_set_.unit_points.cols();
    b.points.resize(kN, count);
    b.propagated.resize(kN, count);
    b.measurement_points.resize(kM, count);
  }
  for (std::size_t set = 0; set < datasets_.size(); ++set) {
    const FilterData& d = *datasets_[set];
    if constexpr (std::is_same_v<P, Params>) {
      if (cvodes_ != nullptr) cvodes_ = MakeTransition<Model>(p, cvodes_options_);
    }
    b.x = StartMean(set).template cast<T>();
    x0s_.Apply(theta + FirstX0Param(), set, &b.x);
    b.P = p0_.template cast<T>();
    b.have_propagated = false;
    long update_index = 0;
    auto predict = [&](size_t k, double t0, double t1, const double* u0, const double* u1) {
      if (q_.DependsOnDt() && t1 - t0 != q_dt) {
        q_dt = t1 - t0;
        Q = q_.template Matrix<T>(theta_q, q_dt);
      }
      try {
        const InputPath<Model> u(InputFrom<Model>(u0), InputFrom<Model>(u1), t0, t1);
        if (!Predict<T>(&b, t0, t1, u, Q, p, &reason))
          return fail(d, k, "prediction failed: " + reason);
      } catch (const NumericalError& e) {  // CVODES failed
        if (why != nullptr) *why = e.what() + OneIntervalBoundNote(e.what());
        return false;
      }
      if (const std::string work = WorkBoundMessage(); !work.empty()) return fail(d, k, work);
      return true;
    };
    auto row = [&](size_t k, const Vec<double, kM>* z, const double* u) {
      if (z != nullptr) {
        MeasT<T> e;
        T log_det;
        if (!Update<T>(&b, *z, d.t[k], InputFrom<Model>(u), R, p, &e, &log_det, &reason))
          return fail(d, k, "update failed: " + reason);
        if (update_index >= options_.burn_in) sink(e, log_det, MissingMask<kM>(*z).Observed());
        ++update_index;
      }
      if (!WithinDivergenceGuard<kN, T>(b.x, b.P, spec_.max_cov_trace, &reason))
        return fail(d, k, reason);
      return true;
    };
    if (!ForEachStep<kM>(spec_, d, predict, row)) return false;
  }
  return true;
}

template <class Model, class Meas>
template <class T, class P>
typename InnovationLikelihood<Model, Meas>::template StateT<T>
InnovationLikelihood<Model, Meas>::Propagate(const StateT<T>& x, double t0, double t1,
                                             const InputPath<Model>& u, const P& p,
                                             StateCovT<T>* F) const {
  if constexpr (std::is_same_v<T, double>) {
    if (cvodes_ != nullptr) {  // x- = Phi(x), F = dPhi/dx from the sensitivities
      cvodes_->SetInput(u.u0, u.u1);
      const long before = cvodes_->stats().internal_steps;
      ++integrated_intervals_;
      try {
        const StateT<T> x1 =
            F != nullptr ? cvodes_->StepWithJacobian(x, t0, t1, F) : cvodes_->Step(x, t0, t1);
        integrator_steps_ += cvodes_->stats().internal_steps - before;
        return x1;
      } catch (...) {
        integrator_steps_ += cvodes_->stats().internal_steps - before;
        throw;
      }
    }
  } else if constexpr (!kDiscreteTime<Model>) {
    if (cvodes_ != nullptr) {  // the same with dx/dtheta, dF/dtheta (cvodes_theta_flow.h)
      auto& flow = ThetaFlow<JetSize<T>::value>();
      const long before = flow.steps();
      ++integrated_intervals_;
      try {
        const StateT<T> x1 = flow.Propagate(x, t0, t1, u, p, F);
        integrator_steps_ += flow.steps() - before;
        return x1;
      } catch (...) {
        integrator_steps_ += flow.steps() - before;
        throw;
      }
    }
  }
  const Integrator scheme = spec_.transition.integrator;
  const int substeps = spec_.transition.substeps;
  if (F == nullptr) return FixedPropagate<Model, T>(scheme, x, t0, t1, substeps, u, p);
  return ValueAndJacobianT<kN, kN>(
      [&](const auto& xs) {
        using S = typename std::decay_t<decltype(xs)>::Scalar;
        return FixedPropagate<Model, S>(scheme, xs, t0, t1, substeps, u, ParamsAs<Model, S>(p));
      },
      x, F);
}

template <class Model, class Meas>
template <int C>
CvodesThetaFlow<Model, C>& InnovationLikelihood<Model, Meas>::ThetaFlow() const {
  std::shared_ptr<void>& flow = theta_flows_[C];
  if (flow == nullptr) flow = std::make_shared<CvodesThetaFlow<Model, C>>(cvodes_options_);
  return *static_cast<CvodesThetaFlow<Model, C>*>(flow.get());
}

template <class Model, class Meas>
template <class T, class P>
bool InnovationLikelihood<Model, Meas>::Predict(Belief<T>* b, double t0, double t1,
                                                const InputPath<Model>& u, const StateCovT<T>& Q,
                                                const P& p, std::string* why) const {
  if (kf_) {
    const KfDiscretization<kN, kU>* step = FindKfStep(t1 - t0);
    if (step == nullptr) {  // cannot happen: SetUpKf saw every step
      *why = "no KF discretisation for this step";
      return false;
    }
    KfPredict<Model, kM, T>(kf_lin_, *step, u.u0, u.u1, Q, &b->x, &b->P);
  } else if (sigma_) {
    // X_i = x + L xi_i (L L^T = P + jitter I),  X-_i = Phi(X_i)
    b->have_propagated = false;
    if (!DrawSigmaPoints<kN, T>(sigma_set_, b->x, b->P, /*add_jitter=*/true, &b->points)) {
      *why = "Cholesky of P + jitter I failed (not positive definite)";
      return false;
    }
    for (Eigen::Index i = 0; i < b->points.cols(); ++i)
      b->propagated.col(i) = Propagate<T>(StateT<T>(b->points.col(i)), t0, t1, u, p, nullptr);
    SigmaPredictMoments<kN, T>(sigma_set_, b->propagated, Q, &b->x, &b->P);
    b->have_propagated = true;
  } else {
    // x- = Phi(x), F = dPhi/dx;  P- = F P F^T + Q
    StateCovT<T> F;
    b->x = Propagate<T>(b->x, t0, t1, u, p, &F);
    b->P = EkfPredictCovariance<kN, T>(F, b->P, Q);
  }
  if (!BeliefFinite<kN, T>(b->x, b->P)) {
    *why = "predicted mean or covariance is not finite";
    return false;
  }
  return true;
}

template <class Model, class Meas>
template <class T, class P>
bool InnovationLikelihood<Model, Meas>::Update(Belief<T>* b, const Vec<double, kM>& z, double t,
                                               const InputOf<Model>& input, const MeasCovT<T>& R,
                                               const P& p, MeasT<T>* whitened, T* log_det,
                                               std::string* why) const {
  GaussianUpdate<T, kN, kM> u;
  FilterStatus status;
  if (kf_) {
    status = KfUpdate<Model, Meas, T>(KfLinAt(t), input, b->x, b->P, z, R, &u, why);
  } else if (sigma_) {
    // Y_i: the propagated points, or new ones from (x-, P-) without jitter.
    const bool redraw = sigma_redraw_ || !b->have_propagated;
    b->have_propagated = false;
    if (redraw && !DrawSigmaPoints<kN, T>(sigma_set_, b->x, b->P, false, &b->points)) {
      *why = "Cholesky of P- failed (not positive definite)";
      return false;
    }
    status =
        SigmaUpdate<Model, Meas, T>(sigma_set_, redraw ? b->points : b->propagated,
                                    &b->measurement_points, b->x, b->P, z, R, t, input, p, &u, why);
  } else {
    status = EkfUpdate<Model, Meas, T>(b->x, b->P, z, R, t, input, p, iterations_, &u, why);
  }
  if (status != FilterStatus::kOk) return false;
  Whiten<kM, T>(u.L, u.nu, whitened, log_det);
  b->x = u.x;
  b->P = u.P;
  return true;
}

template <class Model, class Meas>
void InnovationLikelihood<Model, Meas>::SetUpKf(const KfOptions& options,
                                                const std::vector<FilterData>& datasets) {
  kf_ = true;
  LinearizedKf<Model, Meas> kf(params_, options);  // throws for a bad x*
  kf.Initialize(x0_, p0_);  // h at t = 0: KfLinAt re-linearises an h(t, ...) per update
  kf_lin_ = kf.linearization();
  // Phi, Gamma, d (and Gamma1 for a linear hold) for every step length
  // that Run() will meet.
  const bool ramp = spec_.transition.input_hold == InputHold::kLinear;
  auto add = [&](double dt) {
    if (!(dt > 0.0) || FindKfStep(dt) != nullptr) return;
    if (kf.Predict(0.0, dt, Mat<kN, kN>::Zero()) != FilterStatus::kOk)
      throw InputError("the linearised model (kf) is not finite at the operating point: " +
                       kf.last_error());
    kf_steps_.push_back({dt, kf.DiscretizationFor(dt, ramp)});
  };
  for (const FilterData& d : datasets) {
    if (d.t.empty()) continue;
    double t_prev = spec_.has_t0 ? spec_.t0 : d.t[0];
    for (double t : d.t) {
      if (t > t_prev) add(t - t_prev);
      t_prev = t;
    }
  }
}

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_LIKELIHOOD_H_
