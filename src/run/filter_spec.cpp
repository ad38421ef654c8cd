#include "src/run/filter_spec.h"

#include <boost/math/distributions/chi_squared.hpp>

#include "src/core/types.h"

namespace estlab {

FilterKind ParseFilterKind(const std::string& name) {
  if (name == "kf") return FilterKind::kKf;
  if (name == "ekf" || name == "iekf") return FilterKind::kEkf;
  if (name == "ukf") return FilterKind::kUkf;
  if (name == "ckf") return FilterKind::kCkf;
  if (name == "ghkf") return FilterKind::kGhkf;
  if (name == "pf") return FilterKind::kPf;
  throw InputError("unknown filter '" + name + "' (expected kf, ekf, iekf, ukf, ckf, ghkf or pf)");
}

const char* FilterKindName(FilterKind kind) {
  switch (kind) {
    case FilterKind::kKf:
      return "kf";
    case FilterKind::kEkf:
      return "ekf";
    case FilterKind::kUkf:
      return "ukf";
    case FilterKind::kCkf:
      return "ckf";
    case FilterKind::kGhkf:
      return "ghkf";
    case FilterKind::kPf:
      return "pf";
  }
  return "?";
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
