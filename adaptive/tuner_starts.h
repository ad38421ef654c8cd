// The tuner's multi-start (part of the tuner, adaptive/tuner_impl.h): the
// bounds of every parameter, where the Latin hypercube spreads it, the
// common-scale pre-search on Q and R, the starts on TunerOptions::jobs
// threads and the choice of the best.
#ifndef ESTLAB_ADAPTIVE_TUNER_STARTS_H_
#define ESTLAB_ADAPTIVE_TUNER_STARTS_H_

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/tuner.h"
#include "adaptive/tuner_drivers.h"
#include "adaptive/tuner_objective.h"
#include "src/core/random.h"
#include "src/core/task_pool.h"

namespace estlab {
namespace tuner_internal {

// Resolves the bounds (see TunerOptions); throws InputError.
inline void ResolveBounds(const TunerOptions& o, const std::vector<double>& theta0,
                          const std::vector<bool>& is_log, std::vector<double>* lower,
                          std::vector<double>* upper) {
  const size_t k = theta0.size();
  auto pick = [&](const std::vector<double>& given, const char* which) {
    if (!given.empty() && given.size() != 1 && given.size() != k) {
      throw InputError(std::string(which) + " bounds: expected 1 or " + std::to_string(k) +
                       " values (one per tuned parameter), got " + std::to_string(given.size()));
    }
  };
  pick(o.log_lower, "lower");
  pick(o.log_upper, "upper");
  lower->assign(k, -kInf);
  upper->assign(k, kInf);
  for (size_t i = 0; i < k; ++i) {
    if (o.log_lower.size() == k) {
      (*lower)[i] = o.log_lower[i];
    } else if (is_log[i]) {
      (*lower)[i] = o.log_lower.size() == 1 ? o.log_lower[0] : theta0[i] - o.bound_width;
    }
    if (o.log_upper.size() == k) {
      (*upper)[i] = o.log_upper[i];
    } else if (is_log[i]) {
      (*upper)[i] = o.log_upper.size() == 1 ? o.log_upper[0] : theta0[i] + o.bound_width;
    }
    if ((*lower)[i] > (*upper)[i]) {
      throw InputError("bounds of parameter " + std::to_string(i + 1) + ": lower " +
                       FormatNumber((*lower)[i]) + " is above upper " + FormatNumber((*upper)[i]));
    }
  }
}

// The interval the multi-start spreads theta_d over (TunerOptions::starts):
// Q's and R's log parameters theta0 +- spread (off-diagonal Cholesky entries
// keep their value); a physical parameter its box [lower, upper] when it is
// a real one (both bounds finite; for a log parameter, both given by the
// user, not the +-bound_width default), else theta0 +- spread on the log
// scale or theta0 +- max(|theta0|, 1e-3) spread / 2 on the natural scale.
inline std::pair<double, double> SpreadInterval(const TunerOptions& o, double theta0, bool is_log,
                                                bool physical, bool user_box, double lower,
                                                double upper) {
  if (physical && user_box && std::isfinite(lower) && std::isfinite(upper)) return {lower, upper};
  if (is_log) return {theta0 - o.start_spread, theta0 + o.start_spread};
  if (!physical) return {theta0, theta0};
  const double half = std::max(std::abs(theta0), 1e-3) * 0.5 * o.start_spread;
  return {theta0 - half, theta0 + half};
}

// Start points: theta0, then a Latin hypercube over the intervals, clamped
// into the bounds. Every dimension draws its strata and offsets in turn from
// Rng(seed), used or not, so adding a dimension leaves the others' draws.
inline std::vector<std::vector<double>> StartPoints(
    const TunerOptions& o, const std::vector<double>& theta0,
    const std::vector<std::pair<double, double>>& interval, const std::vector<double>& lower,
    const std::vector<double>& upper) {
  const int k = int(theta0.size());
  std::vector<std::vector<double>> points(o.starts, theta0);
  const int extra = o.starts - 1;
  Rng rng(DeriveSeed({o.seed, uint64_t(k), 0x4c48u}));
  for (int d = 0; d < k && extra > 0; ++d) {
    std::vector<int> strata(extra);
    std::iota(strata.begin(), strata.end(), 0);
    for (int i = extra - 1; i > 0; --i) {  // Fisher-Yates
      const int j = int(rng.Uniform() * (i + 1));
      std::swap(strata[i], strata[std::min(j, i)]);
    }
    const auto [lo, hi] = interval[d];
    for (int s = 0; s < extra; ++s) {
      const double u = (strata[s] + rng.Uniform()) / extra;
      if (hi > lo) points[s + 1][d] = lo + (hi - lo) * u;
    }
  }
  for (auto& p : points)
    for (int d = 0; d < k; ++d) p[d] = std::clamp(p[d], lower[d], upper[d]);
  return points;
}

// theta with Q and R (its first `noise` entries) scaled by e^s: log
// parameters + s, off-diagonal Cholesky entries * e^(s/2). The physical
// parameters after them stay.
inline std::vector<double> ScaleShifted(const std::vector<double>& theta,
                                        const std::vector<bool>& is_log, int noise, double s) {
  std::vector<double> out(theta);
  for (int i = 0; i < noise; ++i) out[i] = is_log[i] ? out[i] + s : out[i] * std::exp(0.5 * s);
  return out;
}

// The common-scale pre-search (TunerOptions::scale_search): returns the s in
// [-8, 8] (within the bounds) minimising NLL(ScaleShifted(theta, s)), 0 when
// no shifted point is better than theta itself.
template <class Model, class Meas>
double ScaleSearch(const Objective<Model, Meas>& objective, const std::vector<double>& theta,
                   const std::vector<bool>& is_log, int noise, const std::vector<double>& lower,
                   const std::vector<double>& upper) {
  double lo = -8.0, hi = 8.0;
  bool any_log = false;
  for (int i = 0; i < noise; ++i) {
    if (!is_log[i]) continue;
    any_log = true;
    lo = std::max(lo, lower[i] - theta[i]);
    hi = std::min(hi, upper[i] - theta[i]);
  }
  if (!any_log || !(lo < hi)) return 0.0;
  auto nll = [&](double s) {
    const std::vector<double> t = ScaleShifted(theta, is_log, noise, s);
    double f = kInf;
    return objective.Value(t.data(), &f) && std::isfinite(f) ? f : kInf;
  };
  double best_s = 0.0, best_f = (lo <= 0.0 && 0.0 <= hi) ? nll(0.0) : kInf;
  for (double s = std::ceil(lo); s <= hi; s += 1.0) {
    const double f = nll(s);
    if (f < best_f) best_f = f, best_s = s;
  }
  if (!std::isfinite(best_f)) return 0.0;
  // Golden section on [best_s - 1, best_s + 1].
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = std::max(lo, best_s - 1.0), b = std::min(hi, best_s + 1.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = nll(c), fd = nll(d);
  for (int it = 0; it < 30 && b - a > 1e-4; ++it) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - g * (b - a), fc = nll(c);
    } else {
      a = c, c = d, fc = fd, d = a + g * (b - a), fd = nll(d);
    }
  }
  const double s = fc < fd ? c : d;
  return std::min(fc, fd) < best_f ? s : best_s;
}

// The bounds of every parameter: Q's and R's (ResolveBounds about the
// initial guess), then the physical parameters', then the initial states'
// (none: a state's value is not constrained).
template <class Model, class Meas>
void LikelihoodBounds(const InnovationLikelihood<Model, Meas>& lik, const TunerOptions& options,
                      std::vector<double>* lower, std::vector<double>* upper) {
  const int noise = lik.NumNoiseParams();
  const std::vector<double> theta0 = lik.InitialTheta();
  const std::vector<bool> is_log = lik.ParamIsLog();
  ResolveBounds(options, std::vector<double>(theta0.begin(), theta0.begin() + noise),
                std::vector<bool>(is_log.begin(), is_log.begin() + noise), lower, upper);
  lik.physical().Bounds(lower, upper);
  lower->resize(size_t(lik.NumParams()), -kInf);
  upper->resize(size_t(lik.NumParams()), kInf);
}

// Where the multi-start spreads each parameter (SpreadInterval) and whether
// its lower bound stands for its constraint (the verdict's at-bound rule):
// Q's and R's log-variances and > 0 parameters (log scale: the bound stands
// for 0), a >= 0 parameter whose lower bound is 0. An initial state spreads
// as an unbounded physical parameter.
template <class Model, class Meas>
void ParameterFacts(const InnovationLikelihood<Model, Meas>& lik, const TunerOptions& o,
                    const std::vector<double>& lower, const std::vector<double>& upper,
                    std::vector<std::pair<double, double>>* spread,
                    std::vector<bool>* lower_is_constraint) {
  const std::vector<double> theta0 = lik.InitialTheta();
  const std::vector<bool> is_log = lik.ParamIsLog();
  const int noise = lik.NumNoiseParams();
  const auto& phys = lik.physical();
  for (int i = 0; i < lik.NumParams(); ++i) {
    bool user_box = false, natural = is_log[i];
    if (i >= noise && i < lik.FirstX0Param()) {
      const int j = i - noise;
      const EstimatedParam& e = phys.estimated()[j];
      user_box = !std::isnan(e.lower) && !std::isnan(e.upper);
      natural =
          natural || (Model::kParams[phys.ModelIndex(j)].constraint == Constraint::kNonNegative &&
                      lower[i] == 0.0);
    }
    spread->push_back(
        SpreadInterval(o, theta0[i], is_log[i], i >= noise, user_box, lower[i], upper[i]));
    lower_is_constraint->push_back(natural);
  }
}

// One start of the multi-start from `point`: its NLL, the common-scale
// pre-search on Q and R, the optimiser.
template <class Model, class Meas>
TuneStart RunStart(const Objective<Model, Meas>& objective, const TunerOptions& o,
                   const std::vector<double>& point, const std::vector<double>& lower,
                   const std::vector<double>& upper, const TuneProgress& where) {
  const auto& lik = objective.likelihood();
  const std::vector<bool> is_log = lik.ParamIsLog();
  const int noise = lik.NumNoiseParams();
  double nll_start = kInf;
  if (!objective.Value(point.data(), &nll_start) || !std::isfinite(nll_start)) nll_start = kInf;
  std::vector<double> from = point;
  double shift = 0.0;
  if (o.scale_search) {
    shift = ScaleSearch(objective, from, is_log, noise, lower, upper);
    from = ScaleShifted(from, is_log, noise, shift);
  }
  bool converged = false;
  TuneStart st =
      o.solver == MlSolver::kLbfgs
          ? RunLbfgs(objective, o, lower, upper, from, &converged, where)
          : RunLeastSquares(objective, o, lower, upper, from, Meas::kDim, &converged, where);
  st.theta_start = point;
  st.theta_scaled = from;
  st.nll_start = nll_start;
  st.scale_shift = shift;
  if (!st.ok) {  // say why the filter failed there
    double nll = 0.0;
    std::string why;
    if (!lik.Nll(from.data(), &nll, &why) && !why.empty())
      st.termination += " The filter at this start: " + why + ".";
  }
  return st;
}

// Every start, a task of one pool (src/core/task_pool.h) of options.jobs
// workers: worker 0 uses `objective`, the others each their own likelihood
// (CVODES solvers are per likelihood), made on the worker's first start. A
// start's result depends only on its point, so not on jobs. Progress is
// serialised. A start that throws stops the others; its exception is
// rethrown.
template <class Model, class Meas>
void RunStarts(const Objective<Model, Meas>& objective, const FilterSpec& spec,
               const TunerOptions& options, const std::vector<FilterData>& datasets,
               const std::vector<std::vector<double>>& points, const std::vector<double>& lower,
               const std::vector<double>& upper, std::vector<TuneStart>* starts) {
  const size_t n = points.size();
  starts->assign(n, TuneStart{});
  std::mutex progress_mutex;
  TunerOptions o = options;
  if (options.progress)
    o.progress = [&](const TuneProgress& p) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      options.progress(p);
    };
  const int jobs = std::max(1, std::min(o.jobs, int(n)));
  std::vector<std::unique_ptr<InnovationLikelihood<Model, Meas>>> own(static_cast<size_t>(jobs));
  std::vector<std::unique_ptr<Objective<Model, Meas>>> own_objective(static_cast<size_t>(jobs));
  TaskPool pool(jobs, n, [&](size_t s, int w) {
    if (w > 0 && !own[size_t(w)]) {
      own[size_t(w)] = std::make_unique<InnovationLikelihood<Model, Meas>>(spec, o, datasets);
      own_objective[size_t(w)] = std::make_unique<Objective<Model, Meas>>(*own[size_t(w)]);
    }
    const Objective<Model, Meas>& obj = w > 0 ? *own_objective[size_t(w)] : objective;
    const TuneProgress where{
        .phase = "start", .start = int(s) + 1, .starts = int(n), .objective = "NLL"};
    (*starts)[s] = RunStart(obj, o, points[s], lower, upper, where);
  });
  pool.Join();
}

// Picks the best admissible start (lowest NLL; the first on a tie) and
// fills the result from it; false when every start failed.
inline bool PickBest(TuneResult* result) {
  TuneResult& r = *result;
  for (size_t s = 0; s < r.starts.size(); ++s) {
    const TuneStart& st = r.starts[s];
    if (st.ok && (r.best_start < 0 || st.nll_end < r.starts[r.best_start].nll_end))
      r.best_start = int(s);
  }
  if (r.best_start < 0) {
    r.status = TuneStatus::kAllStartsFailed;
    r.message = "the filter diverged at every one of the " + std::to_string(r.starts.size()) +
                " start points (" + r.starts.front().termination + ")";
    r.nll_tuned = kInf;
    return false;
  }
  const TuneStart& best = r.starts[r.best_start];
  r.status = best.converged ? TuneStatus::kConverged : TuneStatus::kNoConvergence;
  r.theta = best.theta_end;
  r.nll_tuned = best.nll_end;
  r.iterations = best.iterations;
  r.termination = best.termination;
  r.trace = best.trace;
  int failed = 0;
  for (const auto& st : r.starts) failed += !st.ok;
  // Starts are numbered from 1 here as in 'estlab tune' (start 1 = the
  // initial guess); best_start is the 0-based index into starts.
  r.message = "best of " + std::to_string(r.starts.size()) + " start(s): start " +
              std::to_string(r.best_start + 1) +
              (failed ? " (" + std::to_string(failed) + " diverged)" : "");
  return true;
}

// Q and R fixed, no physical parameter: the initial guess is the result.
inline void NothingToTune(TuneResult* result) {
  TuneStart st;
  st.theta_start = st.theta_scaled = st.theta_end = result->theta_initial;
  st.ok = st.converged = std::isfinite(result->nll_initial);
  st.nll_start = st.nll_scaled = st.nll_end = result->nll_initial;
  st.termination = "nothing to tune (Q and R fixed)";
  st.trace = {st.nll_end};
  st.trace_theta = {st.theta_end};
  result->starts.assign(1, st);
}

}  // namespace tuner_internal
}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNER_STARTS_H_
