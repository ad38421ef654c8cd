// Runs one filter over a dataset: predict to each measurement time, update
// when the row has a measurement, record the per-step diagnostics and the
// summary metrics. Include only from the generated per-model units (models/model_list.cmake).
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

#include "models/model_traits.h"
#include "src/core/white_accel.h"
#include "src/filters/filters.h"
#include "src/filters/noise_adapter.h"
#include "src/run/filter_spec.h"
#include "src/run/first_sample.h"
#include "src/run/step_loop.h"

namespace estlab {

template <class Model>
Mat<Model::kStateDim, Model::kStateDim> WhiteAccelQ(double qc, double dt) {
  Mat<Model::kStateDim, Model::kStateDim> Q;
  FillWhiteAccel(Model::kPositionRatePairs, qc, dt, &Q);
  return Q;
}

template <int R, int C>
Mat<R, C> MatFromVector(const std::vector<double>& v) {
  Mat<R, C> A;
  for (int i = 0; i < R; ++i)
    for (int j = 0; j < C; ++j) A(i, j) = v[i * C + j];
  return A;
}

// The filter of spec.filter: each options struct's MakeFilterFor overload
// (src/filters/filters.h); a kind without one does not compile. Throws
// InputError for invalid options.
template <class Model, class Meas>
std::unique_ptr<Filter<Model, Meas>> MakeFilter(const FilterSpec& spec,
                                                const typename Model::Params& params,
                                                Transition<Model>* transition) {
  return std::visit(
      [&](const auto& options) { return MakeFilterFor<Model, Meas>(options, transition, params); },
      spec.filter);
}

template <class Model, class Meas>
FilterRunOutput RunFilterWith(const FilterSpec& spec, const FilterData& data) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  using StateCov = Mat<N, N>;
  const auto start = std::chrono::steady_clock::now();
  const typename Model::Params params = ParamsFromVector<Model>(spec.params);
  auto transition = MakeTransition<Model>(params, spec.transition);
  auto filter = MakeFilter<Model, Meas>(spec, params, transition.get());
  filter->SetInput(spec.input);  // the transition's, or the KF's own

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
  filter->Initialize(PriorMean<Model, Meas>(spec, data), MatFromVector<N, N>(spec.p0));
  std::vector<double> sq_err(N, 0.0), abs_err(N, 0.0);
  double nis_sum = 0.0, nees_sum = 0.0;
  long nees_count = 0;

  auto fail = [&](size_t k, const std::string& what) {
    s.ok = false;
    s.status = "diverged";
    s.message = "filter " + s.filter + " stopped at step " + std::to_string(k) +
                " (t = " + FormatNumber(data.t[k]) + ", " + data.path + " line " +
                std::to_string(k < data.lines.size() ? data.lines[k] : 0) + "): " + what;
    return false;
  };
  auto predict = [&](size_t k, double t0, double t1, double u) {
    filter->SetInput(u);
    if (spec.q_white_accel && !q_adapted) Q = WhiteAccelQ<Model>(spec.qc, t1 - t0);
    const FilterStatus st = filter->Predict(t0, t1, Q);
    if (st == FilterStatus::kOk) return true;
    return fail(k, std::string("prediction failed: ") + FilterStatusName(st) +
                       (filter->last_error().empty() ? "" : " - " + filter->last_error()));
  };
  auto row = [&](size_t k, const Vec<double, M>* z) {
    const StateCov p_pred = filter->cov();
    StepResult<M> r;
    if (z != nullptr) {
      r = filter->Update(*z, R);
      if (r.status != FilterStatus::kOk)
        return fail(k, std::string("update failed: ") + FilterStatusName(r.status) +
                           (r.message.empty() ? "" : " - " + r.message));
      // A finite but absurd measurement (1e308) can make the statistics
      // overflow while the filter itself reports success: that is a
      // divergence too, not a result.
      if (!r.innovation.allFinite() || !std::isfinite(r.nis) || !std::isfinite(r.log_likelihood))
        return fail(k, "the innovation statistics are not finite (NIS " + FormatNumber(r.nis) +
                           ", log-likelihood " + FormatNumber(r.log_likelihood) +
                           "): a measurement far outside the filter's range");
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
    std::string why;
    if (!WithinDivergenceGuard<N>(x, P, spec.max_cov_trace, &why)) return fail(k, why);
    const bool have_z = z != nullptr;
    std::vector<double> out_row;
    out_row.reserve(cols.size());
    out_row.push_back(data.t[k]);
    for (int i = 0; i < N; ++i) out_row.push_back(x(i));
    for (int i = 0; i < N; ++i) out_row.push_back(P(i, i));
    if (spec.full_cov) {
      for (int i = 0; i < N; ++i)
        for (int j = i + 1; j < N; ++j) out_row.push_back(P(i, j));
    }
    for (int j = 0; j < M; ++j) out_row.push_back(have_z ? r.innovation(j) : nan);
    out_row.push_back(have_z ? r.nis : nan);
    out_row.push_back(have_z ? r.log_likelihood : nan);
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
      for (int i = 0; i < N; ++i) out_row.push_back(e(i));
      out_row.push_back(nees);
    }
    out.rows.push_back(std::move(out_row));
    ++s.steps;
    return true;
  };
  ForEachStep<M>(spec, data, predict, row);

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
  const bool found = VisitMeasurement<Model>(
      spec.measurement, [&](auto m) { out = RunFilterWith<Model, decltype(m)>(spec, data); });
  if (!found) throw InputError("unknown measurement '" + spec.measurement + "'");
  return out;
}

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_RUN_IMPL_H_
