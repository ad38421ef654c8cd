#include "studies/report/study_metrics.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace estlab {

namespace {

// Index of a column, or -1.
int ColumnOf(const FilterRunOutput& out, const std::string& name) {
  const auto it = std::find(out.columns.begin(), out.columns.end(), name);
  return it == out.columns.end() ? -1 : int(it - out.columns.begin());
}

// sqrt(mean of the squares) of the finite values of a column from row `skip` on.
double RootMeanSquare(const FilterRunOutput& out, int column, size_t skip) {
  double sum_sq = 0.0;
  long count = 0;
  for (size_t k = skip; column >= 0 && k < out.rows.size(); ++k) {
    const double v = out.rows[k][size_t(column)];
    if (!std::isfinite(v)) continue;
    sum_sq += v * v;
    ++count;
  }
  return count > 0 ? std::sqrt(sum_sq / double(count)) : NAN;
}

}  // namespace

NoTruthMetrics ComputeNoTruthMetrics(const FilterRunOutput& out,
                                     const std::vector<std::string>& outputs, long skip) {
  NoTruthMetrics m;
  const size_t first = size_t(std::max(0L, skip));
  const int ll = ColumnOf(out, "loglik"), nis = ColumnOf(out, "nis");
  std::vector<int> nu_columns;
  for (const std::string& o : outputs) nu_columns.push_back(ColumnOf(out, "nu_" + o));
  double loglik = 0.0, nis_sum = 0.0;
  long dof = 0;  // the observed components (a missing one's nu is NaN)
  for (size_t k = first; ll >= 0 && nis >= 0 && k < out.rows.size(); ++k) {
    const auto& row = out.rows[k];
    if (!std::isfinite(row[size_t(ll)])) continue;  // no update at this row
    loglik += row[size_t(ll)];
    nis_sum += row[size_t(nis)];
    ++m.updates;
    for (int c : nu_columns) dof += c < 0 || std::isfinite(row[size_t(c)]);
  }
  m.nll_per_step = m.updates > 0 ? -loglik / double(m.updates) : NAN;
  m.mean_nis = m.updates > 0 ? nis_sum / double(m.updates) : NAN;
  ChiSquareMeanBounds95(m.updates, dof, m.nis_bounds95);
  for (const std::string& o : outputs)
    m.pred_rmse.push_back(RootMeanSquare(out, ColumnOf(out, "nu_" + o), first));
  return m;
}

}  // namespace estlab
