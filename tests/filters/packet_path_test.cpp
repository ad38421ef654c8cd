// The packet path (src/core/packet.h) changes no filter result beyond
// rounding: the particle filter on the pendulum (whose particles move and are
// measured kPacketWidth per call) against the same filter on a copy of the
// pendulum that is not a packet model (one scalar call per particle), on the
// same data and seed: means, covariances and log-likelihoods are identical
// bit for bit at every one of 200 steps with the C library's sin and exp
// (ESTLAB_VECTOR_MATH off, the default), and agree to 1e-12 with SLEEF's
// (on; the bound for "results identical to before"), which differ in the
// last bits. The UKF keeps one scalar
// call per sigma point (Transition::StepCloud explains why), so its results
// on the two models are identical bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "models/pendulum.h"
#include "src/core/random.h"
#include "src/filters/particle.h"
#include "src/filters/sigma_point.h"
#include "src/ode/transition_impl.h"

namespace estlab::testing {
namespace {

struct ScalarPendulum : models::Pendulum {
  static constexpr bool kPacketRhs = false;
};
static_assert(kPacketModel<models::Pendulum> && !kPacketModel<ScalarPendulum>);

struct Trace {
  std::vector<Vec<double, 2>> mean;
  std::vector<Mat<2, 2>> cov;
  std::vector<double> log_likelihood;
};

// 200 steps of dt = 0.05 of sin(theta) measured with sd 0.1, from a pendulum
// swinging at 1 rad (no process noise in the data, Q = 1e-4 I in the filter).
std::vector<Vec<double, 1>> Measurements() {
  const models::Pendulum::Params p;
  Vec<double, 2> x(1.0, 0.0);
  Rng rng(11);
  std::vector<Vec<double, 1>> z;
  for (int k = 0; k < 200; ++k) {
    if (k > 0)
      x = FixedPropagate<models::Pendulum, double>(Integrator::kRk4, x, 0.0, 0.05, 5, 0.0, p);
    z.push_back(Vec<double, 1>(std::sin(x(0)) + 0.1 * rng.Normal()));
  }
  return z;
}

template <class Model, template <class, class> class Filter, class Options>
Trace RunFilter(const Options& options) {
  const typename Model::Params p;
  TransitionOptions topt;
  topt.integrator = Integrator::kRk4;
  topt.substeps = 5;
  auto transition = MakeTransition<Model>(p, topt);
  Filter<Model, typename Model::Sin> filter(transition.get(), p, options);
  filter.Initialize(Vec<double, 2>(0.8, 0.1), 0.05 * Mat<2, 2>::Identity());
  const Mat<2, 2> Q = 1e-4 * Mat<2, 2>::Identity();
  const Mat<1, 1> R = Mat<1, 1>::Constant(0.01);
  Trace t;
  const std::vector<Vec<double, 1>> z = Measurements();
  for (size_t k = 0; k < z.size(); ++k) {
    if (k > 0) {
      EXPECT_EQ(filter.Predict(0.05 * (k - 1), 0.05 * k, Q), FilterStatus::kOk);
    }
    const StepResult<1> r = filter.Update(z[k], R);
    EXPECT_EQ(r.status, FilterStatus::kOk);
    t.mean.push_back(filter.mean());
    t.cov.push_back(filter.cov());
    t.log_likelihood.push_back(r.log_likelihood);
  }
  return t;
}

// Largest absolute difference of the means, covariances and log-likelihoods.
double Difference(const Trace& a, const Trace& b) {
  EXPECT_EQ(a.mean.size(), b.mean.size());
  double worst = 0.0;
  for (size_t k = 0; k < a.mean.size() && k < b.mean.size(); ++k) {
    worst = std::max(worst, (a.mean[k] - b.mean[k]).cwiseAbs().maxCoeff());
    worst = std::max(worst, (a.cov[k] - b.cov[k]).cwiseAbs().maxCoeff());
    worst = std::max(worst, std::abs(a.log_likelihood[k] - b.log_likelihood[k]));
  }
  return worst;
}

TEST(PacketPath, ParticleFilterResultsAreTheScalarPaths) {
  ParticleOptions options;
  options.num_particles = 999;  // not a multiple of the width: a padded last packet
  options.seed = 77;
  EXPECT_LE(Difference(RunFilter<models::Pendulum, ParticleFilter>(options),
                       RunFilter<ScalarPendulum, ParticleFilter>(options)),
            ESTLAB_VECTOR_MATH ? 1e-12 : 0.0);
}

TEST(PacketPath, UkfResultsAreBitForBitTheScalarPaths) {
  const SigmaPointOptions options;
  EXPECT_EQ(Difference(RunFilter<models::Pendulum, SigmaPointFilter>(options),
                       RunFilter<ScalarPendulum, SigmaPointFilter>(options)),
            0.0);
}

}  // namespace
}  // namespace estlab::testing
