// Subset updates (src/filters/missing.h, issue 35): a measurement with some
// components missing (NaN) updates with the observed ones only. Each check
// against a reference written here:
//   * one update of every Gaussian kind (KF, EKF, IEKF, UKF, CKF, GHKF) and
//     of the particle filter, for each of the six partial patterns of a
//     three-output measurement, equals the same kind's update with a
//     measurement model that has only the observed outputs (Sub below): the
//     posterior, the log-likelihood, NIS, the reported innovation and S
//     (the missing components' rows and columns NaN), also for an angle
//     output whose innovation wraps;
//   * the KF and EKF updates also equal a hand Kalman update with the
//     observed rows H_o, R_oo (dynamic sizes, written out here) to 1e-12;
//   * a KF run over a record with every pattern and some empty rows equals a
//     hand KF to 1e-12 in every estimate and in the log-likelihood; the mean
//     NIS bounds count the observed components;
//   * the RTS smoother on that record equals the batch Gaussian conditioning
//     of every state on the observed components to 1e-10;
//   * two rows at one time (asynchronous sensors) update in turn as the
//     merged row would, R block-diagonal between them;
//   * the tuner's NLL is minus the run's log-likelihood on that record (KF,
//     EKF, UKF) to 1e-10, and its gradient matches central differences;
//   * EM takes partial rows, its NLL never rising; ALS refuses them, naming
//     the row.
#include <gtest/gtest.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>
#include <vector>

#include "adaptive/tuner.h"
#include "adaptive/tuner_impl.h"
#include "src/filters/filters.h"
#include "src/ode/transition_impl.h"
#include "src/run/filter_run_impl.h"
#include "tests/adaptive/tuner_fixture.h"

namespace estlab {
namespace {

using V2 = Vec<double, 2>;
using M2 = Mat<2, 2>;
using V3 = Vec<double, 3>;
using M3 = Mat<3, 3>;
using Dyn = Eigen::MatrixXd;
using DynV = Eigen::VectorXd;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kLog2PiHere = 1.83787706640934548356;

// A damped oscillator as a discrete-time map, x+ = x + dt (A x), measured
// by three outputs:
//   lin3: h(x) = [x1, x2, x1 - 2 x2]
//   nl3:  h(x) = [x1, sin(x2), x1 x2]
struct Osc {
  static constexpr const char* kName = "subset-test";
  static constexpr const char* kDescription = "oscillator with three outputs (test model)";
  static constexpr int kStateDim = 2;
  static constexpr int kInputDim = 1;
  static constexpr bool kStiff = false;
  static constexpr bool kDiscreteTime = true;
  static constexpr std::array<const char*, 2> kStateNames = {"x1", "x2"};
  static constexpr std::array<const char*, 2> kStateUnits = {"", ""};
  static constexpr std::array<bool, 2> kAngleStates = {false, false};
  static constexpr std::array<std::pair<int, int>, 0> kPositionRatePairs = {};
  struct Params {
    double k = 1.4, c = 0.3;
  };
  static constexpr std::array<ParamSpec<Params>, 2> kParams = {{
      {"k", &Params::k, "spring", Constraint::kAny},
      {"c", &Params::c, "damping", Constraint::kAny},
  }};
  template <class T>
  static Vec<T, 2> Step(const T& /*t*/, const Vec<T, 2>& x, double dt, double u, const Params& p) {
    Vec<T, 2> next;
    next(0) = x(0) + dt * x(1);
    next(1) = x(1) + dt * (-p.k * x(0) - p.c * x(1) + u);
    return next;
  }
  static constexpr std::array<const char*, 0> kInvariantNames = {};
  static bool InvariantsHold(const Params&, double) { return false; }
  static Vec<double, 0> Invariants(const Vec<double, 2>&, const Params&) {
    return Vec<double, 0>();
  }
  struct Lin3 {
    static constexpr const char* kName = "lin3";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"a", "b", "c"};
    static constexpr std::array<bool, 3> kAngleOutputs = {false, false, false};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      return Vec<T, 3>(x(0), x(1), x(0) - 2.0 * x(1));
    }
  };
  struct Nl3 {
    static constexpr const char* kName = "nl3";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"a", "b", "c"};
    static constexpr std::array<bool, 3> kAngleOutputs = {false, false, false};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      using std::sin;
      return Vec<T, 3>(x(0), sin(x(1)), x(0) * x(1));
    }
  };
  // ang3: nl3 with its first output an angle (innovations wrapped).
  struct Ang3 {
    static constexpr const char* kName = "ang3";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"a", "b", "c"};
    static constexpr std::array<bool, 3> kAngleOutputs = {true, false, false};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 2>& x, const Params& p) {
      return Nl3::Eval<T>(x, p);
    }
  };
  // root3: lin3 with its third output sqrt(x1 - 2 x2 - 1), undefined (NaN)
  // at the KF's linearisation point (the prior mean): a sensor that never
  // reports must not stop the KF.
  struct Root3 {
    static constexpr const char* kName = "root3";
    static constexpr int kDim = 3;
    static constexpr std::array<const char*, 3> kOutputs = {"a", "b", "c"};
    static constexpr std::array<bool, 3> kAngleOutputs = {false, false, false};
    template <class T>
    static Vec<T, 3> Eval(const Vec<T, 2>& x, const Params& /*p*/) {
      using std::sqrt;
      return Vec<T, 3>(x(0), x(1), sqrt(x(0) - 2.0 * x(1) - 1.0));
    }
  };
  using Measurements = std::tuple<Lin3, Nl3, Ang3, Root3>;
};

// The outputs of Base whose bit is set in Mask, as a measurement of its own:
// the reference "update with the observed components only".
template <int D>
constexpr std::array<const char*, size_t(D)> Pick(const std::array<const char*, 3>& a, int mask) {
  std::array<const char*, size_t(D)> out{};
  size_t i = 0;
  for (int j = 0; j < 3; ++j)
    if ((mask >> j) & 1) out[i++] = a[size_t(j)];
  return out;
}
template <int D>
constexpr std::array<bool, size_t(D)> PickFlags(const std::array<bool, 3>& a, int mask) {
  std::array<bool, size_t(D)> out{};
  size_t i = 0;
  for (int j = 0; j < 3; ++j)
    if ((mask >> j) & 1) out[i++] = a[size_t(j)];
  return out;
}
template <class Base, int Mask>
struct Sub {
  static constexpr const char* kName = "sub";
  static constexpr int kDim = std::popcount(unsigned(Mask));
  static constexpr std::array<const char*, size_t(kDim)> kOutputs =
      Pick<kDim>(Base::kOutputs, Mask);
  static constexpr std::array<bool, size_t(kDim)> kAngleOutputs =
      PickFlags<kDim>(Base::kAngleOutputs, Mask);
  template <class T>
  static Vec<T, kDim> Eval(const Vec<T, 2>& x, const Osc::Params& p) {
    const Vec<T, 3> full = Base::template Eval<T>(x, p);
    Vec<T, kDim> out;
    int i = 0;
    for (int j = 0; j < 3; ++j)
      if ((Mask >> j) & 1) out(i++) = full(j);
    return out;
  }
};

const V2 kX(0.4, -0.7);
const M2 kP = (M2() << 0.3, 0.05, 0.05, 0.2).finished();
const V3 kZ(0.55, -0.45, 1.6);
const V3 kZWrapped(0.55 - 2.0 * 3.14159265358979323846, -0.45, 1.6);  // ang3: wraps to 0.15
const M3 kR = (M3() << 0.02, 0.004, 0.0, 0.004, 0.03, 0.002, 0.0, 0.002, 0.05).finished();

std::vector<int> ObservedOf(int mask) {
  std::vector<int> idx;
  for (int j = 0; j < 3; ++j)
    if ((mask >> j) & 1) idx.push_back(j);
  return idx;
}

// The outcome of one update: what the comparisons look at.
struct Outcome {
  V2 x;
  M2 P;
  double loglik = 0.0, nis = 0.0;
  Vec<double, 3> nu;
  Mat<3, 3> S;  // the reported innovation covariance (NaN beyond kDim)
  int observed = 0;
};

template <class Meas>
Outcome OneUpdate(const FilterKindOptions& kind, const Vec<double, Meas::kDim>& z,
                  const Mat<Meas::kDim, Meas::kDim>& R) {
  FilterSpec spec;
  spec.filter = kind;
  spec.transition.integrator = Integrator::kDiscrete;
  const Osc::Params p;
  auto transition = MakeTransition<Osc>(p, spec.transition);
  auto filter = MakeFilter<Osc, Meas>(spec, p, transition.get());
  filter->SetTime(0.0);
  filter->Initialize(kX, kP);
  const StepResult<Meas::kDim> r = filter->Update(z, R);
  EXPECT_EQ(r.status, FilterStatus::kOk) << r.message;
  Outcome o;
  o.x = filter->mean();
  o.P = filter->cov();
  o.loglik = r.log_likelihood;
  o.nis = r.nis;
  o.nu.setConstant(kNaN);
  o.S.setConstant(kNaN);
  for (int j = 0; j < Meas::kDim; ++j) {
    o.nu(j) = r.innovation(j);
    for (int i = 0; i < Meas::kDim; ++i) o.S(i, j) = r.innovation_cov(i, j);
  }
  o.observed = r.observed;
  return o;
}

// The full measurement with the components not in `mask` missing, against
// Sub<Base, Mask> with only the observed ones.
template <class Base, int Mask>
void CheckPattern(const FilterKindOptions& kind, double tol, const V3& z_full) {
  using S = Sub<Base, Mask>;
  constexpr int D = S::kDim;
  const std::vector<int> idx = ObservedOf(Mask);
  V3 z = z_full;
  for (int j = 0; j < 3; ++j)
    if (!((Mask >> j) & 1)) z(j) = kNaN;
  Vec<double, D> z_o;
  Mat<D, D> R_o;
  for (int a = 0; a < D; ++a) {
    z_o(a) = z_full(idx[size_t(a)]);
    for (int b = 0; b < D; ++b) R_o(a, b) = kR(idx[size_t(a)], idx[size_t(b)]);
  }
  const Outcome full = OneUpdate<Base>(kind, z, kR);
  const Outcome sub = OneUpdate<S>(kind, z_o, R_o);
  SCOPED_TRACE("mask " + std::to_string(Mask));
  EXPECT_LT((full.x - sub.x).cwiseAbs().maxCoeff(), tol);
  EXPECT_LT((full.P - sub.P).cwiseAbs().maxCoeff(), tol);
  EXPECT_NEAR(full.loglik, sub.loglik, tol * std::max(1.0, std::abs(sub.loglik)));
  EXPECT_NEAR(full.nis, sub.nis, tol * std::max(1.0, sub.nis));
  EXPECT_EQ(full.observed, D);
  // The reported innovation and S: the observed ones equal the reduced
  // update's, the missing rows and columns are NaN (empty cells in the CSV).
  for (int j = 0; j < 3; ++j) {
    const auto a = std::find(idx.begin(), idx.end(), j);
    if (a == idx.end()) {
      EXPECT_TRUE(std::isnan(full.nu(j))) << "component " << j;
      EXPECT_TRUE(full.S.row(j).array().isNaN().all() && full.S.col(j).array().isNaN().all());
      continue;
    }
    EXPECT_NEAR(full.nu(j), sub.nu(int(a - idx.begin())), tol);
    for (int i = 0; i < D; ++i)
      EXPECT_NEAR(full.S(idx[size_t(i)], j), sub.S(i, int(a - idx.begin())), tol);
  }
}

template <class Base>
void CheckEveryPattern(const FilterKindOptions& kind, double tol, const V3& z = kZ) {
  CheckPattern<Base, 1>(kind, tol, z);
  CheckPattern<Base, 2>(kind, tol, z);
  CheckPattern<Base, 3>(kind, tol, z);
  CheckPattern<Base, 4>(kind, tol, z);
  CheckPattern<Base, 5>(kind, tol, z);
  CheckPattern<Base, 6>(kind, tol, z);
  CheckPattern<Base, 7>(kind, tol, z);
}

std::vector<FilterKindOptions> GaussianKinds() {
  return {FilterKindOptions(KfOptions{}),
          FilterKindOptions(EkfOptions{}),
          FilterKindOptions(EkfOptions{.iterations = 3}),
          FilterKindOptions(SigmaPointOptions{}),
          FilterKindOptions(SigmaPointOptions{.rule = SigmaRule::kCubature}),
          FilterKindOptions(SigmaPointOptions{.rule = SigmaRule::kGaussHermite})};
}

TEST(SubsetUpdate, EveryKindEqualsItsUpdateWithTheObservedOutputsAlone) {
  for (const FilterKindOptions& kind : GaussianKinds()) {
    SCOPED_TRACE(FilterKindName(KindOf(kind)));
    CheckEveryPattern<Osc::Lin3>(kind, 1e-12);
    CheckEveryPattern<Osc::Nl3>(kind, 1e-10);
    CheckEveryPattern<Osc::Ang3>(kind, 1e-10, kZWrapped);  // an angle output that wraps
  }
  // The particle filter: the same particles (same seed), weighted by the
  // observed components.
  CheckEveryPattern<Osc::Nl3>(FilterKindOptions(ParticleOptions{.num_particles = 500}), 1e-10);
}

// The Kalman update by hand with the observed rows only (dynamic sizes):
// S = H_o P H_o^T + R_oo, K = P H_o^T S^-1, x+ = x + K nu_o,
// P+ = (I - K H_o) P (I - K H_o)^T + K R_oo K^T.
struct HandUpdate {
  V2 x;
  M2 P;
  double loglik = 0.0;
};
HandUpdate HandKalman(const V2& x, const M2& P, const Dyn& H, const Dyn& R, const DynV& nu) {
  const Dyn S = H * P * H.transpose() + R;
  const Dyn K = P * H.transpose() * S.inverse();
  HandUpdate u;
  u.x = x + K * nu;
  const M2 I_KH = M2::Identity() - K * H;
  u.P = I_KH * P * I_KH.transpose() + K * R * K.transpose();
  u.loglik = -0.5 * (std::log(S.determinant()) + nu.dot(S.inverse() * nu) +
                     double(nu.size()) * kLog2PiHere);
  return u;
}

// H_o, R_oo and nu_o of the nl3 measurement at x for the components in idx.
void ObservedRows(const V2& x, const V3& z, const std::vector<int>& idx, Dyn* H, Dyn* R, DynV* nu) {
  const V3 h(x(0), std::sin(x(1)), x(0) * x(1));
  const Mat<3, 2> J = (Mat<3, 2>() << 1.0, 0.0, 0.0, std::cos(x(1)), x(1), x(0)).finished();
  const Eigen::Index d = Eigen::Index(idx.size());
  H->resize(d, 2);
  R->resize(d, d);
  nu->resize(d);
  for (Eigen::Index a = 0; a < d; ++a) {
    H->row(a) = J.row(idx[size_t(a)]);
    (*nu)(a) = z(idx[size_t(a)]) - h(idx[size_t(a)]);
    for (Eigen::Index b = 0; b < d; ++b) (*R)(a, b) = kR(idx[size_t(a)], idx[size_t(b)]);
  }
}

TEST(SubsetUpdate, EkfEqualsTheHandKalmanUpdateOnTheObservedRows) {
  for (int mask = 1; mask < 8; ++mask) {
    SCOPED_TRACE("mask " + std::to_string(mask));
    V3 z = kZ;
    for (int j = 0; j < 3; ++j)
      if (!((mask >> j) & 1)) z(j) = kNaN;
    Dyn H, R;
    DynV nu;
    ObservedRows(kX, kZ, ObservedOf(mask), &H, &R, &nu);
    const HandUpdate hand = HandKalman(kX, kP, H, R, nu);
    const Outcome ekf = OneUpdate<Osc::Nl3>(EkfOptions{}, z, kR);
    EXPECT_LT((ekf.x - hand.x).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((ekf.P - hand.P).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_NEAR(ekf.loglik, hand.loglik, 1e-12 * std::max(1.0, std::abs(hand.loglik)));
    // The KF linearises h about the prior mean, so its update is the same.
    const Outcome kf = OneUpdate<Osc::Nl3>(KfOptions{}, z, kR);
    EXPECT_LT((kf.x - hand.x).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((kf.P - hand.P).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_NEAR(kf.loglik, hand.loglik, 1e-12 * std::max(1.0, std::abs(hand.loglik)));
  }
}

// ---------------------------------------------------------------------------
// A record with every pattern: rows cycle through the masks 7, 0, 1, ..., 6
// (0: nothing observed, no update), on an uneven grid.

M2 StepMatrix(double dt, const Osc::Params& p) {
  return (M2() << 1.0, dt, -p.k * dt, 1.0 - p.c * dt).finished();
}
const M2 kQ = (M2() << 1e-3, 0.0, 0.0, 2e-3).finished();
const V2 kPrior(0.8, 0.1);
const M2 kP0 = (M2() << 0.2, 0.0, 0.0, 0.2).finished();

FilterData PatternRecord(int n) {
  const Osc::Params p;
  FilterData d;
  d.path = "subset.csv";
  d.m = 3;
  V2 x(1.0, 0.0);
  double t = 0.0;
  for (int k = 0; k < n; ++k) {
    if (k > 0) {
      x = StepMatrix(t - d.t.back(), p) * x + 0.02 * V2(std::sin(1.3 * k), std::cos(0.7 * k));
    }
    d.t.push_back(t);
    d.lines.push_back(k + 2);
    const V3 z = V3(x(0), x(1), x(0) - 2.0 * x(1)) +
                 0.1 * V3(std::sin(3.1 * k), std::cos(2.9 * k), std::sin(1.7 * k));
    const int mask = (k + 7) % 8;  // 7, 0, 1, ..., 6: the full row first
    for (int j = 0; j < 3; ++j) d.z.push_back((mask >> j) & 1 ? z(j) : kNaN);
    t += k % 2 ? 0.25 : 0.1;
  }
  return d;
}

FilterSpec OscSpec(const FilterKindOptions& kind) {
  const Osc::Params p;
  FilterSpec spec;
  spec.params = {p.k, p.c};
  spec.measurement = "lin3";
  spec.transition.integrator = Integrator::kDiscrete;
  spec.filter = kind;
  spec.x0 = {kPrior(0), kPrior(1)};
  spec.p0 = {kP0(0, 0), kP0(0, 1), kP0(1, 0), kP0(1, 1)};
  spec.q = {kQ(0, 0), kQ(0, 1), kQ(1, 0), kQ(1, 1)};
  spec.r.assign(kR.data(), kR.data() + 9);
  return spec;
}

TEST(SubsetUpdate, KfRunEqualsTheHandKfOnEveryPattern) {
  const Osc::Params p;
  const FilterData d = PatternRecord(96);
  const FilterRunOutput out = RunFilterWith<Osc, Osc::Lin3>(OscSpec(KfOptions{}), d);
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  // The hand KF: predict with the exact map, update with the observed rows.
  const Mat<3, 2> J = (Mat<3, 2>() << 1.0, 0.0, 0.0, 1.0, 1.0, -2.0).finished();
  V2 x = kPrior;
  M2 P = kP0;
  double loglik = 0.0;
  long updates = 0, dof = 0;
  std::vector<V2> hand;
  for (size_t k = 0; k < d.t.size(); ++k) {
    if (k > 0) {
      const M2 A = StepMatrix(d.t[k] - d.t[k - 1], p);
      x = A * x;
      P = A * P * A.transpose() + kQ;
    }
    std::vector<int> idx;
    for (int j = 0; j < 3; ++j)
      if (std::isfinite(d.z[k * 3 + size_t(j)])) idx.push_back(j);
    if (!idx.empty()) {
      const Eigen::Index m = Eigen::Index(idx.size());
      Dyn H(m, 2), R(m, m);
      DynV nu(m);
      for (Eigen::Index a = 0; a < m; ++a) {
        H.row(a) = J.row(idx[size_t(a)]);
        nu(a) = d.z[k * 3 + size_t(idx[size_t(a)])] - H.row(a).dot(x);
        for (Eigen::Index b = 0; b < m; ++b) R(a, b) = kR(idx[size_t(a)], idx[size_t(b)]);
      }
      const HandUpdate u = HandKalman(x, P, H, R, nu);
      x = u.x;
      P = u.P;
      loglik += u.loglik;
      ++updates;
      dof += m;
    }
    hand.push_back(x);
  }
  auto col = [&](const std::string& name) {
    return size_t(std::find(out.columns.begin(), out.columns.end(), name) - out.columns.begin());
  };
  const size_t x1 = col("x1_est"), x2 = col("x2_est");
  ASSERT_LT(std::max(x1, x2), out.columns.size());
  ASSERT_EQ(out.rows.size(), hand.size());
  double worst = 0.0;
  for (size_t k = 0; k < hand.size(); ++k)
    worst = std::max(worst, (V2(out.rows[k][x1], out.rows[k][x2]) - hand[k]).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-12);
  EXPECT_NEAR(out.summary.loglik, loglik, 1e-12 * std::abs(loglik));
  EXPECT_EQ(out.summary.updates, updates);
  EXPECT_EQ(updates, 84);  // 96 rows, every eighth has nothing observed
  double bounds[2];
  ChiSquareMeanBounds95(updates, dof, bounds);
  EXPECT_DOUBLE_EQ(out.summary.nis_bounds95[0], bounds[0]);
  EXPECT_DOUBLE_EQ(out.summary.nis_bounds95[1], bounds[1]);
  double full[2];
  ChiSquareBounds95(updates, 3, full);
  EXPECT_GT(std::abs(bounds[1] - full[1]), 0.05);  // the observed dof, not 3 per update
}

// A component whose h is not finite at the KF's linearisation point is no
// failure when it is never observed: the KF checks the observed rows of h*,
// H and D only, and gives lin3's estimates (the same a and b rows).
TEST(SubsetUpdate, KfIgnoresAnUndefinedRowOfAComponentNeverObserved) {
  FilterData d = PatternRecord(40);
  for (size_t k = 0; k < d.t.size(); ++k) d.z[k * 3 + 2] = kNaN;
  FilterSpec spec = OscSpec(KfOptions{});
  const FilterRunOutput lin = RunFilterWith<Osc, Osc::Lin3>(spec, d);
  spec.measurement = "root3";
  const FilterRunOutput root = RunFilterWith<Osc, Osc::Root3>(spec, d);
  ASSERT_TRUE(root.summary.ok) << root.summary.message;
  ASSERT_TRUE(lin.summary.ok) << lin.summary.message;
  ASSERT_EQ(root.rows.size(), lin.rows.size());
  for (const char* name : {"x1_est", "x2_est", "x1_var", "x2_var"}) {
    const auto j =
        size_t(std::find(lin.columns.begin(), lin.columns.end(), name) - lin.columns.begin());
    ASSERT_LT(j, lin.columns.size()) << name;
    for (size_t k = 0; k < lin.rows.size(); ++k)
      EXPECT_NEAR(root.rows[k][j], lin.rows[k][j], 1e-12) << name << " row " << k;
  }
  EXPECT_NEAR(root.summary.loglik, lin.summary.loglik, 1e-12 * std::abs(lin.summary.loglik));
  // Observed, the undefined row is a failure that says so.
  d.z[5 * 3 + 2] = 0.5;
  const FilterRunOutput seen = RunFilterWith<Osc, Osc::Root3>(spec, d);
  EXPECT_FALSE(seen.summary.ok);
  EXPECT_NE(seen.summary.message.find("not finite"), std::string::npos) << seen.summary.message;
}

// The RTS smoother over a record with every pattern equals the batch
// Gaussian conditioning of all states on the observed components:
// X = (x_0, ..., x_n-1) with x_0 ~ N(x0, P0), x_k+1 = A_k x_k + w_k,
// w_k ~ N(0, Q); y = C X + v with the observed rows of H at each row.
TEST(SubsetUpdate, RtsEqualsTheBatchConditioningOnTheObservedComponents) {
  const Osc::Params p;
  const FilterData d = PatternRecord(18);
  FilterSpec spec = OscSpec(KfOptions{});
  spec.smooth = true;
  const FilterRunOutput out = RunFilterWith<Osc, Osc::Lin3>(spec, d);
  ASSERT_TRUE(out.summary.ok) << out.summary.message;
  const Eigen::Index n = Eigen::Index(d.t.size());
  // Prior moments of X.
  DynV mu(2 * n);
  Dyn Sigma = Dyn::Zero(2 * n, 2 * n);
  mu.segment<2>(0) = kPrior;
  Sigma.block<2, 2>(0, 0) = kP0;
  for (Eigen::Index k = 1; k < n; ++k) {
    const M2 A = StepMatrix(d.t[size_t(k)] - d.t[size_t(k) - 1], p);
    mu.segment<2>(2 * k) = A * mu.segment<2>(2 * (k - 1));
    // Cov(x_k, x_j) = A Cov(x_k-1, x_j) for j < k; Var(x_k) = A Var A^T + Q.
    for (Eigen::Index j = 0; j < k; ++j) {
      Sigma.block<2, 2>(2 * k, 2 * j) = A * Sigma.block<2, 2>(2 * (k - 1), 2 * j);
      Sigma.block<2, 2>(2 * j, 2 * k) = Sigma.block<2, 2>(2 * k, 2 * j).transpose();
    }
    Sigma.block<2, 2>(2 * k, 2 * k) =
        A * Sigma.block<2, 2>(2 * (k - 1), 2 * (k - 1)) * A.transpose() + kQ;
  }
  // The observed components: rows of C, y and the block-diagonal R.
  const Mat<3, 2> J = (Mat<3, 2>() << 1.0, 0.0, 0.0, 1.0, 1.0, -2.0).finished();
  std::vector<std::pair<Eigen::Index, int>> seen;  // (row k, component j)
  for (Eigen::Index k = 0; k < n; ++k)
    for (int j = 0; j < 3; ++j)
      if (std::isfinite(d.z[size_t(k) * 3 + size_t(j)])) seen.push_back({k, j});
  const Eigen::Index m = Eigen::Index(seen.size());
  Dyn C = Dyn::Zero(m, 2 * n), R = Dyn::Zero(m, m);
  DynV y(m);
  for (Eigen::Index a = 0; a < m; ++a) {
    C.block<1, 2>(a, 2 * seen[size_t(a)].first) = J.row(seen[size_t(a)].second);
    y(a) = d.z[size_t(seen[size_t(a)].first) * 3 + size_t(seen[size_t(a)].second)];
    for (Eigen::Index b = 0; b < m; ++b)
      if (seen[size_t(a)].first == seen[size_t(b)].first)
        R(a, b) = kR(seen[size_t(a)].second, seen[size_t(b)].second);
  }
  const Dyn G = C * Sigma * C.transpose() + R;
  const DynV post = mu + Sigma * C.transpose() * G.ldlt().solve(y - C * mu);
  auto col = [&](const std::string& name) {
    return size_t(std::find(out.columns.begin(), out.columns.end(), name) - out.columns.begin());
  };
  const size_t x1 = col("x1_est"), x2 = col("x2_est");
  ASSERT_LT(std::max(x1, x2), out.columns.size());
  ASSERT_EQ(Eigen::Index(out.rows.size()), n);
  double worst = 0.0;
  for (Eigen::Index k = 0; k < n; ++k)
    worst = std::max(worst,
                     (V2(out.rows[size_t(k)][x1], out.rows[size_t(k)][x2]) - post.segment<2>(2 * k))
                         .cwiseAbs()
                         .maxCoeff());
  EXPECT_LT(worst, 1e-10);
}

// Asynchronous sensors: two rows at one time, one with component a and one
// with b and c, update in turn with no prediction between them; with R
// block-diagonal between a and (b, c) that is the one update of the merged
// row (the chain rule), in the estimates and the log-likelihood.
TEST(SubsetUpdate, RowsAtOneTimeUpdateInTurnAsTheMergedRow) {
  const FilterData merged = PatternRecord(40);
  FilterData split = merged;
  split.t.clear(), split.lines.clear(), split.z.clear();
  std::vector<size_t> second;  // the split row that ends merged row k
  for (size_t k = 0; k < merged.t.size(); ++k) {
    const double* z = &merged.z[k * 3];
    split.t.push_back(merged.t[k]);
    split.lines.push_back(long(split.t.size()) + 1);
    split.z.insert(split.z.end(), {z[0], kNaN, kNaN});
    split.t.push_back(merged.t[k]);
    split.lines.push_back(long(split.t.size()) + 1);
    split.z.insert(split.z.end(), {kNaN, z[1], z[2]});
    second.push_back(split.t.size() - 1);
  }
  FilterSpec spec = OscSpec(EkfOptions{});
  spec.r = {kR(0, 0), 0.0, 0.0, 0.0, kR(1, 1), kR(1, 2), 0.0, kR(2, 1), kR(2, 2)};
  const FilterRunOutput a = RunFilterWith<Osc, Osc::Lin3>(spec, merged);
  const FilterRunOutput b = RunFilterWith<Osc, Osc::Lin3>(spec, split);
  ASSERT_TRUE(a.summary.ok && b.summary.ok) << a.summary.message << b.summary.message;
  const size_t x1 = 1, x2 = 2;
  ASSERT_EQ(a.columns[x1], "x1_est");
  ASSERT_EQ(a.columns[x2], "x2_est");
  double worst = 0.0;
  for (size_t k = 0; k < merged.t.size(); ++k)
    for (size_t c : {x1, x2})
      worst = std::max(worst, std::abs(a.rows[k][c] - b.rows[second[k]][c]));
  EXPECT_LT(worst, 1e-12);
  EXPECT_NEAR(a.summary.loglik, b.summary.loglik, 1e-12 * std::abs(a.summary.loglik));
}

TEST(SubsetUpdate, TunerNllIsMinusTheRunsLogLikelihoodWithMissingComponents) {
  const std::vector<FilterData> datasets = {PatternRecord(80)};
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{})}) {
    const FilterSpec spec = OscSpec(kind);
    const FilterRunOutput out = RunFilterWith<Osc, Osc::Lin3>(spec, datasets[0]);
    SCOPED_TRACE(out.summary.filter);
    ASSERT_TRUE(out.summary.ok) << out.summary.message;
    TunerOptions options;
    options.q_param = NoiseParam::kFixed;
    options.r_param = NoiseParam::kFixed;
    const InnovationLikelihood<Osc, Osc::Lin3> lik(spec, options, datasets);
    EXPECT_EQ(lik.NumTerms(), out.summary.updates);
    double nll = 0.0;
    ASSERT_TRUE(lik.Nll<double>(lik.InitialTheta().data(), &nll));
    EXPECT_NEAR(nll, -out.summary.loglik, 1e-10 * std::abs(nll));
  }
}

TEST(SubsetUpdate, TunerGradientMatchesCentralDifferencesWithMissingComponents) {
  const std::vector<FilterData> datasets = {PatternRecord(64)};
  TunerOptions options;
  options.q_param = NoiseParam::kDiag;
  options.r_param = NoiseParam::kDiag;
  uint64_t seed = 41;
  for (const FilterKindOptions& kind :
       {FilterKindOptions(KfOptions{}), FilterKindOptions(EkfOptions{}),
        FilterKindOptions(SigmaPointOptions{.alpha = 0.5})}) {
    FilterSpec spec = OscSpec(kind);
    spec.r = {kR(0, 0), 0.0, 0.0, 0.0, kR(1, 1), 0.0, 0.0, 0.0, kR(2, 2)};
    const InnovationLikelihood<Osc, Osc::Lin3> lik(spec, options, datasets);
    ASSERT_EQ(lik.NumParams(), 5);
    testing::CheckGradient(lik, seed++, "subset update");
  }
}

// EM takes partial rows (its M-step treats the missing components as latent;
// adaptive/em.h, and tests/adaptive/em_test.cpp against the ml optimum):
// on every pattern of three outputs the KF's NLL never rises. ALS refuses a
// row with some components missing, naming it.
TEST(SubsetUpdate, EmTakesPartialRowsAndAlsRefusesThem) {
  const std::vector<FilterData> datasets = {PatternRecord(96)};
  FilterSpec spec = OscSpec(KfOptions{});
  TunerOptions em;
  em.estimator = Estimator::kEm;
  em.q_param = NoiseParam::kDiag;
  em.r_param = NoiseParam::kDiag;
  em.max_iterations = 40;
  const TuneResult fit = TuneWith<Osc, Osc::Lin3>(spec, em, datasets);
  ASSERT_TRUE(fit.IsSolutionUsable()) << fit.message << " " << fit.termination;
  EXPECT_EQ(fit.nll_increases, 0);
  EXPECT_LT(fit.nll_tuned, fit.nll_initial);
  // ALS on a record whose only gap is one component of row 5.
  FilterData complete = datasets[0];
  for (double& z : complete.z)
    if (!std::isfinite(z)) z = 0.1;
  complete.z[5 * 3 + 2] = kNaN;
  TunerOptions als;
  als.estimator = Estimator::kAls;
  als.q_param = NoiseParam::kDiag;
  als.r_param = NoiseParam::kDiag;
  try {
    TuneWith<Osc, Osc::Lin3>(spec, als, {complete});
    ADD_FAILURE() << "ALS took a partial row";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("row 5 (line 7) of subset.csv has a missing value"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace estlab
