#include "src/run/filter_spec.h"

#include <boost/math/distributions/chi_squared.hpp>

#include "src/core/types.h"
#include "src/run/filter_options.h"

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

KfOptions KfOptionsOf(const FilterSpec& spec) {
  KfOptions o;
  o.operating_point = spec.linearize_at;
  o.operating_input = spec.input;
  return o;
}

EkfOptions EkfOptionsOf(const FilterSpec& spec) {
  EkfOptions o;
  o.iterations = spec.iterations;
  return o;
}

SigmaPointOptions SigmaPointOptionsOf(const FilterSpec& spec) {
  SigmaPointOptions o;
  switch (spec.kind) {
    case FilterKind::kUkf:
      o.rule = SigmaRule::kUnscented;
      break;
    case FilterKind::kCkf:
      o.rule = SigmaRule::kCubature;
      break;
    case FilterKind::kGhkf:
      o.rule = SigmaRule::kGaussHermite;
      break;
    case FilterKind::kKf:
    case FilterKind::kEkf:
    case FilterKind::kPf:
      throw InputError(std::string("filter ") + FilterKindName(spec.kind) +
                       " has no sigma-point rule");
  }
  o.alpha = spec.alpha;
  o.beta = spec.beta;
  o.kappa = spec.kappa;
  o.gh_order = spec.gh_order;
  o.update = spec.sigma_redraw ? SigmaPointOptions::Update::kRedraw
                               : SigmaPointOptions::Update::kPropagate;
  o.jitter = spec.jitter;
  return o;
}

ParticleOptions ParticleOptionsOf(const FilterSpec& spec) {
  ParticleOptions o;
  o.num_particles = spec.particles;
  o.resample = ParseResampleScheme(spec.resample);
  o.ess_threshold = spec.ess_threshold;
  o.seed = spec.seed;
  return o;
}

bool IsValidFilterOptions(const FilterSpec& spec, int state_dim, std::string* error) {
  if (!spec.transition.IsValid(error)) return false;
  if (!spec.adapt.rule.empty()) {
    const bool sigma = spec.kind == FilterKind::kUkf || spec.kind == FilterKind::kCkf ||
                       spec.kind == FilterKind::kGhkf;
    if (!sigma) {
      if (error != nullptr) *error = "adapt: needs a sigma-point filter (ukf, ckf, ghkf)";
      return false;
    }
    if (!spec.adapt.IsValid(error)) return false;
  }
  switch (spec.kind) {
    case FilterKind::kKf: {
      if (!spec.linearize_at.empty() && int(spec.linearize_at.size()) != state_dim) {
        if (error != nullptr)
          *error = "linearize-at: " + std::to_string(spec.linearize_at.size()) +
                   " values, the model has " + std::to_string(state_dim) + " states";
        return false;
      }
      return KfOptionsOf(spec).IsValid(error);
    }
    case FilterKind::kEkf:
      return EkfOptionsOf(spec).IsValid(error);
    case FilterKind::kUkf:
    case FilterKind::kCkf:
    case FilterKind::kGhkf:
      return SigmaPointOptionsOf(spec).IsValidFor(state_dim, error);
    case FilterKind::kPf:
      try {
        return ParticleOptionsOf(spec).IsValid(error);
      } catch (const InputError& e) {  // the resampling scheme's name
        if (error != nullptr) *error = e.what();
        return false;
      }
  }
  return false;
}

bool AllFilterOptionsValid(const FilterSpec& spec, int state_dim, std::string* error) {
  if (!IsValidFilterOptions(spec, state_dim, error)) return false;
  FilterSpec sigma = spec;
  sigma.kind = FilterKind::kUkf;  // the rule does not matter for IsValid
  try {
    return KfOptionsOf(spec).IsValid(error) && EkfOptionsOf(spec).IsValid(error) &&
           SigmaPointOptionsOf(sigma).IsValid(error) && ParticleOptionsOf(spec).IsValid(error);
  } catch (const InputError& e) {  // the resampling scheme's name
    if (error != nullptr) *error = e.what();
    return false;
  }
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
