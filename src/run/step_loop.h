// The time loop of every filter run, written once: `estlab filter` and the
// studies (filter_run_impl.h) and the tuner's likelihood
// (adaptive/likelihood.h) all step through a dataset with it.
//
// For each row k at time t_k (t_{-1} = spec.t0 when given, else t_0):
//   if t_k > t_{k-1}: predict from t_{k-1} to t_k with the input u held over
//                     the step (the data's u column at row k-1, else
//                     spec.input)
//   then visit the row with z_k, or with no measurement when any component
//   of z_k is missing (NaN): no update then.
// Either callable stops the loop by returning false.
//
// Usage:
//   const bool completed = ForEachStep<M>(
//       spec, data,
//       [&](size_t k, double t0, double t1, double u) { return Predict(...); },
//       [&](size_t k, const Vec<double, M>* z) { return z ? Update(*z) : true; });
#ifndef ESTLAB_RUN_STEP_LOOP_H_
#define ESTLAB_RUN_STEP_LOOP_H_

#include <cmath>
#include <cstddef>
#include <string>

#include "src/core/types.h"
#include "src/filters/filter_util.h"
#include "src/run/filter_spec.h"

namespace estlab {

template <int M, class PredictFn, class RowFn>
bool ForEachStep(const FilterSpec& spec, const FilterData& data, PredictFn&& predict, RowFn&& row) {
  const size_t rows = data.t.size();
  double t_prev = spec.has_t0 ? spec.t0 : (rows ? data.t[0] : 0.0);
  for (size_t k = 0; k < rows; ++k) {
    const double t = data.t[k];
    if (t > t_prev) {
      const double u = data.has_input ? data.u[k > 0 ? k - 1 : 0] : spec.input;
      if (!predict(k, t_prev, t, u)) return false;
    }
    t_prev = t;
    Vec<double, M> z;
    bool have_z = true;
    for (int j = 0; j < M; ++j) {
      z(j) = data.z[k * M + j];
      if (!std::isfinite(z(j))) have_z = false;
    }
    if (!row(k, have_z ? &z : nullptr)) return false;
  }
  return true;
}

// The divergence guard of every run: the estimate and its covariance are
// finite and trace(P) <= max_trace. False with the reason in *why otherwise.
template <int N, class T = double>
bool WithinDivergenceGuard(const Vec<T, N>& x, const MatT<T, N, N>& P, double max_trace,
                           std::string* why) {
  if (!BeliefFinite<N, T>(x, P)) {
    *why = "the estimate or its covariance is not finite";
    return false;
  }
  const double trace = ScalarPart(P.trace());
  if (trace > max_trace) {
    *why = "trace(P) = " + FormatNumber(trace) + " exceeds " + FormatNumber(max_trace);
    return false;
  }
  return true;
}

}  // namespace estlab

#endif  // ESTLAB_RUN_STEP_LOOP_H_
