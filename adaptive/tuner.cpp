#include "adaptive/tuner.h"

#include <cmath>
#include <string>
#include <vector>

#include "src/core/types.h"

namespace estlab {

NoiseParam ParseNoiseParam(const std::string& name, const std::string& option) {
  if (name == "diag") return NoiseParam::kDiag;
  if (name == "full") return NoiseParam::kFull;
  if (name == "white-accel") return NoiseParam::kWhiteAccel;
  if (name == "scalar") return NoiseParam::kScalar;
  if (name == "fixed") return NoiseParam::kFixed;
  throw InputError(option + ": unknown parameterisation '" + name +
                   "' (expected diag, full, white-accel, scalar or fixed)");
}

const char* NoiseParamName(NoiseParam param) {
  switch (param) {
    case NoiseParam::kDiag:
      return "diag";
    case NoiseParam::kFull:
      return "full";
    case NoiseParam::kWhiteAccel:
      return "white-accel";
    case NoiseParam::kScalar:
      return "scalar";
    case NoiseParam::kFixed:
      return "fixed";
  }
  return "?";
}

const char* TuneStatusName(TuneStatus status) {
  switch (status) {
    case TuneStatus::kConverged:
      return "converged";
    case TuneStatus::kNoConvergence:
      return "no-convergence";
    case TuneStatus::kAllStartsFailed:
      return "all-starts-diverged";
    case TuneStatus::kNotAMinimum:
      return "not-a-minimum";
    case TuneStatus::kWorseThanStart:
      return "worse-than-start";
    case TuneStatus::kAtBound:
      return "at-bound";
    case TuneStatus::kUnverified:
      return "unverified";
  }
  return "?";
}

bool TunerOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (burn_in < 0) return fail("burn-in must be >= 0, got " + std::to_string(burn_in));
  if (starts < 1) return fail("starts must be >= 1, got " + std::to_string(starts));
  if (jobs < 1) return fail("jobs must be >= 1, got " + std::to_string(jobs));
  if (!(start_spread >= 0 && std::isfinite(start_spread)))
    return fail("start spread must be finite and >= 0, got " + FormatNumber(start_spread));
  if (!(bound_width > 0)) return fail("bound width must be > 0, got " + FormatNumber(bound_width));
  if (max_iterations < 1) return fail("max iterations must be >= 1");
  if (max_integrator_steps < 1 || max_integrator_steps > 100000000)
    return fail("max integrator steps must be in 1..1e8, got " +
                std::to_string(max_integrator_steps));
  if (!(function_tolerance >= 0 && gradient_tolerance >= 0 && parameter_tolerance >= 0))
    return fail("tolerances must be >= 0");
  if (!(hessian_step > 0 && hessian_step < 1))
    return fail("hessian step must be in (0, 1), got " + FormatNumber(hessian_step));
  if (!(log_det_margin > 0)) return fail("log-det margin must be > 0");
  if (r_param == NoiseParam::kWhiteAccel)
    return fail("white-accel applies to the process noise Q only, not to R");
  const EstimatorInfo& e = InfoOf(estimator);
  const std::string name = e.name;
  if (estimator == Estimator::kEm && !(em_tolerance >= 0 && std::isfinite(em_tolerance)))
    return fail("EM tolerance must be finite and >= 0, got " + FormatNumber(em_tolerance));
  if (estimator == Estimator::kAls && als_lags < 1)
    return fail("ALS lags must be >= 1, got " + std::to_string(als_lags));
  if (!e.burn_in && burn_in != 0)
    return fail("the " + name +
                " estimator uses every update: burn-in applies to the ml and als estimators");
  if (!e.multi_start && starts != 1)
    return fail("the " + name + " estimator runs from the initial guess only (starts 1)");
  if (!e.params && !estimate.empty())
    return fail("the " + name +
                " estimator estimates Q and R only; physical parameters need the ml estimator");
  if (!e.x0 && (!estimate_x0.empty() || x0_per_file)) {
    std::vector<std::string> takers;
    for (const EstimatorInfo& other : Estimators())
      if (other.x0) takers.push_back(other.name);
    std::string with_x0;
    for (size_t i = 0; i < takers.size(); ++i)
      with_x0 += (i == 0 ? "" : i + 1 == takers.size() ? " and " : ", ") + takers[i];
    return fail(std::string(estimate_x0.empty() ? "--x0-per-file" : "--estimate-x0") +
                " applies to the " + with_x0 + " estimators, not " + name);
  }
  if (x0_per_file && estimate_x0.empty())
    return fail("--x0-per-file needs --estimate-x0 (the states estimated per file)");
  for (double v : log_lower)
    if (std::isnan(v)) return fail("a lower bound is NaN");
  for (double v : log_upper)
    if (std::isnan(v)) return fail("an upper bound is NaN");
  if (log_lower.size() == 1 && log_upper.size() == 1 && log_lower[0] > log_upper[0]) {
    return fail("lower bound " + FormatNumber(log_lower[0]) + " is above upper bound " +
                FormatNumber(log_upper[0]));
  }
  return true;
}

bool IsTunable(const FilterSpec& spec, const TunerOptions& options, int state_dim,
               std::string* error) {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!options.IsValid(error)) return false;
  const EstimatorInfo& e = InfoOf(options.estimator);
  if (!e.tuner)
    return fail(std::string("the ") + e.name + " estimator does not run through the tuner");
  if (!e.accepts(spec))
    return fail(std::string("the ") + e.name + " estimator supports " + e.filters + ", not " +
                FilterKindName(spec.kind()) +
                (InfoOf(spec.kind()).tunable
                     ? (spec.iterated() ? " with iterations" : "")
                     : " (its likelihood is a random, non-smooth function of Q and R)"));
  // The filter's own check of its options (the one estlab filter applies).
  if (!IsValidFilterOptions(spec, state_dim, error)) return false;
  if (!spec.adapt.rule.empty())
    return fail("the tuner needs a filter without online adaptation (--adapt)");
  if (!options.estimate.empty() && spec.kind() == FilterKind::kKf)
    return fail(
        "--estimate-param needs the ekf, iekf or a sigma-point filter: the kf "
        "linearises the model once, at the nominal parameters");
  return true;
}

}  // namespace estlab
