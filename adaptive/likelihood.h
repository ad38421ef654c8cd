// The innovation likelihood of a filter run, templated on the scalar type so
// that ceres::Jet gives its exact gradient in the noise parameters theta.
//
//   NLL(theta) = 1/2 sum_datasets sum_{k >= burn_in}
//                [ log det S_k + nu_k^T S_k^-1 nu_k + m log 2 pi ]
//
// The filters in src/filters are double-only, so this file holds a compact
// copy of their recursions (src/filters/ekf.h, sigma_point.h: same equations,
// same order, same wrapping and symmetrisation, so the NLL equals minus the
// sum of their StepResult::log_likelihood) with Q(theta), R(theta) of scalar T:
//
//   EKF / IEKF  x- = Phi(x),  P- = F P F^T + Q,  F = dPhi/dx
//         nu = wrap(z - h(x-)),  S = H P- H^T + R,  K = P- H^T S^-1
//         IEKF: x_{i+1} = x- + K_i (wrap(z - h(x_i)) - H_i wrap(x- - x_i))
//         P+ = (I - K H) P- (I - K H)^T + K R K^T            (Joseph form)
//         (nu, S of the likelihood are those at the prior, i = 0)
//   UKF / CKF / GHKF (unit points xi_i, weights Wm_i, Wc_i of sigma_rules.h)
//         X_i = x + L xi_i (L L^T = P + jitter I),  X-_i = Phi(X_i)
//         x- = X-_0 + sum Wm_i wrap(X-_i - X-_0)
//         P- = sum Wc_i wrap(X-_i - x-)(.)^T + Q + jitter I
//         Y_i = X-_i (propagate) or x- + L- xi_i (redraw),  Z_i = h(Y_i)
//         z^ = Z_0 + sum Wm_i wrap(Z_i - Z_0),  S = sum Wc_i dZ_i dZ_i^T + R + jitter I
//         C = sum Wc_i wrap(Y_i - x-) dZ_i^T,  K = C S^-1,  nu = wrap(z - z^)
//         x+ = x- + K nu,  P+ = P- - K S K^T
//
//   KF    the model linearised once about x* (spec.linearize_at, else the
//         prior mean) and discretised exactly over each step length of the data
//         (src/filters/kalman.h, computed once in double):
//         x- = x* + Phi wrap(x - x*) + Gamma (u - u*) + d,  P- = Phi P Phi^T + Q
//         nu = wrap(z - h(x*) - H wrap(x- - x*)),  S = H P- H^T + R,  Joseph update
//
// Per update the recursion hands the whitened innovation e_k = L_k^-1 nu_k
// (S_k = L_k L_k^T) and log det S_k = 2 sum log (L_k)_ii to a sink; the NLL
// term is 1/2 (e_k^T e_k + log det S_k + m log 2 pi). No matrix is inverted.
//
// Gradients (the tuner's choice, see adaptive/tuner_impl.h): T =
// ceres::Jet<double, C>. For the sigma-point filters that is all. The EKF's F
// and H are Jacobians at a state that depends on theta, so with T = Jet they
// are computed with NestedJet (adaptive/nested_jet.h): a Jet over the state of
// Jets over theta, giving dF/dtheta exactly (second-order forward AD).
//
// Usage:
//   InnovationLikelihood<models::Pendulum, models::Pendulum::Sin> lik(spec, options, data);
//   std::vector<double> theta = lik.InitialTheta();
//   double nll = NegLogLikelihood(lik, theta.data());    // NaN if the filter fails
//   ceres::Jet<double, 2> th[2] = {...};                  // gradient by AD
//   ceres::Jet<double, 2> g = NegLogLikelihood(lik, th);
//
// CVODES. With spec.transition.integrator = cvodes the recursion runs in
// double only, through a Cvodes transition (src/ode/cvodes.h; its flow
// Jacobian from forward sensitivities for the EKF) at rtol <= kCvodesRtol,
// atol <= kCvodesAtol: tighter than the filter's default so that central
// differences of the NLL (tuner_impl.h) are honest. Run<Jet>() then fails.
//
// WARNING: a Cvodes transition is not thread-safe, so neither is an
// InnovationLikelihood with integrator cvodes: one per thread. A failed Cholesky,
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
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "adaptive/nested_jet.h"
#include "adaptive/noise_param.h"
#include "adaptive/tuner.h"
#include "src/filters/kalman.h"
#include "src/filters/sigma_rules.h"
#include "src/ode/fixed_step.h"
#include "src/ode/transition.h"
#include "src/registry/model_traits.h"
#include "src/run/filter_spec.h"

namespace estlab {

// The Jet type that carries d/dx (N directions) on top of scalar T: a plain
// Jet for T = double, a NestedJet for T = Jet<double, K>.
template <class T, int N>
struct Tangent;
template <int N>
struct Tangent<double, N> {
  using type = ceres::Jet<double, N>;
  static type Seed(double v, int i) { return type(v, i); }
  static double Value(const type& y) { return y.a; }
  static double Deriv(const type& y, int c) { return y.v(c); }
};
template <int K, int N>
struct Tangent<ceres::Jet<double, K>, N> {
  using Inner = ceres::Jet<double, K>;
  using type = NestedJet<K, N>;
  static type Seed(const Inner& v, int i) { return type(typename type::Base(v, i)); }
  static Inner Value(const type& y) { return y.j.a; }
  static Inner Deriv(const type& y, int c) { return y.j.v(c); }
};

// f(x) and its Jacobian df/dx for x of any scalar T (see Tangent).
template <int Mout, int N, class T, class F>
Eigen::Matrix<T, Mout, 1> ValueAndJacobianT(F&& f, const Eigen::Matrix<T, N, 1>& x,
                                            Eigen::Matrix<T, Mout, N>* jacobian) {
  using Tg = Tangent<T, N>;
  Eigen::Matrix<typename Tg::type, N, 1> xs;
  for (int i = 0; i < N; ++i) xs(i) = Tg::Seed(x(i), i);
  const Eigen::Matrix<typename Tg::type, Mout, 1> y = f(xs);
  Eigen::Matrix<T, Mout, 1> value;
  for (int r = 0; r < Mout; ++r) {
    value(r) = Tg::Value(y(r));
    for (int c = 0; c < N; ++c) (*jacobian)(r, c) = Tg::Deriv(y(r), c);
  }
  return value;
}

template <class Model, class Meas>
class InnovationLikelihood {
 public:
  static constexpr int kN = Model::kStateDim;
  static constexpr int kM = Meas::kDim;
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

  int NumParams() const { return q_.NumParams() + r_.NumParams(); }
  std::vector<double> InitialTheta() const;
  std::vector<std::string> ParamNames() const;
  std::vector<bool> ParamIsLog() const;
  const CovarianceParam<kN>& q_param() const { return q_; }
  const CovarianceParam<kM>& r_param() const { return r_; }
  long NumTerms() const { return terms_; }  // updates after burn-in, all datasets
  double dt_ref() const { return dt_ref_; }
  // True when the process model is CVODES: only Run<double> works, and the
  // tuner differentiates the NLL by central differences.
  bool UsesCvodes() const { return cvodes_ != nullptr; }

  // CVODES tolerances of the likelihood (the spec's, if tighter).
  static constexpr double kCvodesRtol = 1e-10;
  static constexpr double kCvodesAtol = 1e-12;

  // Runs the filter over every dataset with Q(theta), R(theta); calls
  // sink(e_k, log det S_k) for every update after burn-in. Returns false
  // (with *why set when non-null) when the filter fails.
  // (The sink is a std::function so that the recursion is compiled once per
  // scalar type, not once per caller.)
  template <class T>
  using Sink = std::function<void(const MeasT<T>& whitened, const T& log_det)>;
  template <class T>
  bool Run(const T* theta, const Sink<T>& sink, std::string* why = nullptr) const;

  // NLL(theta); false when the filter fails.
  template <class T>
  bool Nll(const T* theta, T* nll, std::string* why = nullptr) const {
    const double c = 0.5 * kM * std::log(2.0 * 3.14159265358979323846);
    T sum(0.0);
    const bool ok = Run<T>(
        theta,
        [&](const MeasT<T>& e, const T& log_det) { sum += 0.5 * (e.squaredNorm() + log_det) + c; },
        why);
    *nll = sum;
    return ok && ScalarFinite(sum);
  }

 private:
  template <class T>
  static bool ScalarFinite(const T& v) {
    return std::isfinite(ScalarPart(v));
  }

  // Sigma points chi = [x, x + gamma L_i, x - gamma L_i] (no centre for CKF).
  template <class T>
  bool SigmaPoints(const StateT<T>& x, const StateCovT<T>& P, bool add_jitter,
                   std::vector<StateT<T>>* points) const;
  // EKF gain at x: residual wrap(z - h(x)), H, S = H P H^T + R, K.
  template <class T>
  bool Gain(const StateT<T>& x, const StateCovT<T>& P, const Vec<double, kM>& z,
            const MeasCovT<T>& R, MeasT<T>* residual, Eigen::Matrix<T, kM, kN>* H, MeasCovT<T>* S,
            Eigen::LLT<MeasCovT<T>>* llt, Eigen::Matrix<T, kN, kM>* K) const;

  // KF: one discretisation per distinct step length of the data.
  struct KfStep {
    double dt;
    Mat<kN, kN> phi;
    Vec<double, kN> gamma, drift;
  };
  const KfStep* FindKfStep(double dt) const {
    for (const KfStep& s : kf_steps_)
      if (s.dt == dt) return &s;
    return nullptr;
  }
  void SetUpKf(const std::vector<FilterData>& datasets);
  template <class T>
  bool PredictKf(StateT<T>* x, StateCovT<T>* P, double dt, double u, const StateCovT<T>& Q) const;
  template <class T>
  bool UpdateKf(StateT<T>* x, StateCovT<T>* P, const Vec<double, kM>& z, const MeasCovT<T>& R,
                MeasT<T>* whitened, T* log_det) const;

  template <class T>
  bool PredictEkf(StateT<T>* x, StateCovT<T>* P, double t0, double t1, double u,
                  const StateCovT<T>& Q) const;
  template <class T>
  bool UpdateEkf(StateT<T>* x, StateCovT<T>* P, const Vec<double, kM>& z, const MeasCovT<T>& R,
                 MeasT<T>* whitened, T* log_det) const;
  template <class T>
  bool PredictSigma(StateT<T>* x, StateCovT<T>* P, std::vector<StateT<T>>* propagated, double t0,
                    double t1, double u, const StateCovT<T>& Q) const;
  template <class T>
  bool UpdateSigma(StateT<T>* x, StateCovT<T>* P, const std::vector<StateT<T>>* propagated,
                   const Vec<double, kM>& z, const MeasCovT<T>& R, MeasT<T>* whitened,
                   T* log_det) const;
  // Innovation statistics from S (Cholesky): e = L^-1 nu, log det S.
  template <class T>
  static void Whiten(const Eigen::LLT<MeasCovT<T>>& llt, const MeasT<T>& nu, MeasT<T>* whitened,
                     T* log_det) {
    using std::log;
    *whitened = llt.matrixL().solve(nu);
    const MeasCovT<T> L = llt.matrixL();
    T sum(0.0);
    for (int i = 0; i < kM; ++i) sum += log(L(i, i));
    *log_det = 2.0 * sum;
  }
  template <class T>
  static MeasT<T> WrapOutputs(MeasT<T> v) {
    for (int i = 0; i < kM; ++i)
      if (Meas::kAngleOutputs[i]) v(i) = WrapAngleT(v(i));
    return v;
  }
  template <class T>
  static StateT<T> WrapStates(StateT<T> v) {
    for (int i = 0; i < kN; ++i)
      if (Model::kAngleStates[i]) v(i) = WrapAngleT(v(i));
    return v;
  }

  FilterSpec spec_;
  TunerOptions options_;
  Params params_;
  std::vector<const FilterData*> datasets_;
  Vec<double, kN> x0_;
  Mat<kN, kN> p0_;
  double dt_ref_ = 0.0;
  CovarianceParam<kN> q_;
  CovarianceParam<kM> r_;
  long terms_ = 0;
  // Sigma-point rule (src/filters/sigma_rules.h): unit points xi_i of
  // N(0, I) and their weights.
  bool sigma_ = false;
  Eigen::MatrixXd unit_points_;
  Eigen::VectorXd mean_weights_, cov_weights_;
  // KF (see KfStep).
  bool kf_ = false;
  Vec<double, kN> x_star_ = Vec<double, kN>::Zero();
  double u_star_ = 0.0;
  Vec<double, kM> h_star_ = Vec<double, kM>::Zero();
  Mat<kM, kN> h_jacobian_ = Mat<kM, kN>::Zero();
  std::vector<KfStep> kf_steps_;
  // CVODES process model (null for the fixed-step ones), made anew for every
  // dataset of every Run(): CVODES carries step-size history from call to
  // call, and the NLL must be a function of theta alone for the central
  // differences. Step() is not const, hence mutable.
  TransitionOptions cvodes_options_;
  mutable std::unique_ptr<Transition<Model>> cvodes_;
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

namespace likelihood_internal {

// Median of the positive time steps of a dataset (0 when it has none).
inline double MedianStep(const FilterData& data) {
  std::vector<double> steps;
  for (size_t k = 1; k < data.t.size(); ++k)
    if (data.t[k] > data.t[k - 1]) steps.push_back(data.t[k] - data.t[k - 1]);
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

template <class Model>
std::vector<std::pair<int, int>> Pairs() {
  std::vector<std::pair<int, int>> out;
  for (const auto& p : Model::kPositionRatePairs) out.push_back(p);
  return out;
}

template <int D>
InitialCovariance<D> InitialFromVector(const std::vector<double>& v, const std::string& what) {
  if (v.size() != size_t(D) * D) {
    throw InputError("the initial " + what + " has " + std::to_string(v.size()) +
                     " entries, expected " + std::to_string(D) + " x " + std::to_string(D));
  }
  InitialCovariance<D> c;
  for (int i = 0; i < D; ++i)
    for (int j = 0; j < D; ++j) c.matrix(i, j) = v[i * D + j];
  return c;
}

template <class Model>
InitialCovariance<Model::kStateDim> InitialQ(const FilterSpec& spec) {
  if (spec.q_white_accel) {
    InitialCovariance<Model::kStateDim> c;
    if (!(spec.qc >= 0 && std::isfinite(spec.qc)))
      throw InputError("the initial qc must be finite and >= 0, got " + FormatNumber(spec.qc));
    c.white_accel = true;
    c.qc = spec.qc;
    return c;
  }
  return InitialFromVector<Model::kStateDim>(spec.q, "Q");
}

template <class Model>
std::vector<std::string> StateNames() {
  std::vector<std::string> out;
  for (const char* s : Model::kStateNames) out.push_back(s);
  return out;
}
template <class Meas>
std::vector<std::string> OutputNames() {
  std::vector<std::string> out;
  for (const char* s : Meas::kOutputs) out.push_back(s);
  return out;
}

// Checks the spec before anything is built from it.
template <class Model, class Meas>
const FilterSpec& CheckSpec(const FilterSpec& spec, const TunerOptions& options,
                            const std::vector<FilterData>& datasets) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError(error);
  if (spec.kind == FilterKind::kPf) {
    throw InputError(
        "the tuner supports the kf, ekf, iekf, ukf, ckf and ghkf filters, not pf (its "
        "likelihood is a random, non-smooth function of Q and R)");
  }
  if (spec.iterations < 1) throw InputError("EKF iterations must be >= 1");
  if (!spec.adapt.rule.empty())
    throw InputError("the tuner needs a filter without online adaptation (--adapt)");
  if (!(spec.transition.substeps >= 1)) throw InputError("substeps must be >= 1");
  if (spec.x0.size() != size_t(Model::kStateDim))
    throw InputError("x0 has " + std::to_string(spec.x0.size()) + " entries, expected " +
                     std::to_string(Model::kStateDim));
  if (spec.p0.size() != size_t(Model::kStateDim) * Model::kStateDim)
    throw InputError("P0 has the wrong size");
  if (datasets.empty()) throw InputError("the tuner needs at least one dataset");
  for (const FilterData& d : datasets) {
    const std::string name = d.path.empty() ? "a dataset" : d.path;
    if (d.m != Meas::kDim || d.z.size() != d.t.size() * size_t(Meas::kDim))
      throw InputError(name + ": measurement columns do not match '" + std::string(Meas::kName) +
                       "'");
    if (d.has_input && d.u.size() != d.t.size()) throw InputError(name + ": input column size");
    long updates = 0;
    std::vector<long> finite(Meas::kDim, 0);
    for (size_t k = 0; k < d.t.size(); ++k) {
      bool all = true;
      for (int j = 0; j < Meas::kDim; ++j) {
        const bool f = std::isfinite(d.z[k * Meas::kDim + j]);
        finite[j] += f;
        all = all && f;
      }
      updates += all;
    }
    for (int j = 0; j < Meas::kDim; ++j) {
      if (finite[j] == 0)
        throw InputError(name + ": measurement column z_" + std::string(Meas::kOutputs[j]) +
                         " has no value (all missing)");
    }
    if (updates <= options.burn_in) {
      throw InputError(name + ": " + std::to_string(updates) +
                       " measurement updates, not more than the burn-in of " +
                       std::to_string(options.burn_in));
    }
  }
  return spec;
}

}  // namespace likelihood_internal

template <class Model, class Meas>
InnovationLikelihood<Model, Meas>::InnovationLikelihood(const FilterSpec& spec,
                                                        const TunerOptions& options,
                                                        const std::vector<FilterData>& datasets)
    : spec_(likelihood_internal::CheckSpec<Model, Meas>(spec, options, datasets)),
      options_(options),
      params_(ParamsFromVector<Model>(spec.params)),
      dt_ref_(likelihood_internal::MedianStep(datasets.front())),
      q_(options.q_param, "q", likelihood_internal::StateNames<Model>(),
         likelihood_internal::Pairs<Model>(), likelihood_internal::InitialQ<Model>(spec),
         likelihood_internal::MedianStep(datasets.front())),
      r_(options.r_param, "r", likelihood_internal::OutputNames<Meas>(), {},
         likelihood_internal::InitialFromVector<kM>(spec.r, "R"), 0.0) {
  for (const FilterData& d : datasets) datasets_.push_back(&d);
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
    for (size_t k = 0; k < d.t.size(); ++k) {
      bool all = true;
      for (int j = 0; j < kM; ++j) all = all && std::isfinite(d.z[k * kM + j]);
      updates += all;
    }
    terms_ += updates - options.burn_in;
  }
  if (spec.kind == FilterKind::kKf) {
    SetUpKf(datasets);
  } else if (spec.transition.integrator == Integrator::kCvodes) {
    TransitionOptions o = spec.transition;
    o.rtol = std::min(o.rtol, kCvodesRtol);
    o.atol = std::min(o.atol, kCvodesAtol);
    std::string error;
    if (!o.IsValid(&error)) throw InputError(error);
    cvodes_options_ = o;
    cvodes_ = MakeTransition<Model>(params_, o);
  }
  if (spec.kind != FilterKind::kEkf && spec.kind != FilterKind::kKf) {
    sigma_ = true;
    SigmaPointOptions o;
    o.rule = spec.kind == FilterKind::kUkf   ? SigmaRule::kUnscented
             : spec.kind == FilterKind::kCkf ? SigmaRule::kCubature
                                             : SigmaRule::kGaussHermite;
    o.alpha = spec.alpha;
    o.beta = spec.beta;
    o.kappa = spec.kappa;
    o.gh_order = spec.gh_order;
    o.jitter = spec.jitter;
    std::string error;
    if (!o.IsValid(&error)) throw InputError(error);
    const UnitSigmaPoints unit = MakeUnitSigmaPoints(kN, o);
    unit_points_ = unit.points;
    mean_weights_ = unit.mean_weights;
    cov_weights_ = unit.cov_weights;
  }
}

template <class Model, class Meas>
std::vector<double> InnovationLikelihood<Model, Meas>::InitialTheta() const {
  std::vector<double> theta = q_.InitialTheta();
  const auto& r = r_.InitialTheta();
  theta.insert(theta.end(), r.begin(), r.end());
  return theta;
}

template <class Model, class Meas>
std::vector<std::string> InnovationLikelihood<Model, Meas>::ParamNames() const {
  std::vector<std::string> names = q_.Names();
  const auto& r = r_.Names();
  names.insert(names.end(), r.begin(), r.end());
  return names;
}

template <class Model, class Meas>
std::vector<bool> InnovationLikelihood<Model, Meas>::ParamIsLog() const {
  std::vector<bool> out = q_.IsLog();
  const auto& r = r_.IsLog();
  out.insert(out.end(), r.begin(), r.end());
  return out;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::Run(const T* theta, const Sink<T>& sink,
                                            std::string* why) const {
  auto fail = [&](const FilterData& d, size_t k, const char* what) {
    if (why != nullptr) {
      *why = std::string(what) + " at step " + std::to_string(k) +
             (d.path.empty() ? "" : " of " + d.path) + " (t = " + FormatNumber(d.t[k]) + ")";
    }
    return false;
  };
  const T* theta_q = theta;
  const T* theta_r = theta + q_.NumParams();
  if constexpr (!std::is_same_v<T, double>) {
    if (cvodes_ != nullptr) {
      if (why != nullptr)
        *why = "a CVODES process model has no AD gradient (use central differences)";
      return false;
    }
  }
  const MeasCovT<T> R = r_.template Matrix<T>(theta_r, 0.0);
  StateCovT<T> Q = q_.template Matrix<T>(theta_q, dt_ref_);
  double q_dt = dt_ref_;
  std::vector<StateT<T>> propagated;

  for (const FilterData* data : datasets_) {
    const FilterData& d = *data;
    if (cvodes_ != nullptr) cvodes_ = MakeTransition<Model>(params_, cvodes_options_);
    StateT<T> x = x0_.template cast<T>();
    StateCovT<T> P = p0_.template cast<T>();
    double t_prev = spec_.has_t0 ? spec_.t0 : d.t[0];
    long update_index = 0;
    for (size_t k = 0; k < d.t.size(); ++k) {
      const double t = d.t[k];
      const double u = d.has_input ? d.u[k > 0 ? k - 1 : 0] : spec_.input;
      bool predicted = false;
      if (t > t_prev) {
        if (q_.DependsOnDt() && t - t_prev != q_dt) {
          q_dt = t - t_prev;
          Q = q_.template Matrix<T>(theta_q, q_dt);
        }
        bool ok = false;
        try {
          ok = kf_      ? PredictKf<T>(&x, &P, t - t_prev, u, Q)
               : sigma_ ? PredictSigma<T>(&x, &P, &propagated, t_prev, t, u, Q)
                        : PredictEkf<T>(&x, &P, t_prev, t, u, Q);
        } catch (const NumericalError& e) {  // CVODES failed
          if (why != nullptr) *why = e.what();
          return false;
        }
        if (!ok) return fail(d, k, "prediction failed");
        predicted = true;
      }
      t_prev = t;
      Vec<double, kM> z;
      bool have_z = true;
      for (int j = 0; j < kM; ++j) {
        z(j) = d.z[k * kM + j];
        if (!std::isfinite(z(j))) have_z = false;
      }
      if (have_z) {
        MeasT<T> e;
        T log_det;
        const bool ok =
            kf_      ? UpdateKf<T>(&x, &P, z, R, &e, &log_det)
            : sigma_ ? UpdateSigma<T>(&x, &P, predicted ? &propagated : nullptr, z, R, &e, &log_det)
                     : UpdateEkf<T>(&x, &P, z, R, &e, &log_det);
        if (!ok) return fail(d, k, "update failed (innovation covariance not positive definite)");
        if (update_index >= options_.burn_in) sink(e, log_det);
        ++update_index;
      }
      bool finite = true;
      for (int i = 0; i < kN && finite; ++i) {
        finite = ScalarFinite(x(i));
        for (int c = 0; c < kN && finite; ++c) finite = ScalarFinite(P(i, c));
      }
      if (!finite) return fail(d, k, "the estimate or its covariance is not finite");
      if (ScalarPart(P.trace()) > spec_.max_cov_trace) return fail(d, k, "trace(P) too large");
    }
  }
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::PredictEkf(StateT<T>* x, StateCovT<T>* P, double t0,
                                                   double t1, double u,
                                                   const StateCovT<T>& Q) const {
  StateCovT<T> F;
  if constexpr (std::is_same_v<T, double>) {
    if (cvodes_ != nullptr) {  // x- = Phi(x), F = dPhi/dx from the sensitivities
      cvodes_->SetInput(u);
      *x = cvodes_->StepWithJacobian(*x, t0, t1, &F);
      if (!x->allFinite() || !F.allFinite()) return false;
      const StateCovT<T> Pm = F * (*P) * F.transpose() + Q;
      *P = 0.5 * (Pm + Pm.transpose());
      return true;
    }
  }
  const Integrator scheme = spec_.transition.integrator;
  const int substeps = spec_.transition.substeps;
  const Params& p = params_;
  *x = ValueAndJacobianT<kN, kN>(
      [&](const auto& xs) {
        using S = typename std::decay_t<decltype(xs)>::Scalar;
        return FixedPropagate<Model, S>(scheme, xs, t0, t1, substeps, u, p);
      },
      *x, &F);
  // P- = F P F^T + Q
  const StateCovT<T> Pm = F * (*P) * F.transpose() + Q;
  *P = 0.5 * (Pm + Pm.transpose());
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::Gain(const StateT<T>& x, const StateCovT<T>& P,
                                             const Vec<double, kM>& z, const MeasCovT<T>& R,
                                             MeasT<T>* residual, Eigen::Matrix<T, kM, kN>* H,
                                             MeasCovT<T>* S, Eigen::LLT<MeasCovT<T>>* llt,
                                             Eigen::Matrix<T, kN, kM>* K) const {
  const Params& p = params_;
  const MeasT<T> z_pred = ValueAndJacobianT<kM, kN>(
      [&](const auto& xs) {
        using S = typename std::decay_t<decltype(xs)>::Scalar;
        return Meas::template Eval<S>(xs, p);
      },
      x, H);
  *residual = WrapOutputs<T>(z.template cast<T>() - z_pred);
  // S = H P H^T + R,  K = P H^T S^-1, i.e. K^T = S^-1 (H P)
  const Eigen::Matrix<T, kM, kN> HP = (*H) * P;
  *S = HP * H->transpose() + R;
  *S = (0.5 * (*S + S->transpose())).eval();
  llt->compute(*S);
  if (llt->info() != Eigen::Success) return false;
  *K = llt->solve(HP).transpose();
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::UpdateEkf(StateT<T>* x, StateCovT<T>* P,
                                                  const Vec<double, kM>& z, const MeasCovT<T>& R,
                                                  MeasT<T>* whitened, T* log_det) const {
  Eigen::Matrix<T, kM, kN> H;
  MeasCovT<T> S;
  Eigen::LLT<MeasCovT<T>> llt;
  Eigen::Matrix<T, kN, kM> K;
  MeasT<T> nu;
  // i = 0: nu = wrap(z - h(x-)), S = H P- H^T + R (the likelihood term)
  if (!Gain<T>(*x, *P, z, R, &nu, &H, &S, &llt, &K)) return false;
  Whiten<T>(llt, nu, whitened, log_det);
  const StateT<T> x_prior = *x;
  StateT<T> x_iter = x_prior + K * nu;
  // IEKF: x_{i+1} = x- + K_i (wrap(z - h(x_i)) - H_i wrap(x- - x_i))
  for (int i = 1; i < spec_.iterations; ++i) {
    MeasT<T> r;
    if (!Gain<T>(x_iter, *P, z, R, &r, &H, &S, &llt, &K)) return false;
    x_iter = x_prior + K * (r - H * WrapStates<T>(x_prior - x_iter));
  }
  // P+ = (I - K H) P- (I - K H)^T + K R K^T with the last K, H
  const StateCovT<T> I_KH = StateCovT<T>::Identity() - K * H;
  const StateCovT<T> Pp = I_KH * (*P) * I_KH.transpose() + K * R * K.transpose();
  *x = x_iter;
  *P = 0.5 * (Pp + Pp.transpose());
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::SigmaPoints(const StateT<T>& x, const StateCovT<T>& P,
                                                    bool add_jitter,
                                                    std::vector<StateT<T>>* points) const {
  // X_i = x + L xi_i,  L L^T = P (+ jitter I)
  StateCovT<T> C = P;
  if (add_jitter && spec_.jitter > 0) C.diagonal().array() += T(spec_.jitter);
  const Eigen::LLT<StateCovT<T>> llt(C);
  if (llt.info() != Eigen::Success) return false;
  const StateCovT<T> L = llt.matrixL();
  points->resize(unit_points_.cols());
  for (Eigen::Index i = 0; i < unit_points_.cols(); ++i) {
    const Vec<double, kN> xi = unit_points_.col(i);
    (*points)[i] = x + L * xi.template cast<T>();
  }
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::PredictSigma(StateT<T>* x, StateCovT<T>* P,
                                                     std::vector<StateT<T>>* propagated, double t0,
                                                     double t1, double u,
                                                     const StateCovT<T>& Q) const {
  if (!SigmaPoints<T>(*x, *P, true, propagated)) return false;
  const int count = int(propagated->size());
  if constexpr (std::is_same_v<T, double>) {
    if (cvodes_ != nullptr) cvodes_->SetInput(u);
  }
  for (auto& point : *propagated) {
    if constexpr (std::is_same_v<T, double>) {
      if (cvodes_ != nullptr) {
        point = cvodes_->Step(point, t0, t1);
        continue;
      }
    }
    point = FixedPropagate<Model, T>(spec_.transition.integrator, point, t0, t1,
                                     spec_.transition.substeps, u, params_);
  }
  // x- = X-_0 + sum_i Wm_i wrap(X-_i - X-_0)
  const std::vector<StateT<T>>& Y = *propagated;
  StateT<T> mean = StateT<T>::Zero();
  for (int i = 1; i < count; ++i) mean += mean_weights_(i) * WrapStates<T>(Y[i] - Y[0]);
  mean += Y[0];
  // P- = sum_i Wc_i dX_i dX_i^T + Q + jitter I
  StateCovT<T> cov = Q;
  for (int i = 0; i < count; ++i) {
    const StateT<T> d = WrapStates<T>(Y[i] - mean);
    cov += cov_weights_(i) * d * d.transpose();
  }
  if (spec_.jitter > 0) cov.diagonal().array() += T(spec_.jitter);
  *x = mean;
  *P = 0.5 * (cov + cov.transpose());
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::UpdateSigma(StateT<T>* x, StateCovT<T>* P,
                                                    const std::vector<StateT<T>>* propagated,
                                                    const Vec<double, kM>& z, const MeasCovT<T>& R,
                                                    MeasT<T>* whitened, T* log_det) const {
  // Y_i: the propagated points, or new ones from (x-, P-) without jitter.
  std::vector<StateT<T>> redrawn;
  const std::vector<StateT<T>>* points = propagated;
  if (points == nullptr || spec_.sigma_redraw) {
    if (!SigmaPoints<T>(*x, *P, false, &redrawn)) return false;
    points = &redrawn;
  }
  const std::vector<StateT<T>>& Y = *points;
  const int count = int(Y.size());
  // Z_i = h(Y_i),  z^ = Z_0 + sum_i Wm_i wrap(Z_i - Z_0)
  std::vector<MeasT<T>> Z(count);
  for (int i = 0; i < count; ++i) Z[i] = Meas::template Eval<T>(Y[i], params_);
  MeasT<T> z_pred = MeasT<T>::Zero();
  for (int i = 1; i < count; ++i) z_pred += mean_weights_(i) * WrapOutputs<T>(Z[i] - Z[0]);
  z_pred += Z[0];
  // S = sum_i Wc_i dZ_i dZ_i^T + R + jitter I,  C = sum_i Wc_i dY_i dZ_i^T
  MeasCovT<T> S = MeasCovT<T>::Zero();
  Eigen::Matrix<T, kN, kM> C = Eigen::Matrix<T, kN, kM>::Zero();
  for (int i = 0; i < count; ++i) {
    const MeasT<T> dz = WrapOutputs<T>(Z[i] - z_pred);
    S += cov_weights_(i) * dz * dz.transpose();
    C += cov_weights_(i) * WrapStates<T>(Y[i] - *x) * dz.transpose();
  }
  S += R;
  if (spec_.jitter > 0) S.diagonal().array() += T(spec_.jitter);
  S = (0.5 * (S + S.transpose())).eval();
  const Eigen::LLT<MeasCovT<T>> llt(S);
  if (llt.info() != Eigen::Success) return false;
  // K = C S^-1, i.e. K^T = S^-1 C^T;  nu = wrap(z - z^)
  const Eigen::Matrix<T, kN, kM> K = llt.solve(C.transpose()).transpose();
  const MeasT<T> nu = WrapOutputs<T>(z.template cast<T>() - z_pred);
  Whiten<T>(llt, nu, whitened, log_det);
  // x+ = x- + K nu,  P+ = P- - K S K^T
  *x += K * nu;
  const StateCovT<T> Pp = *P - K * S * K.transpose();
  *P = 0.5 * (Pp + Pp.transpose());
  return true;
}

template <class Model, class Meas>
void InnovationLikelihood<Model, Meas>::SetUpKf(const std::vector<FilterData>& datasets) {
  kf_ = true;
  KfOptions o;
  o.operating_point = spec_.linearize_at;
  o.operating_input = spec_.input;
  LinearizedKf<Model, Meas> kf(params_, o);  // throws InputError for a bad operating point
  kf.Initialize(x0_, p0_);
  x_star_ = kf.operating_point();
  u_star_ = spec_.input;
  h_jacobian_ = kf.H();
  h_star_ = Meas::template Eval<double>(x_star_, params_);
  // Phi, Gamma, d for every step length that Run() will meet.
  auto add = [&](double dt) {
    if (!(dt > 0.0) || FindKfStep(dt) != nullptr) return;
    if (kf.Predict(0.0, dt, Mat<kN, kN>::Zero()) != FilterStatus::kOk)
      throw InputError("the linearised model (kf) is not finite at the operating point: " +
                       kf.last_error());
    kf_steps_.push_back({dt, kf.Phi(), kf.Gamma(), kf.d()});
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

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::PredictKf(StateT<T>* x, StateCovT<T>* P, double dt,
                                                  double u, const StateCovT<T>& Q) const {
  const KfStep* step = FindKfStep(dt);
  if (step == nullptr) return false;  // cannot happen: SetUpKf saw every step
  // x- = x* + Phi wrap(x - x*) + Gamma (u - u*) + d,  P- = Phi P Phi^T + Q
  const StateT<T> delta = WrapStates<T>(*x - x_star_.template cast<T>());
  const Mat<kN, kN>& phi = step->phi;
  const StateT<T> x_pred = x_star_.template cast<T>() + phi.template cast<T>() * delta +
                           (step->gamma * (u - u_star_) + step->drift).template cast<T>();
  const StateCovT<T> Pm = phi.template cast<T>() * (*P) * phi.transpose().template cast<T>() + Q;
  *x = x_pred;
  *P = 0.5 * (Pm + Pm.transpose());
  return true;
}

template <class Model, class Meas>
template <class T>
bool InnovationLikelihood<Model, Meas>::UpdateKf(StateT<T>* x, StateCovT<T>* P,
                                                 const Vec<double, kM>& z, const MeasCovT<T>& R,
                                                 MeasT<T>* whitened, T* log_det) const {
  const Eigen::Matrix<T, kM, kN> H = h_jacobian_.template cast<T>();
  // z^ = h(x*) + H wrap(x- - x*),  nu = wrap(z - z^)
  const StateT<T> delta = WrapStates<T>(*x - x_star_.template cast<T>());
  const MeasT<T> z_pred = h_star_.template cast<T>() + H * delta;
  const MeasT<T> nu = WrapOutputs<T>(z.template cast<T>() - z_pred);
  // S = H P H^T + R,  K^T = S^-1 (H P)
  const Eigen::Matrix<T, kM, kN> HP = H * (*P);
  MeasCovT<T> S = HP * H.transpose() + R;
  S = (0.5 * (S + S.transpose())).eval();
  const Eigen::LLT<MeasCovT<T>> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix<T, kN, kM> K = llt.solve(HP).transpose();
  Whiten<T>(llt, nu, whitened, log_det);
  // x+ = x- + K nu,  P+ = (I - K H) P- (I - K H)^T + K R K^T
  const StateCovT<T> I_KH = StateCovT<T>::Identity() - K * H;
  const StateCovT<T> Pp = I_KH * (*P) * I_KH.transpose() + K * R * K.transpose();
  *x += K * nu;
  *P = 0.5 * (Pp + Pp.transpose());
  return true;
}

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_LIKELIHOOD_H_
