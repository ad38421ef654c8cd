// One estimated model parameter on the optimiser's scale, shared by the
// prediction-error fit (physical_params.h) and the output-error fit
// (studies/run/output_error.h), so that both check, scale and bound a parameter
// alike:
//
//   theta = log p   when p is constrained > 0, else theta = p
//   bounds: --param-bounds on the natural scale, mapped; else the
//   constraint's (>= 0 gives 0) and, for log p, initial +- bound_width
//
// Usage:
//   const ThetaScale s = ResolveThetaScale(e, Constraint::kPositive, 0.15, 20.0);
//   double p = s.Natural(theta);
#ifndef ESTLAB_ADAPTIVE_THETA_SCALE_H_
#define ESTLAB_ADAPTIVE_THETA_SCALE_H_

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/core/params.h"

namespace estlab {

struct ThetaScale {
  bool is_log = false;
  double theta0 = 0.0;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  double Natural(double theta) const { return is_log ? std::exp(theta) : theta; }
};

// Checks `e` against its constraint and the initial value (bounds inside
// the constraint and around the initial value, a finite prior with sd > 0)
// and maps it; throws InputError naming the option and the parameter.
ThetaScale ResolveThetaScale(const EstimatedParam& e, Constraint constraint, double initial,
                             double bound_width);

// The index of `name` in `names` (the model's parameters); InputError
// listing them otherwise.
int FindEstimatedParam(const std::string& name, const std::vector<std::string>& names,
                       const std::string& model);

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_THETA_SCALE_H_
