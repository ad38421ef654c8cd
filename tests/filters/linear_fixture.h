// Shared fixture of the filter tests (in the spirit of Drake's
// systems/estimators/test/nonlinear_kalman_filter_test.h): linear test models
// with the same static interface as models/*.h, a hand-written Kalman filter
// that is the reference, random-but-fixed linear-Gaussian data, and a driver
// that runs a filter and the reference side by side and reports the largest
// difference at any step.
//
// For a linear Rhs one explicit Euler step is exactly linear,
//   x+ = x + dt (A x + B u) = F x + G u,  F = I + dt A,  G = dt B,
// so every Gaussian filter run with an Euler transition must reproduce the
// Kalman filter with (F, G, H) up to rounding.
#ifndef ESTLAB_TESTS_FILTERS_LINEAR_FIXTURE_H_
#define ESTLAB_TESTS_FILTERS_LINEAR_FIXTURE_H_

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/core/params.h"
#include "src/core/random.h"
#include "src/core/types.h"
#include "src/filters/filter.h"
#include "src/ode/transition.h"
#include "src/ode/transition_impl.h"  // MakeTransition for the test models

namespace estlab::testing {

// Damped oscillator driven by a force:  x' = v,  v' = -k x - c v + u.
struct DampedOscillator {
  static constexpr const char* kName = "damped-oscillator";
  static constexpr const char* kDescription = "linear damped oscillator (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 2> kStateNames = {"x", "v"};
  static constexpr std::array<const char*, 2> kStateUnits = {"m", "m/s"};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 1> kPositionRatePairs = {{{0, 1}}};

  struct Params {
    double k = 2.0;
    double c = 0.3;
  };
  static constexpr std::array<ParamSpec<Params>, 2> kParams = {{
      {"k", &Params::k, "stiffness [1/s^2]", Constraint::kNonNegative},
      {"c", &Params::c, "damping [1/s]", Constraint::kNonNegative},
  }};

  template <class T>
  static Vec<T, 2> Rhs(const T& /*t*/, const Vec<T, 2>& x, double u, const Params& p) {
    Vec<T, 2> dx;
    dx(0) = x(1);
    dx(1) = -p.k * x(0) - p.c * x(1) + u;
    return dx;
  }

  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params& /*p*/, double /*u*/) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>& /*x*/, const Params& /*p*/) {
    return Vec<double, 0>();
  }

  // The continuous system written out by hand (not by AD).
  static Mat<2, 2> A(const Params& p) { return (Mat<2, 2>() << 0, 1, -p.k, -p.c).finished(); }
  static Vec<double, 2> B() { return Vec<double, 2>(0, 1); }

  struct Position {
    static constexpr const char* kName = "position";
    static constexpr int kDim = 1;
    static constexpr std::array<const char*, 1> kOutputs = {"x"};
    static constexpr std::array<bool, 1> kAngleOutputs = {false};
    template <class T>
    static Vec<T, 1> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      return Vec<T, 1>(x(0));
    }
    static Mat<1, 2> H() { return Mat<1, 2>(1, 0); }
  };
  // Two outputs: z = (x, x + v / 2).
  struct Mixed {
    static constexpr const char* kName = "mixed";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"x", "x_plus_half_v"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      return Vec<T, 2>(x(0), x(0) + 0.5 * x(1));
    }
    static Mat<2, 2> H() { return (Mat<2, 2>() << 1, 0, 1, 0.5).finished(); }
  };
  using Measurements = std::tuple<Position, Mixed>;
};

// Two masses and two springs, the first mass forced:
//   x1'' = -(k1 + k2) x1 + k2 x2 - c v1 + u,   x2'' = k2 (x1 - x2) - c v2.
// State [x1, v1, x2, v2]; measured z = (x1, x2 - x1).
struct CoupledOscillators {
  static constexpr const char* kName = "coupled-oscillators";
  static constexpr const char* kDescription = "two coupled linear oscillators (test model)";
  static constexpr int kStateDim = 4;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr std::array<const char*, 4> kStateNames = {"x1", "v1", "x2", "v2"};
  static constexpr std::array<const char*, 4> kStateUnits = {"m", "m/s", "m", "m/s"};
  static constexpr std::array<bool, 4> kAngleStates = {false, false, false, false};
  static constexpr std::array<std::pair<int, int>, 2> kPositionRatePairs = {{{0, 1}, {2, 3}}};

  struct Params {
    double k1 = 1.5;
    double k2 = 0.7;
    double c = 0.2;
  };
  static constexpr std::array<ParamSpec<Params>, 3> kParams = {{
      {"k1", &Params::k1, "first spring [1/s^2]", Constraint::kNonNegative},
      {"k2", &Params::k2, "coupling spring [1/s^2]", Constraint::kNonNegative},
      {"c", &Params::c, "damping [1/s]", Constraint::kNonNegative},
  }};

  template <class T>
  static Vec<T, 4> Rhs(const T& /*t*/, const Vec<T, 4>& x, double u, const Params& p) {
    Vec<T, 4> dx;
    dx(0) = x(1);
    dx(1) = -(p.k1 + p.k2) * x(0) + p.k2 * x(2) - p.c * x(1) + u;
    dx(2) = x(3);
    dx(3) = p.k2 * (x(0) - x(2)) - p.c * x(3);
    return dx;
  }

  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params& /*p*/, double /*u*/) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 4>& /*x*/, const Params& /*p*/) {
    return Vec<double, 0>();
  }

  static Mat<4, 4> A(const Params& p) {
    Mat<4, 4> a;
    a << 0, 1, 0, 0,                    //
        -(p.k1 + p.k2), -p.c, p.k2, 0,  //
        0, 0, 0, 1,                     //
        p.k2, 0, -p.k2, -p.c;
    return a;
  }
  static Vec<double, 4> B() { return Vec<double, 4>(0, 1, 0, 0); }

  struct Relative {
    static constexpr const char* kName = "relative";
    static constexpr int kDim = 2;
    static constexpr std::array<const char*, 2> kOutputs = {"x1", "x2_minus_x1"};
    static constexpr std::array<bool, 2> kAngleOutputs = {false, false};
    template <class T>
    static Vec<T, 2> Eval(const Vec<T, 4>& x, const Params& /*p*/) {
      return Vec<T, 2>(x(0), x(2) - x(0));
    }
    static Mat<2, 4> H() { return (Mat<2, 4>() << 1, 0, 0, 0, -1, 0, 1, 0).finished(); }
  };
  using Measurements = std::tuple<Relative>;
};

// Hand-written Kalman filter, the reference:
//   predict:  x- = F x + G u,  P- = F P F^T + Q
//   update:   S = H P- H^T + R,  K = P- H^T S^-1,  x+ = x- + K nu,  P+ = (I - K H) P-
// (plain inverse and the short covariance form on purpose: a different route
// from the filters' Cholesky solves and Joseph form).
//
// Variants reproducing the documented sigma-point options exactly on a linear
// model:
//   jitter j:  predict draws points from P + j I, so P- = F (P + j I) F^T + Q + j I,
//              and S gets + j I;
//   q_in_update = false (SigmaPointOptions::Update::kPropagate): the propagated
//              points have covariance P_f = F (P + j I) F^T without Q, so
//              S = H P_f H^T + R + j I, C = P_f H^T, K = C S^-1 and
//              P+ = P- - K S K^T.
template <int N, int M>
struct HandKf {
  Mat<N, N> F;
  Vec<double, N> G = Vec<double, N>::Zero();
  Mat<M, N> H;
  Vec<double, N> x;
  Mat<N, N> P;
  double jitter = 0.0;
  bool q_in_update = true;

  Mat<N, N> P_flow;  // F (P + j I) F^T of the last predict
  bool predicted = false;

  struct Out {
    Vec<double, M> innovation;
    Mat<M, M> S;
    double log_likelihood;
    double nis;
    Mat<N, M> K;
  };

  void Predict(const Mat<N, N>& Q, double u) {
    const Mat<N, N> Pj = P + jitter * Mat<N, N>::Identity();
    x = F * x + G * u;
    P_flow = F * Pj * F.transpose();
    P = P_flow + Q + jitter * Mat<N, N>::Identity();
    predicted = true;
  }

  Out Update(const Vec<double, M>& z, const Mat<M, M>& R) {
    Out o;
    const bool propagate = !q_in_update && predicted;
    const Mat<N, N> Pc = propagate ? P_flow : P;
    const Mat<N, M> C = Pc * H.transpose();
    o.S = H * Pc * H.transpose() + R;
    o.S += jitter * Mat<M, M>::Identity();
    o.K = C * o.S.inverse();
    o.innovation = z - H * x;
    o.nis = o.innovation.dot(o.S.inverse() * o.innovation);
    o.log_likelihood = -0.5 * (std::log(o.S.determinant()) + o.nis + M * std::log(2 * M_PI));
    x = x + o.K * o.innovation;
    if (jitter == 0.0 && q_in_update)
      P = (Mat<N, N>::Identity() - o.K * H) * P;
    else
      P = P - o.K * o.S * o.K.transpose();
    P = 0.5 * (P + P.transpose()).eval();
    predicted = false;
    return o;
  }
};

// Random-but-fixed linear-Gaussian data: the truth moves by the Euler map plus
// N(0, Q) noise, measured through H plus N(0, R) noise; every `gap`-th step
// has no measurement (two predicts in a row).
template <int N, int M>
struct LinearData {
  double dt = 0.1;
  int steps = 0;
  Vec<double, N> x0;
  Mat<N, N> P0, Q;
  Mat<M, M> R;
  std::vector<double> u;  // u[k]: input held from t_k to t_{k+1}
  std::vector<Vec<double, M>> z;
  std::vector<bool> has_z;
  double t(int k) const { return k * dt; }
};

template <int N, int M>
Vec<double, N> DrawGaussian(const Mat<N, N>& cov, Rng& rng) {
  const Mat<N, N> L = cov.llt().matrixL();
  Vec<double, N> e;
  for (int i = 0; i < N; ++i) e(i) = rng.Normal();
  return L * e;
}

template <int N, int M>
LinearData<N, M> MakeLinearData(const Mat<N, N>& F, const Vec<double, N>& G, const Mat<M, N>& H,
                                int steps, uint64_t seed, int gap = 7) {
  LinearData<N, M> d;
  d.steps = steps;
  Rng rng(seed);
  // Generic, fully coupled covariances.
  Mat<N, N> a = Mat<N, N>::Identity();
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) a(i, j) += 0.2 * std::sin(1.0 + i + 2.0 * j);
  d.P0 = 0.3 * a * a.transpose();
  d.Q = 0.01 * a.transpose() * a;
  Mat<M, M> b = Mat<M, M>::Identity();
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) b(i, j) += 0.3 * std::cos(2.0 + i - j);
  d.R = 0.05 * b * b.transpose();
  Vec<double, N> truth;
  for (int i = 0; i < N; ++i) truth(i) = 0.8 * std::cos(0.7 * i + 0.3);
  d.x0 = truth + DrawGaussian<N, M>(d.P0, rng);
  for (int k = 0; k < steps; ++k) {
    d.u.push_back(0.5 * std::sin(0.2 * k));
    if (k > 0) truth = F * truth + G * d.u[k - 1] + DrawGaussian<N, M>(d.Q, rng);
    d.z.push_back(H * truth + DrawGaussian<M, M>(d.R, rng));
    d.has_z.push_back(gap <= 0 || k % gap != gap - 1);
  }
  return d;
}

// Largest |a - b| / max(1, max|b|) over the entries.
template <class A, class B>
double ScaledDiff(const A& a, const B& b) {
  const double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
  return (a - b).cwiseAbs().maxCoeff() / scale;
}
inline double ScaledDiff(double a, double b) {
  return std::abs(a - b) / std::max(1.0, std::abs(b));
}

// The largest differences between a filter and the reference over a run.
struct Deviation {
  double mean = 0.0, cov = 0.0, innovation = 0.0, innovation_cov = 0.0, log_likelihood = 0.0,
         nis = 0.0, gain = 0.0;
  bool all_ok = true;
  double CovMax() const { return std::max({cov, innovation_cov, gain}); }
  double MeanMax() const { return std::max({mean, innovation, log_likelihood, nis}); }
  double Max() const {
    return std::max({mean, cov, innovation, innovation_cov, log_likelihood, nis, gain});
  }
};

// Runs `filter` and `reference` over `data` and records the largest deviation
// after every predict and every update.
template <class Model, class Meas, int N = Model::kStateDim, int M = Meas::kDim>
Deviation CompareWithReference(Filter<Model, Meas>& filter, HandKf<N, M> reference,
                               const LinearData<N, M>& data, const Mat<N, N>& Q) {
  Deviation dev;
  filter.Initialize(data.x0, data.P0);
  reference.x = data.x0;
  reference.P = data.P0;
  for (int k = 0; k < data.steps; ++k) {
    if (k > 0) {
      filter.SetInput(data.u[k - 1]);
      const FilterStatus status = filter.Predict(data.t(k - 1), data.t(k), Q);
      if (status != FilterStatus::kOk) dev.all_ok = false;
      reference.Predict(Q, data.u[k - 1]);
      dev.mean = std::max(dev.mean, ScaledDiff(filter.mean(), reference.x));
      dev.cov = std::max(dev.cov, ScaledDiff(filter.cov(), reference.P));
    }
    if (!data.has_z[k]) continue;
    const StepResult<M> r = filter.Update(data.z[k], data.R);
    if (r.status != FilterStatus::kOk) dev.all_ok = false;
    const auto o = reference.Update(data.z[k], data.R);
    dev.mean = std::max(dev.mean, ScaledDiff(filter.mean(), reference.x));
    dev.cov = std::max(dev.cov, ScaledDiff(filter.cov(), reference.P));
    dev.innovation = std::max(dev.innovation, ScaledDiff(r.innovation, o.innovation));
    dev.innovation_cov = std::max(dev.innovation_cov, ScaledDiff(r.innovation_cov, o.S));
    dev.log_likelihood =
        std::max(dev.log_likelihood, ScaledDiff(r.log_likelihood, o.log_likelihood));
    dev.nis = std::max(dev.nis, ScaledDiff(r.nis, o.nis));
    if (r.gain.rows() != N || r.gain.cols() != M) {
      dev.all_ok = false;
    } else {
      dev.gain = std::max(dev.gain, ScaledDiff(Mat<N, M>(r.gain), o.K));
    }
  }
  return dev;
}

// Covariances (P, S, K) within tol; the mean, innovation, log-likelihood and
// NIS within mean_tol (default tol).
inline ::testing::AssertionResult DeviationBelow(const Deviation& d, double tol,
                                                 double mean_tol = -1.0) {
  if (mean_tol < 0) mean_tol = tol;
  const double cov_max = d.CovMax();
  const double mean_max = d.MeanMax();
  if (d.all_ok && cov_max <= tol && mean_max <= mean_tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "status ok: " << d.all_ok << ", max deviation " << cov_max << " (tol " << tol << ") / "
         << mean_max << " (tol " << mean_tol << ") (mean " << d.mean << ", cov " << d.cov << ", nu "
         << d.innovation << ", S " << d.innovation_cov << ", loglik " << d.log_likelihood
         << ", nis " << d.nis << ", gain " << d.gain << ")";
}

// An Euler transition with one step per Predict.
template <class Model>
std::unique_ptr<Transition<Model>> EulerTransition(const typename Model::Params& params) {
  TransitionOptions options;
  options.integrator = Integrator::kEuler;
  options.substeps = 1;
  return MakeTransition<Model>(params, options);
}

// The reference for a model with an Euler transition: F = I + dt A, G = dt B.
template <class Model, class Meas>
HandKf<Model::kStateDim, Meas::kDim> EulerReference(const typename Model::Params& params,
                                                    double dt) {
  constexpr int N = Model::kStateDim;
  HandKf<N, Meas::kDim> ref;
  ref.F = Mat<N, N>::Identity() + dt * Model::A(params);
  ref.G = dt * Model::B();
  ref.H = Meas::H();
  return ref;
}

// A transition that always fails, as CVODES does on "too much work".
template <class Model>
class ThrowingTransition final : public Transition<Model> {
 public:
  using typename Transition<Model>::State;
  using typename Transition<Model>::Jacobian;
  explicit ThrowingTransition(const typename Model::Params& p) : Transition<Model>(p) {}
  State Step(const State&, double, double) override {
    throw NumericalError("CVODES: too much work (test)");
  }
  State StepWithJacobian(const State&, double, double, Jacobian*) override {
    throw NumericalError("CVODES: too much work (test)");
  }
  std::string Name() const override { return "throwing"; }
};

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_FILTERS_LINEAR_FIXTURE_H_
