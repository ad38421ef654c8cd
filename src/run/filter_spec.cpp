#include "src/run/filter_spec.h"

#include <boost/math/distributions/chi_squared.hpp>

#include "src/core/types.h"

namespace estlab {

bool IsValidFilterOptions(const FilterSpec& spec, int state_dim, std::string* error) {
  if (!spec.transition.IsValid(error)) return false;
  if (!spec.adapt.rule.empty()) {
    if (!std::holds_alternative<SigmaPointOptions>(spec.filter)) {
      if (error != nullptr) *error = "adapt: needs a sigma-point filter (ukf, ckf, ghkf)";
      return false;
    }
    if (!spec.adapt.IsValid(error)) return false;
  }
  return std::visit([&](const auto& o) { return o.IsValidFor(state_dim, error); }, spec.filter);
}

void ChiSquareBounds95(long steps, int dim, double bounds[2]) {
  if (steps <= 0 || dim <= 0) {
    bounds[0] = bounds[1] = 0.0;
    return;
  }
  const double dof = double(steps) * dim;
  boost::math::chi_squared dist(dof);
  bounds[0] = boost::math::quantile(dist, 0.025) / double(steps);
  bounds[1] = boost::math::quantile(dist, 0.975) / double(steps);
}

}  // namespace estlab
