// Runs one filter over a dataset: predict to each measurement time, update
// when the row has a measurement, record the per-step diagnostics and the
// summary metrics. Include only from src/models_inst/*.cpp.
//
// Per step k (time t_k):
//   Q_k = Q, or qc * Q_wa(t_k - t_{k-1})       (white-noise acceleration)
//   predict from t_{k-1} to t_k (none for the first row unless --t0 < t_0)
//   update with z_k (skipped when any z_k component is missing)
//   nis_k = nu^T S^-1 nu,  loglik_k = log N(nu; 0, S)
//   with truth: e_k = x_k - x^_k (angles wrapped), nees_k = e^T P^-1 e
#ifndef ESTLAB_RUN_FILTER_RUN_IMPL_H_
#define ESTLAB_RUN_FILTER_RUN_IMPL_H_

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "adaptive/noise_adapter.h"
#include "src/filters/ekf.h"
#include "src/filters/kalman.h"
#include "src/filters/particle.h"
#include "src/filters/sigma_point.h"
#include "src/registry/model_traits.h"
#include "src/run/filter_spec.h"

namespace estlab {

template <class Model>
Mat<Model::kStateDim, Model::kStateDim> WhiteAccelQ(double qc, double dt) {
  constexpr int N = Model::kStateDim;
  Mat<N, N> Q = Mat<N, N>::Zero();
  for (const auto& [pos, rate] : Model::kPositionRatePairs) {
    Q(pos, pos) = qc * dt * dt * dt / 3.0;
    Q(pos, rate) = Q(rate, pos) = qc * dt * dt / 2.0;
    Q(rate, rate) = qc * dt;
  }
  return Q;
}

template <int R, int C>
Mat<R, C> MatFromVector(const std::vector<double>& v) {
  Mat<R, C> A;
  for (int i = 0; i < R; ++i)
    for (int j = 0; j < C; ++j) A(i, j) = v[i * C + j];
  return A;
}

template <class Model, class Meas>
std::unique_ptr<Filter<Model, Meas>> MakeFilter(const FilterSpec& spec,
                                                const typename Model::Params& params,
                                                Transition<Model>* transition) {
  std::string error;
  switch (spec.kind) {
    case FilterKind::kKf: {
      KfOptions o;
      o.operating_point = spec.linearize_at;
      o.operating_input = spec.input;
      if (!o.IsValid(&error)) throw InputError(error);
      return std::make_unique<LinearizedKf<Model, Meas>>(params, o);
    }
    case FilterKind::kEkf: {
      EkfOptions o;
      o.iterations = spec.iterations;
      if (!o.IsValid(&error)) throw InputError(error);
      return std::make_unique<Ekf<Model, Meas>>(transition, params, o);
    }
    case FilterKind::kPf: {
      ParticleOptions o;
      o.num_particles = spec.particles;
      o.resample = ParseResampleScheme(spec.resample);
      o.ess_threshold = spec.ess_threshold;
      o.seed = spec.seed;
      if (!o.IsValid(&error)) throw InputError(error);
      return std::make_unique<ParticleFilter<Model, Meas>>(transition, params, o);
    }
    default: {
      SigmaPointOptions o;
      o.rule = spec.kind == FilterKind::kUkf   ? SigmaRule::kUnscented
               : spec.kind == FilterKind::kCkf ? SigmaRule::kCubature
                                               : SigmaRule::kGaussHermite;
      o.alpha = spec.alpha;
      o.beta = spec.beta;
      o.kappa = spec.kappa;
      o.gh_order = spec.gh_order;
      o.update = spec.sigma_redraw ? SigmaPointOptions::Update::kRedraw
                                   : SigmaPointOptions::Update::kPropagate;
      o.jitter = spec.jitter;
      if (!o.IsValid(&error)) throw InputError(error);
      return std::make_unique<SigmaPointFilter<Model, Meas>>(transition, params, o);
    }
  }
}

template <class Model, class Meas>
FilterRunOutput RunFilterWith(const FilterSpec& spec, const FilterData& data) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  using StateCov = Mat<N, N>;
  const auto start = std::chrono::steady_clock::now();
  const typename Model::Params params = ParamsFromVector<Model>(spec.params);
  auto transition = MakeTransition<Model>(params, spec.transition);
  transition->SetInput(spec.input);
  auto filter = MakeFilter<Model, Meas>(spec, params, transition.get());
  if (spec.kind == FilterKind::kKf) {
    static_cast<LinearizedKf<Model, Meas>*>(filter.get())->SetInput(spec.input);
  }

  std::optional<NoiseAdapter<N, M>> adapter;
  if (!spec.adapt.rule.empty()) adapter.emplace(spec.adapt);
  StateCov Q = spec.q_white_accel ? StateCov::Zero() : MatFromVector<N, N>(spec.q);
  bool q_adapted = false;
  Mat<M, M> R = MatFromVector<M, M>(spec.r);

  FilterRunOutput out;
  FilterSummary& s = out.summary;
  s.filter = filter->Name();
  for (const char* name : Model::kStateNames) s.states.push_back(name);
  auto& cols = out.columns;
  cols.push_back("t");
  for (const char* name : Model::kStateNames) cols.push_back(std::string(name) + "_est");
  for (const char* name : Model::kStateNames) cols.push_back(std::string(name) + "_var");
  if (spec.full_cov) {
    for (int i = 0; i < N; ++i)
      for (int j = i + 1; j < N; ++j)
        cols.push_back(std::string("cov_") + Model::kStateNames[i] + "_" + Model::kStateNames[j]);
  }
  for (const char* o : Meas::kOutputs) cols.push_back(std::string("nu_") + o);
  cols.push_back("nis");
  cols.push_back("loglik");
  if (data.has_truth) {
    for (const char* name : Model::kStateNames) cols.push_back(std::string(name) + "_err");
    cols.push_back("nees");
  }

  const double nan = std::numeric_limits<double>::quiet_NaN();
  filter->Initialize(ToVec<N>(spec.x0), MatFromVector<N, N>(spec.p0));
  const size_t rows = data.t.size();
  double t_prev = spec.has_t0 ? spec.t0 : (rows ? data.t[0] : 0.0);
  std::vector<double> sq_err(N, 0.0), abs_err(N, 0.0);
  double nis_sum = 0.0, nees_sum = 0.0;
  long nees_count = 0;

  auto fail = [&](size_t k, const std::string& what) {
    s.ok = false;
    s.status = "diverged";
    s.message = "filter " + s.filter + " stopped at step " + std::to_string(k) + " (t = " +
                FormatNumber(data.t[k]) + ", " + data.path + " line " +
                std::to_string(k < data.lines.size() ? data.lines[k] : 0) + "): " + what;
  };

  for (size_t k = 0; k < rows; ++k) {
    const double t = data.t[k];
    const double u = data.has_input ? data.u[k > 0 ? k - 1 : 0] : spec.input;
    if (t > t_prev) {
      transition->SetInput(u);
      if (spec.kind == FilterKind::kKf)
        static_cast<LinearizedKf<Model, Meas>*>(filter.get())->SetInput(u);
      if (spec.q_white_accel && !q_adapted) Q = WhiteAccelQ<Model>(spec.qc, t - t_prev);
      const FilterStatus st = filter->Predict(t_prev, t, Q);
      if (st != FilterStatus::kOk) {
        fail(k, std::string("prediction failed: ") + FilterStatusName(st) +
                    (filter->last_error().empty() ? "" : " - " + filter->last_error()));
        break;
      }
    }
    t_prev = t;
    const StateCov p_pred = filter->cov();

    Vec<double, M> z;
    bool have_z = true;
    for (int j = 0; j < M; ++j) {
      z(j) = data.z[k * M + j];
      if (!std::isfinite(z(j))) have_z = false;
    }
    StepResult<M> r;
    if (have_z) {
      r = filter->Update(z, R);
      if (r.status != FilterStatus::kOk) {
        fail(k, std::string("update failed: ") + FilterStatusName(r.status) +
                    (r.message.empty() ? "" : " - " + r.message));
        break;
      }
      ++s.updates;
      s.loglik += r.log_likelihood;
      nis_sum += r.nis;
      if (adapter) {
        adapter->Observe(r, p_pred, filter->cov(), &Q, &R);
        if (spec.adapt.adapt_q) q_adapted = true;
      }
    }
    const auto& x = filter->mean();
    const StateCov& P = filter->cov();
    if (!x.allFinite() || !P.allFinite()) {
      fail(k, "the estimate or its covariance is not finite");
      break;
    }
    if (P.trace() > spec.max_cov_trace) {
      fail(k, "trace(P) = " + FormatNumber(P.trace()) + " exceeds " +
                  FormatNumber(spec.max_cov_trace));
      break;
    }

    std::vector<double> row;
    row.reserve(cols.size());
    row.push_back(t);
    for (int i = 0; i < N; ++i) row.push_back(x(i));
    for (int i = 0; i < N; ++i) row.push_back(P(i, i));
    if (spec.full_cov) {
      for (int i = 0; i < N; ++i)
        for (int j = i + 1; j < N; ++j) row.push_back(P(i, j));
    }
    for (int j = 0; j < M; ++j) row.push_back(have_z ? r.innovation(j) : nan);
    row.push_back(have_z ? r.nis : nan);
    row.push_back(have_z ? r.log_likelihood : nan);
    if (data.has_truth) {
      Vec<double, N> e;
      bool truth_ok = true;
      for (int i = 0; i < N; ++i) {
        e(i) = x(i) - data.truth[k * N + i];
        if (Model::kAngleStates[i]) e(i) = WrapAngle(e(i));
        if (!std::isfinite(e(i))) truth_ok = false;
      }
      double nees = nan;
      if (truth_ok) {
        const Eigen::LLT<StateCov> llt(P);
        if (llt.info() == Eigen::Success) {
          nees = e.dot(llt.solve(e));
          nees_sum += nees;
          ++nees_count;
        }
        for (int i = 0; i < N; ++i) {
          sq_err[i] += e(i) * e(i);
          abs_err[i] += std::abs(e(i));
        }
      }
      for (int i = 0; i < N; ++i) row.push_back(e(i));
      row.push_back(nees);
    }
    out.rows.push_back(std::move(row));
    ++s.steps;
  }

  if (data.has_truth && s.steps > 0) {
    for (int i = 0; i < N; ++i) {
      s.rmse.push_back(std::sqrt(sq_err[i] / s.steps));
      s.mae.push_back(abs_err[i] / s.steps);
    }
  }
  s.mean_nis = s.updates ? nis_sum / s.updates : nan;
  ChiSquareBounds95(s.updates, M, s.nis_bounds95);
  s.mean_nees = nees_count ? nees_sum / nees_count : nan;
  ChiSquareBounds95(nees_count, N, s.nees_bounds95);
  if (adapter) s.adapt_clips = adapter->clip_count();
  s.final_q.assign(Q.data(), Q.data() + N * N);  // symmetric: storage order irrelevant
  s.final_r.assign(R.data(), R.data() + M * M);
  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  s.us_per_step = s.steps ? 1e6 * s.wall_s / s.steps : 0.0;
  return out;
}

// Dispatches on the measurement name.
template <class Model>
FilterRunOutput RunFilter(const FilterSpec& spec, const FilterData& data) {
  FilterRunOutput out;
  const bool found = VisitMeasurement<Model>(spec.measurement, [&](auto m) {
    out = RunFilterWith<Model, decltype(m)>(spec, data);
  });
  if (!found) throw InputError("unknown measurement '" + spec.measurement + "'");
  return out;
}

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_RUN_IMPL_H_
