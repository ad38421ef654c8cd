#include "src/run/filter_spec.h"

#include <boost/math/distributions/chi_squared.hpp>

#include "src/core/types.h"

namespace estlab {

bool IsValidFilterOptions(const FilterSpec& spec, int state_dim, std::string* error) {
  if (!spec.transition.IsValid(error)) return false;
  if (spec.smooth && spec.smoother_trajectories < 2) {
    if (error != nullptr)
      *error = "smoother-trajectories: must be at least 2, got " +
               std::to_string(spec.smoother_trajectories);
    return false;
  }
  if (!spec.adapt.rule.empty()) {
    if (!std::holds_alternative<SigmaPointOptions>(spec.filter)) {
      if (error != nullptr) *error = "adapt: needs a sigma-point filter (ukf, ckf, ghkf)";
      return false;
    }
    if (!spec.adapt.IsValid(error)) return false;
  }
  return std::visit([&](const auto& o) { return o.IsValidFor(state_dim, error); }, spec.filter);
}

std::string SmootherName(const std::string& filter_name) {
  if (filter_name == "kf") return "rts";
  if (filter_name == "ekf") return "erts";
  if (filter_name == "ukf") return "urts";
  if (filter_name == "pf") return "pf-bs";
  return filter_name + "-rts";  // iekf-rts, ckf-rts, ghkf-rts
}

std::string FilterOfSmoother(const std::string& name) {
  for (const char* filter : {"kf", "ekf", "iekf", "ukf", "ckf", "ghkf", "pf"})
    if (SmootherName(filter) == name) return filter;
  return "";
}

void ChiSquareBounds95(long steps, int dim, double bounds[2]) {
  ChiSquareMeanBounds95(steps, steps * long(dim), bounds);
}

void ChiSquareMeanBounds95(long steps, long dof, double bounds[2]) {
  if (steps <= 0 || dof <= 0) {
    bounds[0] = bounds[1] = 0.0;
    return;
  }
  const boost::math::chi_squared dist{double(dof)};
  bounds[0] = boost::math::quantile(dist, 0.025) / double(steps);
  bounds[1] = boost::math::quantile(dist, 0.975) / double(steps);
}

}  // namespace estlab
