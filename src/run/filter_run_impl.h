// Runs one filter over a dataset: predict to each measurement time, update
// when the row has a measurement, record the per-step diagnostics and the
// summary metrics; with spec.smooth, then its smoother's backward pass. Include only from the
// generated per-model units (models/model_list.cmake).
//
// Per step k (time t_k):
//   Q_k = Q, or qc * Q_wa(t_k - t_{k-1})       (white-noise acceleration)
//   predict from t_{k-1} to t_k (none for the first row unless --t0 < t_0)
//   update with the observed components of z_k (none observed: no update)
//   nis_k = nu^T S^-1 nu,  loglik_k = log N(nu; 0, S)
//   particle filters: ESS_k, the degeneracy check (degeneracy.h)
//   with truth: e_k = x_k - x^_k (angles wrapped), nees_k = e^T P^-1 e
#ifndef ESTLAB_RUN_FILTER_RUN_IMPL_H_
#define ESTLAB_RUN_FILTER_RUN_IMPL_H_

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/model_traits.h"
#include "src/core/white_accel.h"
#include "src/filters/filters.h"
#include "src/filters/noise_adapter.h"
#include "src/run/degeneracy.h"
#include "src/run/filter_spec.h"
#include "src/run/first_sample.h"
#include "src/run/group_nis.h"
#include "src/run/run_parts.h"
#include "src/run/smoother_recorder.h"
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

// The refusal of a run that asks for a part its library was compiled
// without (run_parts.h): the loader asks for the library of the same
// request, so this is a bug, never the user's.
[[noreturn]] inline void MissingRunPart(const std::string& part) {
  throw std::logic_error("this model library was compiled without " + part +
                         " (src/run/run_parts.h); delete the model cache to rebuild it");
}

// The filter of spec.filter: each options struct's MakeFilterFor overload
// (src/filters/filters.h); a kind without one does not compile. Only the
// classes in Parts are compiled. Throws InputError for invalid options.
template <class Model, class Meas, class Parts = AllRunParts>
std::unique_ptr<Filter<Model, Meas>> MakeFilter(const FilterSpec& spec,
                                                const typename Model::Params& params,
                                                Transition<Model>* transition) {
  return std::visit(
      [&](const auto& options) -> std::unique_ptr<Filter<Model, Meas>> {
        if constexpr (HasFilter<Parts, std::decay_t<decltype(options)>>())
          return MakeFilterFor<Model, Meas>(options, transition, params);
        else
          MissingRunPart(std::string("the filter ") + FilterKindName(KindOf(spec.filter)));
      },
      spec.filter);
}

// Stand-ins for the noise adapter and the smoother in a run library compiled
// without them (run_parts.h): never constructed (the run refuses a spec that
// asks for them), they only let the run loop name their calls.
template <int N, int M>
struct AbsentAdapter {
  void Observe(const StepResult<M>&, const Mat<N, N>&, const Mat<N, N>&, Mat<N, N>*, Mat<M, M>*) {}
  long clip_count() const { return 0; }
};
template <int N>
struct AbsentSmoother {
  void OnPrior() {}
  bool BeforePredict(double, double, const Mat<N, N>&, std::string*) { return true; }
  bool AfterPredict(std::string*) { return true; }
  size_t OnRow() { return 0; }
};

// One row of the forward pass: its belief (filtered, or smoothed after the
// backward pass) and its innovation statistics.
template <int N, int M>
struct RowRecord {
  double t = 0.0;
  Vec<double, N> x;
  Mat<N, N> P;
  bool have_z = false;
  Vec<double, M> nu;
  Mat<M, M> S;  // the innovation covariance
  double nis = 0.0, loglik = 0.0;
  size_t step = 0;  // the smoother's step (smoother_recorder.h)
};

// Row k of a smoothed run as typed moments, for code that runs the smoother
// itself (EM's E-step, adaptive/em.h): x^s_k, P^s_k and the lag-one
// cross-covariance C^s_k = Cov(x_k, x_{k+1} | all data) (NaN on the last
// row and for the particle smoother). The same numbers as the row columns
// <s>_est, <s>_var, cov_<a>_<b> and lag1_<a>_<b> of `estlab smooth
// --full-cov`.
template <int N>
struct SmoothedMoments {
  Vec<double, N> x;
  Mat<N, N> P;
  Mat<N, N> lag_one;
};

// Which columns a run writes (EstimateColumns).
struct RowLayout {
  bool full_cov = false;
  // nu_<output>, S_<output> [, S_<a>_<b>], nis, loglik: the filter's, not a
  // smoother's.
  bool innovations = true;
  bool lag_one = false;  // smooth --full-cov: lag1_<a>_<b> = Cov(a_k, b_{k+1} | all data)
};

// t, <state>_est, <state>_var [, cov_<a>_<b>] [, lag1_<a>_<b>]
// [, nu_<output>, S_<output> [, S_<a>_<b>], nis, loglik] [, <state>_err, nees].
template <class Model, class Meas>
std::vector<std::string> EstimateColumns(const RowLayout& layout, bool has_truth) {
  constexpr int N = Model::kStateDim;
  const auto& names = Model::kStateNames;
  std::vector<std::string> cols{"t"};
  for (const char* name : names) cols.push_back(std::string(name) + "_est");
  for (const char* name : names) cols.push_back(std::string(name) + "_var");
  if (layout.full_cov) {
    for (int i = 0; i < N; ++i)
      for (int j = i + 1; j < N; ++j)
        cols.push_back(std::string("cov_") + names[i] + "_" + names[j]);
  }
  if (layout.lag_one) {
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) cols.push_back(std::string("lag1_") + names[i] + "_" + names[j]);
  }
  if (layout.innovations) {
    const auto& outputs = Meas::kOutputs;
    for (const char* o : outputs) cols.push_back(std::string("nu_") + o);
    for (const char* o : outputs) cols.push_back(std::string("S_") + o);
    if (layout.full_cov) {
      for (size_t i = 0; i < outputs.size(); ++i)
        for (size_t j = i + 1; j < outputs.size(); ++j)
          cols.push_back(std::string("S_") + outputs[i] + "_" + outputs[j]);
    }
    cols.push_back("nis");
    cols.push_back("loglik");
  }
  if (has_truth) {
    for (const char* name : names) cols.push_back(std::string(name) + "_err");
    cols.push_back("nees");
  }
  return cols;
}

// The rows of `records` (when rows != nullptr) and, with truth, the RMSE,
// MAE and mean NEES of their beliefs in *s:
//   e_k = x_k - x^_k (angles wrapped), nees_k = e^T P^-1 e.
// Each state's RMSE and MAE are over the rows where its truth is finite
// (their count in s->truth_rows; NaN when none); NEES over the rows where
// every state's is.
// lag_one(k) gives the lag-one covariance of record k (nullptr: NaN).
template <class Model, class Meas, class LagOneFn>
void EmitRows(const std::vector<RowRecord<Model::kStateDim, Meas::kDim>>& records,
              const FilterData& data, const RowLayout& layout, LagOneFn&& lag_one,
              std::vector<std::vector<double>>* rows, FilterSummary* s) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  using StateCov = Mat<N, N>;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> sq_err(N, 0.0), abs_err(N, 0.0);
  std::vector<long> truth_rows(N, 0);  // rows with a finite error, per state
  double nees_sum = 0.0;
  long nees_count = 0;
  for (size_t k = 0; k < records.size(); ++k) {
    const RowRecord<N, M>& r = records[k];
    std::vector<double> row{r.t};
    for (int i = 0; i < N; ++i) row.push_back(r.x(i));
    for (int i = 0; i < N; ++i) row.push_back(r.P(i, i));
    if (layout.full_cov) {
      for (int i = 0; i < N; ++i)
        for (int j = i + 1; j < N; ++j) row.push_back(r.P(i, j));
    }
    if (layout.lag_one) {
      const StateCov* L = lag_one(r.step);
      for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) row.push_back(L ? (*L)(i, j) : nan);
    }
    if (layout.innovations) {
      for (int j = 0; j < M; ++j) row.push_back(r.have_z ? r.nu(j) : nan);
      for (int j = 0; j < M; ++j) row.push_back(r.have_z ? r.S(j, j) : nan);
      if (layout.full_cov) {
        for (int i = 0; i < M; ++i)
          for (int j = i + 1; j < M; ++j) row.push_back(r.have_z ? r.S(i, j) : nan);
      }
      row.push_back(r.have_z ? r.nis : nan);
      row.push_back(r.have_z ? r.loglik : nan);
    }
    if (data.has_truth) {
      Vec<double, N> e;
      bool truth_ok = true;
      for (int i = 0; i < N; ++i) {
        e(i) = r.x(i) - data.truth[k * N + i];
        if (Model::kAngleStates[i]) e(i) = WrapAngle(e(i));
        if (!std::isfinite(e(i))) truth_ok = false;
      }
      double nees = nan;
      if (truth_ok) {
        const Eigen::LLT<StateCov> llt(r.P);
        if (llt.info() == Eigen::Success) {
          nees = e.dot(llt.solve(e));
          nees_sum += nees;
          ++nees_count;
        }
      }
      for (int i = 0; i < N; ++i) {  // each state over its own finite rows
        if (!std::isfinite(e(i))) continue;
        sq_err[i] += e(i) * e(i);
        abs_err[i] += std::abs(e(i));
        ++truth_rows[i];
      }
      for (int i = 0; i < N; ++i) row.push_back(e(i));
      row.push_back(nees);
    }
    if (rows != nullptr) rows->push_back(std::move(row));
  }
  s->rmse.clear();
  s->mae.clear();
  s->truth_rows.clear();
  if (data.has_truth && !records.empty()) {
    for (int i = 0; i < N; ++i) {  // NaN for a state with no finite truth
      const double n = truth_rows[i] > 0 ? double(truth_rows[i]) : nan;
      s->rmse.push_back(std::sqrt(sq_err[i] / n));
      s->mae.push_back(abs_err[i] / n);
      s->truth_rows.push_back(truth_rows[i]);
    }
  }
  s->mean_nees = nees_count ? nees_sum / double(nees_count) : nan;
  ChiSquareBounds95(nees_count, N, s->nees_bounds95);
}

// The particle filter's ESS figures in *s and, for a degenerate run (and
// only when nothing failed before), the status "degenerate" with the step,
// the time and the usual remedies.
inline void ReportDegeneracy(const DegeneracyMonitor& d, const FilterData& data, FilterSummary* s) {
  s->particles = d.particles();
  s->min_ess = d.min_ess();
  s->mean_ess = d.mean_ess();
  s->collapsed_updates = d.collapsed_updates();
  s->degenerate = d.degenerate();
  if (!d.degenerate() || !s->ok) return;
  const size_t k = d.onset_step();
  s->status = "degenerate";
  s->message = "particle filter degenerate: the effective sample size stayed below " +
               FormatNumber(DegeneracyMonitor::Threshold(d.particles())) + " of " +
               std::to_string(d.particles()) + " particles for " +
               std::to_string(DegeneracyMonitor::kDegenerateRun) + " updates in a row up to step " +
               std::to_string(k) + " (t = " + FormatNumber(data.t[k]) + "); " +
               std::to_string(d.collapsed_updates()) + " updates collapsed, smallest ESS " +
               FormatNumber(d.min_ess()) +
               ". Its estimates follow a single particle. Try a larger R (--r-diag; the "
               "measurement noise is often larger than the sensor's resolution), more particles "
               "(--particles), or a narrower prior (--p0-diag)";
}

inline bool IsParticle(const FilterSpec& spec) { return spec.kind() == FilterKind::kPf; }

// `estlab smooth`: the forward summary of `records` goes to out->summary.forward,
// the backward pass replaces each record's belief by the smoothed one, and
// the rows and error statistics are the smoother's. A backward pass that
// fails leaves no rows (a filtered row under a smoother's name would be
// silently wrong) and the status "smoother failed" naming the step.
// With moments, each record's smoothed moments too (lag-one included).
template <class Model, class Meas>
void SmoothRecords(const FilterData& data, const RowLayout& layout,
                   SmootherRecorder<Model, Meas>* smoother,
                   std::vector<RowRecord<Model::kStateDim, Meas::kDim>>* records,
                   FilterRunOutput* out, std::vector<SmoothedMoments<Model::kStateDim>>* moments) {
  using StateCov = Mat<Model::kStateDim, Model::kStateDim>;
  FilterSummary& s = out->summary;
  auto forward = std::make_shared<FilterSummary>(s);
  EmitRows<Model, Meas>(
      *records, data, layout, [](size_t) -> const StateCov* { return nullptr; }, nullptr,
      forward.get());
  s.filter = SmootherName(forward->filter);
  s.forward = forward;
  if (records->empty()) return;
  std::string why;
  if (!smoother->Smooth(layout.lag_one || moments != nullptr, &why)) {
    s.ok = false;
    s.status = "smoother failed";
    s.message = "smoother " + s.filter + ": " + why + "; no smoothed rows written";
    s.rmse.clear();
    s.mae.clear();
    s.truth_rows.clear();
    return;
  }
  for (auto& r : *records) {
    r.x = smoother->mean(r.step);
    r.P = smoother->cov(r.step);
  }
  if (moments != nullptr) {
    moments->clear();
    moments->reserve(records->size());
    for (const auto& r : *records) {
      const StateCov* L = smoother->lag_one(r.step);
      moments->push_back(
          {r.x, r.P, L ? *L : StateCov::Constant(std::numeric_limits<double>::quiet_NaN())});
    }
  }
  EmitRows<Model, Meas>(
      *records, data, layout, [&](size_t k) { return smoother->lag_one(k); }, &out->rows, &s);
}

// With spec.smooth and moments, also the smoothed rows as typed moments
// (SmoothedMoments; left empty when the run or the smoother fails).
// Parts (run_parts.h) says which filter classes, and whether the noise
// adapter and the smoother, are compiled.
template <class Model, class Meas, class Parts = AllRunParts>
FilterRunOutput RunFilterWith(const FilterSpec& spec, const FilterData& data,
                              std::vector<SmoothedMoments<Model::kStateDim>>* moments = nullptr) {
  constexpr int N = Model::kStateDim;
  constexpr int M = Meas::kDim;
  using StateCov = Mat<N, N>;
  using Adapter = std::conditional_t<Parts::kAdapt, NoiseAdapter<N, M>, AbsentAdapter<N, M>>;
  using Smoother =
      std::conditional_t<Parts::kSmooth, SmootherRecorder<Model, Meas>, AbsentSmoother<N>>;
  const auto start = std::chrono::steady_clock::now();
  const typename Model::Params params = ParamsFromVector<Model>(spec.params);
  auto transition = MakeTransition<Model>(params, spec.transition);
  auto filter = MakeFilter<Model, Meas, Parts>(spec, params, transition.get());
  if (const std::string why = CheckInputWidths(spec, data, kInputDim<Model>); !why.empty())
    throw InputError(why);
  filter->SetInput(InputFrom<Model>(InputAtRow(spec, data, 0)));  // the transition's, or the KF's

  std::optional<Adapter> adapter;
  if (!spec.adapt.rule.empty()) {
    if constexpr (Parts::kAdapt)
      adapter.emplace(spec.adapt);
    else
      MissingRunPart("the noise adapter");
  }
  filter->SetPostFitResidual(adapter.has_value());  // the adapter's input only
  StateCov Q = spec.q_white_accel ? StateCov::Zero() : MatFromVector<N, N>(spec.q);
  bool q_adapted = false;
  Mat<M, M> R = MatFromVector<M, M>(spec.r);
  std::optional<Smoother> smoother;
  if (spec.smooth) {
    if constexpr (Parts::kSmooth)
      smoother.emplace(spec, filter.get(), transition.get());
    else
      MissingRunPart("the smoother");
  }

  FilterRunOutput out;
  FilterSummary& s = out.summary;
  s.filter = filter->Name();
  for (const char* name : Model::kStateNames) s.states.push_back(name);
  const RowLayout layout{.full_cov = spec.full_cov,
                         .innovations = !spec.smooth,
                         .lag_one = spec.smooth && spec.full_cov && !IsParticle(spec)};
  out.columns = EstimateColumns<Model, Meas>(layout, data.has_truth);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec<double, N> x0 = PriorMean<Model, Meas>(spec, data);
  s.x0.assign(x0.data(), x0.data() + N);
  if (!data.t.empty()) filter->SetTime(data.t[0]);
  filter->Initialize(x0, MatFromVector<N, N>(spec.p0));
  if (smoother) smoother->OnPrior();
  std::vector<RowRecord<N, M>> records;
  records.reserve(data.t.size());
  double nis_sum = 0.0;
  long nis_dof = 0;  // the observed components over all updates
  GroupNisTally<Meas> group_nis;
  DegeneracyMonitor degeneracy;

  auto fail = [&](size_t k, const std::string& what) {
    s.ok = false;
    s.status = "diverged";
    s.message = "filter " + s.filter + " stopped at step " + std::to_string(k) +
                " (t = " + FormatNumber(data.t[k]) + ", " + data.path + " line " +
                std::to_string(k < data.lines.size() ? data.lines[k] : 0) + "): " + what;
    return false;
  };
  auto predict = [&](size_t k, double t0, double t1, const double* u0, const double* u1) {
    filter->SetInputPath(InputFrom<Model>(u0), InputFrom<Model>(u1));
    if (spec.q_white_accel && !q_adapted) Q = WhiteAccelQ<Model>(spec.qc, t1 - t0);
    std::string why;
    if (smoother && !smoother->BeforePredict(t0, t1, Q, &why)) return fail(k, why);
    const FilterStatus st = filter->Predict(t0, t1, Q);
    if (st != FilterStatus::kOk)
      return fail(k, std::string("prediction failed: ") + FilterStatusName(st) +
                         (filter->last_error().empty() ? "" : " - " + filter->last_error()));
    if (smoother && !smoother->AfterPredict(&why)) return fail(k, why);
    return true;
  };
  auto row = [&](size_t k, const Vec<double, M>* z, const double* u) {
    StateCov p_pred = StateCov::Zero();
    if (adapter) p_pred = filter->cov();    // the adapter's
    filter->SetInput(InputFrom<Model>(u));  // u_k: seen by h(t, x, u), held over the next step
    filter->SetTime(data.t[k]);
    RowRecord<N, M> rec;
    rec.t = data.t[k];
    rec.have_z = z != nullptr;
    rec.nu.setConstant(nan);
    rec.S.setConstant(nan);
    if (z != nullptr) {
      const StepResult<M> r = filter->Update(*z, R);
      if (r.status != FilterStatus::kOk)
        return fail(k, std::string("update failed: ") + FilterStatusName(r.status) +
                           (r.message.empty() ? "" : " - " + r.message));
      // A finite but absurd measurement (1e308) can make the statistics
      // overflow while the filter itself reports success: that is a
      // divergence too, not a result.
      if (!InnovationFinite<M>(*z, r.innovation) || !std::isfinite(r.nis) ||
          !std::isfinite(r.log_likelihood))
        return fail(k, "the innovation statistics are not finite (NIS " + FormatNumber(r.nis) +
                           ", log-likelihood " + FormatNumber(r.log_likelihood) +
                           "): a measurement far outside the filter's range");
      ++s.updates;
      s.loglik += r.log_likelihood;
      nis_sum += r.nis;
      nis_dof += r.observed;
      group_nis.Observe(r.innovation, r.innovation_cov);
      rec.nu = r.innovation;
      rec.S = r.innovation_cov;
      rec.nis = r.nis;
      double ess = 0.0;
      int particles = 0;
      if (filter->EffectiveSampleSize(&ess, &particles)) degeneracy.Observe(ess, particles, k);
      rec.loglik = r.log_likelihood;
      if (adapter && r.observed == M) {  // adapts on complete rows only (noise_adapter.h)
        adapter->Observe(r, p_pred, filter->cov(), &Q, &R);
        if (spec.adapt.adapt_q) q_adapted = true;
      }
    }
    rec.x = filter->mean();
    rec.P = filter->cov();
    std::string why;
    if (!WithinDivergenceGuard<N>(rec.x, rec.P, spec.max_cov_trace, &why)) return fail(k, why);
    if (smoother) rec.step = smoother->OnRow();
    records.push_back(rec);
    ++s.steps;
    return true;
  };
  const auto loop_start = std::chrono::steady_clock::now();
  if (!ForEachStep<M>(spec, data, predict, row) && s.ok) {  // a Ctrl-C noted (interrupt.h)
    s.ok = false;
    s.status = "interrupted";
    s.message = "filter " + s.filter + " interrupted before step " + std::to_string(s.steps);
  }
  s.loop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  s.us_per_step = s.steps ? 1e6 * s.loop_s / double(s.steps) : 0.0;

  s.mean_nis = s.updates ? nis_sum / s.updates : nan;
  ChiSquareMeanBounds95(s.updates, nis_dof, s.nis_bounds95);
  group_nis.Report(&s);
  if (adapter) s.adapt_clips = adapter->clip_count();
  if (degeneracy.observed()) ReportDegeneracy(degeneracy, data, &s);
  s.final_q.assign(Q.data(), Q.data() + N * N);  // symmetric: storage order irrelevant
  s.final_r.assign(R.data(), R.data() + M * M);
  auto timing = [&](FilterSummary* summary) {
    summary->wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  auto no_lag_one = [](size_t) { return static_cast<const StateCov*>(nullptr); };
  if (!smoother) {
    EmitRows<Model, Meas>(records, data, layout, no_lag_one, &out.rows, &s);
  } else {
    timing(&s);  // the forward pass's, copied into s.forward
    if constexpr (Parts::kSmooth)
      SmoothRecords<Model, Meas>(data, layout, &*smoother, &records, &out, moments);
  }
  timing(&s);
  return out;
}

// Dispatches on the measurement name (those in Parts).
template <class Model, class Parts = AllRunParts>
FilterRunOutput RunFilter(const FilterSpec& spec, const FilterData& data) {
  FilterRunOutput out;
  const bool found = VisitMeasurement<Model>(spec.measurement, [&](auto m) {
    using Meas = decltype(m);
    if constexpr (HasMeasurement<Parts, Model, Meas>())
      out = RunFilterWith<Model, Meas, Parts>(spec, data);
    else
      MissingRunPart("the measurement " + spec.measurement);
  });
  if (!found) throw InputError("unknown measurement '" + spec.measurement + "'");
  return out;
}

}  // namespace estlab

#endif  // ESTLAB_RUN_FILTER_RUN_IMPL_H_
