// The NIS of each sensor group of a run (FilterSummary::group_nis): for a
// measurement with groups (models/model.h, kGroups), each update's
// innovation restricted to the group's observed components o,
//
//   NIS_g = nu_o' S_oo^-1 nu_o,   chi-square with |o| degrees of freedom
//
// when the filter is consistent, so the mean over the updates that observed
// the group has the bounds ChiSquareMeanBounds95(updates, sum |o|). A
// measurement without groups adds nothing (the run's NIS is the group's).
//
// Usage (src/run/filter_run_impl.h):
//   GroupNisTally<Meas> tally;
//   tally.Observe(r.innovation, r.innovation_cov);  // NaN: a missing component
//   tally.Report(&summary);
#ifndef ESTLAB_RUN_GROUP_NIS_H_
#define ESTLAB_RUN_GROUP_NIS_H_

#include <Eigen/Cholesky>
#include <array>
#include <cmath>
#include <limits>

#include "models/model.h"
#include "src/core/types.h"
#include "src/run/filter_spec.h"

namespace estlab {

template <class Meas>
class GroupNisTally {
 public:
  static constexpr int M = Meas::kDim;
  static constexpr auto kGroups = MeasurementGroups<Meas>();
  static constexpr size_t G = kGroups.size();

  // One update: nu with NaN in the missing components, S its covariance.
  // The observed block of S is embedded in the identity, so the fixed-size
  // Cholesky solve equals the reduced one (src/filters/missing.h).
  void Observe(const Vec<double, M>& nu, const Mat<M, M>& S) {
    if constexpr (G > 1) {
      for (size_t g = 0; g < G; ++g) {
        const int first = kGroups[g].first, last = first + kGroups[g].count;
        Mat<M, M> s = Mat<M, M>::Identity();
        Vec<double, M> v = Vec<double, M>::Zero();
        int observed = 0;
        for (int i = first; i < last; ++i) {
          if (!std::isfinite(nu(i))) continue;
          ++observed;
          v(i) = nu(i);
          for (int j = first; j < last; ++j)
            if (std::isfinite(nu(j))) s(i, j) = S(i, j);
        }
        if (observed == 0) continue;
        const Eigen::LLT<Mat<M, M>> llt(s);
        const double nis = llt.info() == Eigen::Success ? v.dot(llt.solve(v))
                                                        : std::numeric_limits<double>::quiet_NaN();
        sum_[g] += nis;
        dof_[g] += observed;
        ++updates_[g];
      }
    }
  }

  void Report(FilterSummary* s) const {
    s->group_nis.clear();
    if constexpr (G > 1) {
      for (size_t g = 0; g < G; ++g) {
        FilterSummary::GroupNis out;
        out.group = kGroups[g].name;
        out.updates = updates_[g];
        out.mean_nis =
            updates_[g] ? sum_[g] / double(updates_[g]) : std::numeric_limits<double>::quiet_NaN();
        ChiSquareMeanBounds95(updates_[g], dof_[g], out.nis_bounds95);
        s->group_nis.push_back(out);
      }
    }
  }

 private:
  std::array<double, G> sum_{};
  std::array<long, G> dof_{}, updates_{};
};

}  // namespace estlab

#endif  // ESTLAB_RUN_GROUP_NIS_H_
