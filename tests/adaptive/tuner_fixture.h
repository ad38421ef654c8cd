// Shared by the tuner's tests: white-accel Q, a simulator of the discretised
// model with additive Gaussian noise, and the gradient check against central
// differences.
#ifndef ESTLAB_TESTS_ADAPTIVE_TUNER_FIXTURE_H_
#define ESTLAB_TESTS_ADAPTIVE_TUNER_FIXTURE_H_

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "adaptive/likelihood.h"
#include "adaptive/tuner_impl.h"
#include "src/core/random.h"
#include "src/ode/fixed_step.h"

namespace estlab::testing {

constexpr double kPi = 3.14159265358979323846;

// qc [[dt^3/3, dt^2/2], [dt^2/2, dt]] on every (position, rate) pair.
template <class Model>
Mat<Model::kStateDim, Model::kStateDim> WhiteAccel(double qc, double dt) {
  Mat<Model::kStateDim, Model::kStateDim> Q = Mat<Model::kStateDim, Model::kStateDim>::Zero();
  for (const auto& [p, r] : Model::kPositionRatePairs) {
    Q(p, p) = qc * dt * dt * dt / 3.0;
    Q(p, r) = Q(r, p) = qc * dt * dt / 2.0;
    Q(r, r) = qc * dt;
  }
  return Q;
}

// Simulates x_{k+1} = Phi(x_k) + w_k, w_k ~ N(0, Q), z_k = h(x_k) + v_k,
// v_k ~ N(0, R), with the fixed-step scheme; rows t_k = k dt.
template <class Model, class Meas>
FilterData Simulate(Integrator scheme, const Vec<double, Model::kStateDim>& x0, double dt,
                    int steps, const Mat<Model::kStateDim, Model::kStateDim>& Q,
                    const Mat<Meas::kDim, Meas::kDim>& R, uint64_t seed,
                    const typename Model::Params& params = {}) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  Rng rng(seed);
  const Mat<N, N> LQ = Eigen::LLT<Mat<N, N>>(Q).matrixL();
  const Mat<M, M> LR = Eigen::LLT<Mat<M, M>>(R).matrixL();
  FilterData d;
  d.m = M;
  d.has_truth = true;
  Vec<double, N> x = x0;
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    d.t.push_back(t);
    d.lines.push_back(k + 2);
    Vec<double, M> v;
    for (int j = 0; j < M; ++j) v(j) = rng.Normal();
    const Vec<double, M> z = Meas::template Eval<double>(x, params) + LR * v;
    for (int j = 0; j < M; ++j) d.z.push_back(z(j));
    for (int i = 0; i < N; ++i) d.truth.push_back(x(i));
    Vec<double, N> w;
    for (int i = 0; i < N; ++i) w(i) = rng.Normal();
    x = FixedPropagate<Model, double>(scheme, x, t, t + dt, 1, 0.0, params) + LQ * w;
  }
  return d;
}

// The gradient the tuner uses (tuner_internal::Objective: chunked Jets,
// nested Jets for the EKF) against central differences of the double NLL at 5
// random points theta0 + U(-1, 1): second order with step h (the default,
// for NLLs exact to rounding), or fourth order,
//   g = [8 (f(h) - f(-h)) - (f(2h) - f(-2h))] / 12h,
// for a NLL with integration noise eps (CVODES), where a larger h keeps the
// noise term ~1.5 eps / h small while the truncation stays O(h^4).
struct CentralDifference {
  double h = 1e-5;
  bool fourth_order = false;
};

template <class Model, class Meas>
void CheckGradient(const InnovationLikelihood<Model, Meas>& lik, uint64_t seed, const char* label,
                   CentralDifference cd = {}) {
  const int k = lik.NumParams();
  const tuner_internal::Objective<Model, Meas> objective(lik);
  Rng rng(seed);
  auto nll_at = [&](std::vector<double> theta, int i, double step) {
    theta[i] += step;
    double f = 0.0;
    EXPECT_TRUE(lik.Nll(theta.data(), &f));
    return f;
  };
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> theta = lik.InitialTheta();
    for (double& v : theta) v += 2.0 * rng.Uniform() - 1.0;
    std::vector<double> grad(k);
    double f = 0.0;
    ASSERT_TRUE(objective.ValueAndGradient(theta.data(), &f, grad.data()));
    double worst = 0.0;
    for (int i = 0; i < k; ++i) {
      const double h = cd.h;
      double fd = (nll_at(theta, i, h) - nll_at(theta, i, -h)) / (2 * h);
      if (cd.fourth_order)
        fd = (4.0 * fd - (nll_at(theta, i, 2 * h) - nll_at(theta, i, -2 * h)) / (4 * h)) / 3.0;
      const double rel = std::abs(grad[i] - fd) / std::max(std::abs(grad[i]), 1.0);
      worst = std::max(worst, rel);
      EXPECT_LT(rel, 1e-6) << label << " point " << trial << " parameter " << lik.ParamNames()[i]
                           << ": AD " << grad[i] << " vs central differences " << fd;
    }
    std::printf("  %-5s point %d: NLL %12.4f, |grad| %10.4g, largest relative error %.2e\n", label,
                trial, f, Eigen::Map<const Eigen::VectorXd>(grad.data(), k).norm(), worst);
  }
}

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_ADAPTIVE_TUNER_FIXTURE_H_
