#include "studies/study_metrics.h"

#include <algorithm>
#include <cmath>

namespace estlab {

NoTruthMetrics ComputeNoTruthMetrics(const FilterRunOutput& out,
                                     const std::vector<std::string>& outputs) {
  NoTruthMetrics m;
  const FilterSummary& s = out.summary;
  m.nll_per_step = s.updates > 0 ? -s.loglik / double(s.updates) : NAN;
  m.nis_bounds95[0] = s.nis_bounds95[0];
  m.nis_bounds95[1] = s.nis_bounds95[1];
  for (const std::string& o : outputs) {
    const auto it = std::find(out.columns.begin(), out.columns.end(), "nu_" + o);
    double sum_sq = 0.0;
    long count = 0;
    if (it != out.columns.end()) {
      const size_t c = size_t(it - out.columns.begin());
      for (const auto& row : out.rows) {
        if (!std::isfinite(row[c])) continue;
        sum_sq += row[c] * row[c];
        ++count;
      }
    }
    m.pred_rmse.push_back(count > 0 ? std::sqrt(sum_sq / double(count)) : NAN);
  }
  return m;
}

}  // namespace estlab
