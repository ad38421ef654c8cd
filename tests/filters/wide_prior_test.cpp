// Sigma-point and particle filters on the pendulum of Saerkkae & Svensson,
// Bayesian Filtering and Smoothing (2nd ed., 2023), from a WIDE prior
// (P0 = I, sd 1 rad): regression test of the wrapped-mean defect.
//
// The defect: WeightedMean formed sigma-point means relative to the first
// point and wrapped every point-to-point difference of an angle state to
// (-pi, pi]. With P0 = I the Gauss-Hermite grid corners differ by more than
// pi in theta, the wrapped differences jump by 2 pi and the GHKF's angle RMSE
// was 1.26 (a textbook GHKF: ~0.1). The rule now: the mean and covariance of
// a point set are plain weighted sums (no wrapping inside the set); only
// innovations of angle outputs vs data and errors vs truth are wrapped; the
// filter state is never wrapped. The particle filter's mean is the plain
// weighted mean of its particles (no circular mean).
//
// Settings (the book's pendulum example, with the wide prior):
//   state x = (theta, omega), f(x) = x + dt (omega, -(g / L) sin theta)
//     (one explicit Euler step of models::Pendulum, g = 9.81, L = 1, b = 0)
//   dt = 0.01, qc = 0.01, Q = qc [[dt^3/3, dt^2/2], [dt^2/2, dt]]
//   y_k = sin(theta_k) + r_k, R = 0.1 (models::Pendulum::Sin)
//   truth x_0 = (1.5, 0), x_k = f(x_{k-1}) + q_{k-1}, q ~ N(0, Q), k = 1..500
//   filters: m0 = (0, 0), P0 = I; Predict(t_{k-1}, t_k) then Update(y_k)
//   data seed 20230 (std::mt19937_64 + std::normal_distribution)
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "models/pendulum.h"
#include "src/core/types.h"
#include "src/filters/particle.h"
#include "src/filters/sigma_point.h"
#include "src/filters/sigma_rules.h"
#include "src/ode/transition.h"
#include "src/ode/transition_impl.h"  // MakeTransition<models::Pendulum>

namespace estlab::testing {
namespace {

using P = models::Pendulum;
using Vec2 = Eigen::Vector2d;
using Mat2 = Eigen::Matrix2d;
using Points2 = Eigen::Matrix<double, 2, Eigen::Dynamic>;

constexpr double kDt = 0.01;
constexpr double kQc = 0.01;
constexpr double kR = 0.1;
constexpr int kSteps = 500;
constexpr uint64_t kDataSeed = 20230;

double Time(int k) { return k * kDt; }

// Q = qc [[dt^3/3, dt^2/2], [dt^2/2, dt]]
Mat2 ProcessNoise() {
  Mat2 Q;
  Q << kDt * kDt * kDt / 3.0, kDt * kDt / 2.0, kDt * kDt / 2.0, kDt;
  return kQc * Q;
}

// x1 = x0 + h Rhs(x0): one explicit Euler step of the pendulum.
Vec2 EulerStep(const Vec2& x, double h) {
  const P::Params params;
  return x + h * P::Rhs<double>(0.0, x, 0.0, params);
}

// The same step as an estlab transition (Euler, one substep per Predict).
std::unique_ptr<Transition<P>> PendulumTransition() {
  TransitionOptions options;
  options.integrator = Integrator::kEuler;
  options.substeps = 1;
  return MakeTransition<P>(P::Params{}, options);
}

// truth[k], y[k] for k = 1..kSteps (index 0 holds x_0 and no measurement).
struct PendulumData {
  std::vector<Vec2> truth;
  std::vector<double> y;
};

// x_k = f(x_{k-1}) + L_Q e,  e ~ N(0, I),  L_Q L_Q^T = Q;  y_k = sin(theta_k) + sqrt(R) e'.
PendulumData SimulatePendulum() {
  std::mt19937_64 rng(kDataSeed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Mat2 LQ = Eigen::LLT<Mat2>(ProcessNoise()).matrixL();
  PendulumData d;
  d.truth.assign(kSteps + 1, Vec2(1.5, 0.0));
  d.y.assign(kSteps + 1, 0.0);
  for (int k = 1; k <= kSteps; ++k) {
    const double e0 = normal(rng), e1 = normal(rng);
    d.truth[k] = EulerStep(d.truth[k - 1], kDt) + LQ * Vec2(e0, e1);
    d.y[k] = std::sin(d.truth[k](0)) + std::sqrt(kR) * normal(rng);
  }
  return d;
}

// Reference sigma-point filter, textbook form (Saerkkae & Svensson 2023,
// additive-noise UKF / CKF / GHKF), with NO wrapping anywhere. Only the unit
// points xi_i and weights Wm_i, Wc_i come from estlab (MakeUnitSigmaPoints).
class ReferenceSigmaFilter {
 public:
  explicit ReferenceSigmaFilter(const SigmaPointOptions& options)
      : unit_(MakeUnitSigmaPoints(2, options)) {}

  void Initialize(const Vec2& m0, const Mat2& P0) {
    m_ = m0;
    P_ = P0;
  }

  // X_i = m + L xi_i,  X-_i = f(X_i),  m- = sum Wm_i X-_i,
  // P- = sum Wc_i (X-_i - m-)(X-_i - m-)^T + Q
  void Predict(double h, const Mat2& Q) {
    Points2 X = Draw(m_, P_);
    for (Eigen::Index i = 0; i < X.cols(); ++i) X.col(i) = EulerStep(X.col(i), h);
    m_ = X * unit_.mean_weights;
    const Points2 D = X.colwise() - m_;
    P_ = D * unit_.cov_weights.asDiagonal() * D.transpose() + Q;
  }

  // Y_i = m- + L- xi_i,  Z_i = h(Y_i) = sin(Y_i,theta),  mu = sum Wm_i Z_i,
  // S = sum Wc_i (Z_i - mu)^2 + R,  C = sum Wc_i (Y_i - m-)(Z_i - mu),
  // K = C S^-1,  m+ = m- + K (y - mu),  P+ = P- - K S K^T
  void Update(double y, double R) {
    const Points2 Y = Draw(m_, P_);
    const Eigen::RowVectorXd Z = Y.row(0).array().sin().matrix();
    const double mu = Z.dot(unit_.mean_weights);
    const Eigen::RowVectorXd dZ = Z.array() - mu;
    const double S = dZ.cwiseProduct(unit_.cov_weights.transpose()).dot(dZ) + R;
    const Vec2 C = (Y.colwise() - m_) * unit_.cov_weights.cwiseProduct(dZ.transpose());
    const Vec2 K = C / S;
    m_ += K * (y - mu);
    P_ -= K * S * K.transpose();
  }

  const Vec2& mean() const { return m_; }
  const Mat2& cov() const { return P_; }

 private:
  // X_i = m + L xi_i with L L^T = P (Eigen::LLT).
  Points2 Draw(const Vec2& m, const Mat2& P) const {
    const Eigen::LLT<Mat2> llt(P);
    EXPECT_EQ(llt.info(), Eigen::Success) << "reference: P not positive definite";
    const Mat2 L = llt.matrixL();
    return (L * unit_.points).colwise() + m;
  }

  UnitSigmaPoints unit_;
  Vec2 m_ = Vec2::Zero();
  Mat2 P_ = Mat2::Identity();
};

struct Rule {
  const char* label;
  SigmaRule rule;
  int gh_order;
};

// UKF with alpha = 1, beta = 0, kappa = 1 (Saerkkae's UKF), CKF, GHKF p = 3..7.
constexpr Rule kRules[] = {
    {"ukf", SigmaRule::kUnscented, 3},         {"ckf", SigmaRule::kCubature, 3},
    {"ghkf p=3", SigmaRule::kGaussHermite, 3}, {"ghkf p=4", SigmaRule::kGaussHermite, 4},
    {"ghkf p=5", SigmaRule::kGaussHermite, 5}, {"ghkf p=6", SigmaRule::kGaussHermite, 6},
    {"ghkf p=7", SigmaRule::kGaussHermite, 7},
};

SigmaPointOptions MakeOptions(const Rule& r) {
  SigmaPointOptions o;
  o.rule = r.rule;
  o.alpha = 1.0;
  o.beta = 0.0;
  o.kappa = 1.0;
  o.gh_order = r.gh_order;
  o.update = SigmaPointOptions::Update::kRedraw;
  o.jitter = 0.0;
  return o;
}

// One run of estlab's filter beside the reference: the posterior means after
// each update (k = 1..kSteps), and the largest differences of mean and
// covariance after any predict or update.
struct SigmaTrace {
  std::vector<Vec2> estlab_mean, reference_mean;
  double max_mean_diff = 0.0, max_cov_diff = 0.0;
  bool all_ok = true;
};

void RecordDiff(const SigmaPointFilter<P, P::Sin>& f, const ReferenceSigmaFilter& ref,
                SigmaTrace* t) {
  t->max_mean_diff = std::max(t->max_mean_diff, (f.mean() - ref.mean()).cwiseAbs().maxCoeff());
  t->max_cov_diff = std::max(t->max_cov_diff, (f.cov() - ref.cov()).cwiseAbs().maxCoeff());
}

SigmaTrace RunRule(const Rule& rule, const PendulumData& data) {
  auto transition = PendulumTransition();
  SigmaPointFilter<P, P::Sin> filter(transition.get(), P::Params{}, MakeOptions(rule));
  ReferenceSigmaFilter ref(MakeOptions(rule));
  const Mat2 Q = ProcessNoise();
  const Mat<1, 1> R = Mat<1, 1>::Constant(kR);
  filter.Initialize(Vec2::Zero(), Mat2::Identity());
  ref.Initialize(Vec2::Zero(), Mat2::Identity());
  SigmaTrace t;
  for (int k = 1; k <= kSteps; ++k) {
    t.all_ok &= filter.Predict(Time(k - 1), Time(k), Q) == FilterStatus::kOk;
    ref.Predict(Time(k) - Time(k - 1), Q);  // the h of FixedPropagate: (t1 - t0) / 1
    RecordDiff(filter, ref, &t);
    t.all_ok &= filter.Update(Vec<double, 1>(data.y[k]), R).status == FilterStatus::kOk;
    ref.Update(data.y[k], kR);
    RecordDiff(filter, ref, &t);
    t.estlab_mean.push_back(filter.mean());
    t.reference_mean.push_back(ref.mean());
  }
  return t;
}

// sqrt(1/K sum_k wrap(theta_est_k - theta_true_k)^2), k = 1..kSteps.
double AngleRmse(const std::vector<Vec2>& estimates, const PendulumData& data) {
  double sum_sq = 0.0;
  for (int k = 1; k <= kSteps; ++k) {
    const double e = WrapAngle(estimates[k - 1](0) - data.truth[k](0));
    sum_sq += e * e;
  }
  return std::sqrt(sum_sq / kSteps);
}

// A: estlab's sigma-point filters equal the textbook recursion at every step.
// Before the fix the GHKF (whose grid spans more than pi in theta with
// P0 = I) failed this from the first predict.
TEST(WidePriorTest, SigmaPointFiltersEqualTextbookReference) {
  const PendulumData data = SimulatePendulum();
  for (const Rule& rule : kRules) {
    const SigmaTrace t = RunRule(rule, data);
    std::printf("[ measured ] %-9s vs reference: max |dm| %.1e  max |dP| %.1e\n", rule.label,
                t.max_mean_diff, t.max_cov_diff);
    EXPECT_TRUE(t.all_ok) << rule.label;
    EXPECT_LE(t.max_mean_diff, 1e-10) << rule.label;
    EXPECT_LE(t.max_cov_diff, 1e-10) << rule.label;
  }
}

// B: every rule's angle RMSE is within 25 % of the UKF's, and the UKF is
// sane. Saerkkae reports ~0.1 for these settings from a narrow prior; the
// wide prior adds a transient of a few dozen steps with errors up to 1.5 rad
// (the textbook reference over data seeds 1..9 and 20230: UKF 0.07 to 0.17,
// 0.05 to 0.12 after step 50). 0.25 is well above that and far below what a
// broken filter gives (1.26 for the GHKF with wrapped point differences).
TEST(WidePriorTest, AngleRmseOfEveryRuleIsCloseToTheUkf) {
  const PendulumData data = SimulatePendulum();
  std::vector<double> rmse;
  for (const Rule& rule : kRules) {
    const SigmaTrace t = RunRule(rule, data);
    rmse.push_back(AngleRmse(t.estlab_mean, data));
    std::printf("[ measured ] %-9s angle RMSE %.4f (reference %.4f)\n", rule.label, rmse.back(),
                AngleRmse(t.reference_mean, data));
  }
  const double ukf = rmse[0];
  EXPECT_LT(ukf, 0.25);
  for (size_t i = 0; i < rmse.size(); ++i)
    EXPECT_LE(rmse[i] / ukf, 1.25) << kRules[i].label << " RMSE " << rmse[i] << " vs ukf " << ukf;
}

// Plain weighted moments of a particle set: m = sum_i w_i x_i,
// C = sum_i w_i (x_i - m)(x_i - m)^T (no circular mean, no wrapping).
Vec2 PlainMean(const Points2& x, const std::vector<double>& w) {
  Vec2 m = Vec2::Zero();
  for (Eigen::Index i = 0; i < x.cols(); ++i) m += w[i] * x.col(i);
  return m;
}

Mat2 PlainCov(const Points2& x, const std::vector<double>& w, const Vec2& m) {
  Mat2 C = Mat2::Zero();
  for (Eigen::Index i = 0; i < x.cols(); ++i)
    C += w[i] * (x.col(i) - m) * (x.col(i) - m).transpose();
  return C;
}

// The bootstrap weights of an update, recomputed from the particles and
// weights before it: w_i <- w_i N(y - sin theta_i; 0, R) / sum_j (...),
// in logs with the maximum taken out (the constant of N cancels).
std::vector<double> UpdatedWeights(const Points2& x, const std::vector<double>& w, double y) {
  std::vector<double> l(w.size());
  for (size_t i = 0; i < w.size(); ++i) {
    const double nu = y - std::sin(x(0, Eigen::Index(i)));
    l[i] = std::log(w[i]) - 0.5 * nu * nu / kR;
  }
  const double max_l = *std::max_element(l.begin(), l.end());
  double sum = 0.0;
  for (double& v : l) sum += (v = std::exp(v - max_l));
  for (double& v : l) v /= sum;
  return l;
}

struct MomentDiff {
  double mean = 0.0, cov = 0.0;
  void Add(const Vec2& m, const Mat2& C, const Vec2& m_ref, const Mat2& C_ref) {
    mean = std::max(mean, (m - m_ref).cwiseAbs().maxCoeff());
    cov = std::max(cov, (C - C_ref).cwiseAbs().maxCoeff());
  }
};

// C: the particle filter's estimate is the plain weighted mean (and
// covariance) of its particles. particle.h exposes particles() and weights();
// after an Update that resampled they are the resampled set with uniform
// weights, while mean()/cov() are those of the weighted set before
// resampling. So the posterior weights are recomputed here from the particles
// and weights read before the Update (which does not move particles) and
// compared at every step; when the filter did not resample, its own
// particles() and weights() are used as well. Before the fix the mean was a
// circular mean atan2(sum w sin, sum w cos) on the branch of the previous
// estimate, which differs from the plain mean by far more than 1e-10 with
// theta spread over sd 1 rad.
TEST(WidePriorTest, ParticleFilterMeanIsThePlainWeightedMean) {
  const PendulumData data = SimulatePendulum();
  auto transition = PendulumTransition();
  ParticleOptions options;
  options.num_particles = 20000;
  options.resample = ResampleScheme::kSystematic;
  options.seed = 7;
  ParticleFilter<P, P::Sin> pf(transition.get(), P::Params{}, options);
  pf.Initialize(Vec2::Zero(), Mat2::Identity());
  const Mat2 Q = ProcessNoise();
  const Mat<1, 1> R = Mat<1, 1>::Constant(kR);
  MomentDiff predicted, updated, updated_own;
  std::vector<Vec2> means;
  int resampled = 0;
  for (int k = 1; k <= kSteps; ++k) {
    ASSERT_EQ(pf.Predict(Time(k - 1), Time(k), Q), FilterStatus::kOk) << pf.last_error();
    const Points2 x = pf.particles();
    const std::vector<double> w = pf.weights();
    const Vec2 m_pred = PlainMean(x, w);
    predicted.Add(pf.mean(), pf.cov(), m_pred, PlainCov(x, w, m_pred));
    const StepResult<1> r = pf.Update(Vec<double, 1>(data.y[k]), R);
    ASSERT_EQ(r.status, FilterStatus::kOk) << r.message;
    const std::vector<double> w_post = UpdatedWeights(x, w, data.y[k]);
    const Vec2 m_post = PlainMean(x, w_post);
    updated.Add(pf.mean(), pf.cov(), m_post, PlainCov(x, w_post, m_post));
    if (pf.resampled()) {
      ++resampled;
    } else {
      const Vec2 m_own = PlainMean(pf.particles(), pf.weights());
      updated_own.Add(pf.mean(), pf.cov(), m_own, PlainCov(pf.particles(), pf.weights(), m_own));
    }
    means.push_back(pf.mean());
  }
  // For the closing note only (Monte Carlo; not asserted).
  std::printf(
      "[ measured ] pf (2e4 particles, systematic, resampled %d/%d): angle RMSE %.4f; "
      "max |mean - plain mean| predict %.1e update %.1e (own weights %.1e); "
      "max |cov - plain cov| predict %.1e update %.1e (own weights %.1e)\n",
      resampled, kSteps, AngleRmse(means, data), predicted.mean, updated.mean, updated_own.mean,
      predicted.cov, updated.cov, updated_own.cov);
  EXPECT_LE(predicted.mean, 1e-10);
  EXPECT_LE(updated.mean, 1e-10);
  EXPECT_LE(updated_own.mean, 1e-10);
  // Covariance: the same rule (no wrapping of differences inside the set).
  EXPECT_LE(predicted.cov, 1e-10);
  EXPECT_LE(updated.cov, 1e-10);
  EXPECT_LE(updated_own.cov, 1e-10);
}

}  // namespace
}  // namespace estlab::testing
