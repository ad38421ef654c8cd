// The metrics of a filter run that need no truth, for studies on recorded
// data: what the measurements alone can say about a filter and its Q/R.
//
//   nll_per_step   -(1/K) sum_k log N(nu_k; 0, S_k) over the K updates
//   NIS bounds     two-sided 95 % bounds of the K-step mean NIS, K mean ~ chi2(K m)
//   pred_rmse_j    sqrt((1/K_j) sum_k nu_kj^2): the one-step-ahead prediction
//                  error of output j, the recorded z_kj against the filter's
//                  prediction h(x_k|k-1) (the innovation; angle outputs are
//                  wrapped by the filters, src/filters/filter.h)
//
// Usage:
//   const FilterRunOutput out = model.run_filter(spec, data);
//   const NoTruthMetrics m = ComputeNoTruthMetrics(out, {"phi1", "phi2"});
//   m.pred_rmse[0];   // rad, for output phi1
#ifndef ESTLAB_STUDIES_STUDY_METRICS_H_
#define ESTLAB_STUDIES_STUDY_METRICS_H_

#include <string>
#include <vector>

#include "src/run/filter_spec.h"

namespace estlab {

struct NoTruthMetrics {
  double nll_per_step = 0.0;  // NaN without updates
  double nis_bounds95[2] = {0.0, 0.0};
  std::vector<double> pred_rmse;  // per requested output; NaN when it has no innovation
};

// From the run's nu_OUTPUT columns (rows without an update hold NaN and are
// skipped) and its summary (loglik, updates, NIS bounds). An output the run
// has no column for gets NaN.
NoTruthMetrics ComputeNoTruthMetrics(const FilterRunOutput& out,
                                     const std::vector<std::string>& outputs);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_STUDY_METRICS_H_
