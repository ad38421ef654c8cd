// The time loop of every filter run, written once: `estlab filter` and the
// studies (filter_run_impl.h) and the tuner's likelihood
// (adaptive/likelihood.h) all step through a dataset with it.
//
// For each row k at time t_k (t_{-1} = spec.t0 when given, else t_0):
//   if t_k > t_{k-1}: predict from t_{k-1} to t_k with the input u0 = u_{k-1}
//                     at its start and u1 at its end: u1 = u_{k-1} under
//                     zero-order hold (held over the step), u1 = u_k under
//                     spec.transition.input_hold = linear (the line between
//                     the samples, src/ode/input_path.h); row 0's input
//                     before the first row
//   then visit the row with z_k (NaN in the components that are missing:
//   the filters update with the observed ones, src/filters/missing.h), or
//   with no measurement when every component is missing: no update then;
//   with the input u_k, which a measurement h(t, x, u) sees at the row's
//   time t_k.
// An input is a pointer to nu values (InputAtRow: the data's input columns,
// else spec.input), or null for the zero input; InputFrom<Model>(u)
// (models/model.h) makes it the model's input.
// Either callable stops the loop by returning false; so does a Ctrl-C
// that a caller notes without ending the process (src/core/interrupt.h),
// before the next row.
//
// Usage:
//   const bool completed = ForEachStep<M>(
//       spec, data,
//       [&](size_t k, double t0, double t1, const double* u0, const double* u1) {
//         return Predict(...);
//       },
//       [&](size_t k, const Vec<double, M>* z, const double* u) { return z ? Update(*z) : true; });
#ifndef ESTLAB_RUN_STEP_LOOP_H_
#define ESTLAB_RUN_STEP_LOOP_H_

#include <cmath>
#include <cstddef>
#include <string>

#include "src/core/interrupt.h"
#include "src/core/types.h"
#include "src/filters/filter_util.h"
#include "src/run/filter_spec.h"

namespace estlab {

// Row k's input: its nu input cells, else spec.input (null when empty).
inline const double* InputAtRow(const FilterSpec& spec, const FilterData& data, size_t k) {
  if (data.nu > 0)
    return (k + 1) * size_t(data.nu) <= data.u.size() ? &data.u[k * size_t(data.nu)] : nullptr;
  return spec.input.empty() ? nullptr : spec.input.data();
}

// "" when the data's input columns and spec.input fit a model with `inputs`
// inputs (each either absent or of that width), else what does not.
inline std::string CheckInputWidths(const FilterSpec& spec, const FilterData& data, int inputs) {
  if (data.nu != 0 && data.nu != inputs)
    return data.path + ": " + std::to_string(data.nu) + " input columns for a model with " +
           std::to_string(inputs) + " inputs";
  if (data.nu != 0 && data.u.size() != data.t.size() * size_t(data.nu))
    return data.path + ": the input columns do not cover every row";
  if (!spec.input.empty() && int(spec.input.size()) != inputs)
    return "input: " + std::to_string(spec.input.size()) + " values for a model with " +
           std::to_string(inputs) + " inputs";
  return "";
}

// Whether row k of `data` updates: some component of z_k is observed.
inline bool RowUpdates(const FilterData& data, size_t k) {
  for (int j = 0; j < data.m; ++j)
    if (std::isfinite(data.z[k * size_t(data.m) + size_t(j)])) return true;
  return false;
}

template <int M, class PredictFn, class RowFn>
bool ForEachStep(const FilterSpec& spec, const FilterData& data, PredictFn&& predict, RowFn&& row) {
  const size_t rows = data.t.size();
  const bool linear = spec.transition.input_hold == InputHold::kLinear;
  double t_prev = spec.has_t0 ? spec.t0 : (rows ? data.t[0] : 0.0);
  for (size_t k = 0; k < rows; ++k) {
    if (InterruptRequested()) return false;
    const double t = data.t[k];
    if (t > t_prev) {
      const double* u0 = InputAtRow(spec, data, k > 0 ? k - 1 : 0);
      if (!predict(k, t_prev, t, u0, linear ? InputAtRow(spec, data, k) : u0)) return false;
    }
    t_prev = t;
    Vec<double, M> z;
    bool have_z = false;
    for (int j = 0; j < M; ++j) {
      z(j) = data.z[k * M + j];
      if (std::isfinite(z(j))) have_z = true;
    }
    if (!row(k, have_z ? &z : nullptr, InputAtRow(spec, data, k))) return false;
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
