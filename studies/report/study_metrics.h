// The metrics of a filter run that need no truth, for studies on recorded
// data: what the measurements alone can say about a filter and its Q/R. Over
// the rows with an update from row `skip` on (a recorded run's prior
// transient left out):
//
//   nll_per_step   -(1/K) sum_k log N(nu_k; 0, S_k) over the K updates
//   mean_nis       (1/K) sum_k nu_k^T S_k^-1 nu_k, with the two-sided 95 %
//                  bounds of a K-step mean: K mean ~ chi2(K m)
//   pred_rmse_j    sqrt((1/K_j) sum_k nu_kj^2): the one-step-ahead prediction
//                  error of output j, the recorded z_kj against the filter's
//                  prediction h(x_k|k-1) (the innovation; angle outputs are
//                  wrapped by the filters, src/filters/filter.h)
//
// Usage:
//   const FilterRunOutput out = model.run_filter(spec, data);
//   const NoTruthMetrics m = ComputeNoTruthMetrics(out, {"phi1", "phi2"}, 50);
//   m.pred_rmse[0];   // rad, for output phi1
//
// WARNING: with skip = 0 the first innovation is the measurement against
// the prior mean; with a vague prior it alone can dominate pred_rmse.
#ifndef ESTLAB_STUDIES_REPORT_STUDY_METRICS_H_
#define ESTLAB_STUDIES_REPORT_STUDY_METRICS_H_

#include <string>
#include <vector>

#include "src/run/filter_spec.h"

namespace estlab {

struct NoTruthMetrics {
  long updates = 0;           // K: the rows from `skip` on with an update
  double nll_per_step = 0.0;  // NaN without updates
  double mean_nis = 0.0;      // NaN without updates
  double nis_bounds95[2] = {0.0, 0.0};
  std::vector<double> pred_rmse;  // per requested output; NaN when it has no innovation
};

// From the run's per-row loglik, nis and nu_OUTPUT columns (rows without an
// update hold NaN and are skipped), `outputs` being the measurement's
// outputs (their number is the NIS dimension). An output the run has no
// column for gets NaN.
NoTruthMetrics ComputeNoTruthMetrics(const FilterRunOutput& out,
                                     const std::vector<std::string>& outputs, long skip = 0);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_REPORT_STUDY_METRICS_H_
