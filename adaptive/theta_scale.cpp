#include "adaptive/theta_scale.h"

#include "src/core/types.h"

namespace estlab {

ThetaScale ResolveThetaScale(const EstimatedParam& e, Constraint c, double v,
                             double bound_width) {
  ThetaScale s;
  s.is_log = c == Constraint::kPositive;
  if (s.is_log && !(v > 0))
    throw InputError("--estimate-param: the initial " + e.name + " must be > 0, got " +
                     FormatNumber(v));
  auto check_bound = [&](double b, const char* which) {
    if (std::isnan(b)) return;
    if (!std::isfinite(b) || (s.is_log && !(b > 0)) || (c == Constraint::kNonNegative && b < 0))
      throw InputError("--param-bounds: the " + std::string(which) + " bound of " + e.name +
                       " must be finite and " + ConstraintText(c) + ", got " + FormatNumber(b));
  };
  check_bound(e.lower, "lower");
  check_bound(e.upper, "upper");
  if (!std::isnan(e.lower) && !std::isnan(e.upper) && !(e.lower < e.upper))
    throw InputError("--param-bounds: " + e.name + "'s lower bound " + FormatNumber(e.lower) +
                     " is not below its upper bound " + FormatNumber(e.upper));
  if ((!std::isnan(e.lower) && v < e.lower) || (!std::isnan(e.upper) && v > e.upper))
    throw InputError("--param-bounds: the initial " + e.name + " = " + FormatNumber(v) +
                     " is outside its bounds");
  if (e.has_prior && !(e.prior_sd > 0 && std::isfinite(e.prior_sd) && std::isfinite(e.prior_mean)))
    throw InputError("--param-prior: " + e.name + " needs a finite mean and sd > 0");
  if (s.is_log) {
    s.theta0 = std::log(v);
    s.lower = std::isnan(e.lower) ? s.theta0 - bound_width : std::log(e.lower);
    s.upper = std::isnan(e.upper) ? s.theta0 + bound_width : std::log(e.upper);
  } else {
    s.theta0 = v;
    if (!std::isnan(e.lower)) {
      s.lower = e.lower;
    } else if (c == Constraint::kNonNegative) {
      s.lower = 0.0;
    }
    if (!std::isnan(e.upper)) s.upper = e.upper;
  }
  return s;
}

int FindEstimatedParam(const std::string& name, const std::vector<std::string>& names,
                       const std::string& model) {
  std::string known;
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return int(i);
    known += (i ? ", " : "") + names[i];
  }
  throw InputError("--estimate-param: model '" + model + "' has no parameter '" + name +
                   "' (it has " + known + ")");
}

}  // namespace estlab
