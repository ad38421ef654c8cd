// The prior mean of `x0 = first-sample` (FilterSpec::x0_first_sample): a
// recorded run starts wherever it starts, so each dataset gets its own x0
// from its first finite measurement of each state that an output of the
// same name measures (theta measured as output theta); the other states keep
// spec.x0's value (0 unless given).
//
// Usage:
//   const Vec<double, N> x0 = PriorMean<Model, Meas>(spec, data);
#ifndef ESTLAB_RUN_FIRST_SAMPLE_H_
#define ESTLAB_RUN_FIRST_SAMPLE_H_

#include <cmath>
#include <string>

#include "models/model_traits.h"
#include "src/core/types.h"
#include "src/run/filter_spec.h"

namespace estlab {

// spec.x0, or with x0_first_sample the dataset's first measured states.
template <class Model, class Meas>
Vec<double, Model::kStateDim> PriorMean(const FilterSpec& spec, const FilterData& data) {
  Vec<double, Model::kStateDim> x0 = ToVec<Model::kStateDim>(spec.x0);
  if (!spec.x0_first_sample) return x0;
  for (int j = 0; j < Meas::kDim; ++j) {
    for (int i = 0; i < Model::kStateDim; ++i) {
      if (std::string(Meas::kOutputs[j]) != Model::kStateNames[i]) continue;
      for (size_t k = 0; k < data.t.size(); ++k) {
        const double z = data.z[k * Meas::kDim + j];
        if (std::isfinite(z)) {
          x0(i) = z;
          break;
        }
      }
    }
  }
  return x0;
}

}  // namespace estlab

#endif  // ESTLAB_RUN_FIRST_SAMPLE_H_
