// The checks of the filter options (filter_options.h); every message starts
// with the option key it is about.
#include "src/filters/filter_options.h"

#include <cmath>
#include <string>

#include "src/core/types.h"

namespace estlab {

// Particles of one filter: 1e7 of a 4-state model already hold about 1 GB
// (states, propagated states, weights).
constexpr int kMaxParticles = 10000000;

bool EkfOptions::IsValid(std::string* error) const {
  if (iterations < 1 || iterations > 100) {
    if (error != nullptr)
      *error = "iterations: must be in [1, 100], got " + std::to_string(iterations);
    return false;
  }
  return true;
}

bool KfOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  for (size_t i = 0; i < operating_point.size(); ++i) {
    if (!std::isfinite(operating_point[i]))
      return fail("linearize-at: operating point component " + std::to_string(i) +
                  " is not finite");
  }
  for (size_t i = 0; i < operating_input.size(); ++i) {
    if (!std::isfinite(operating_input[i]))
      return fail("input: the operating input u* component " + std::to_string(i) +
                  " is not finite");
  }
  return true;
}

bool KfOptions::IsValidFor(int n, std::string* error) const {
  if (!operating_point.empty() && int(operating_point.size()) != n) {
    if (error != nullptr)
      *error = "linearize-at: " + std::to_string(operating_point.size()) +
               " values, the model has " + std::to_string(n) + " states";
    return false;
  }
  return IsValid(error);
}

ResampleScheme ParseResampleScheme(const std::string& name) {
  if (name == "multinomial") return ResampleScheme::kMultinomial;
  if (name == "systematic") return ResampleScheme::kSystematic;
  if (name == "stratified") return ResampleScheme::kStratified;
  if (name == "residual") return ResampleScheme::kResidual;
  throw InputError("resample: unknown scheme '" + name +
                   "' (expected multinomial, systematic, stratified or residual)");
}

const char* ResampleSchemeName(ResampleScheme scheme) {
  switch (scheme) {
    case ResampleScheme::kMultinomial:
      return "multinomial";
    case ResampleScheme::kSystematic:
      return "systematic";
    case ResampleScheme::kStratified:
      return "stratified";
    case ResampleScheme::kResidual:
      return "residual";
  }
  return "?";
}

bool ParticleOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (num_particles < 1 || num_particles > kMaxParticles)
    return fail("particles: must be in [1, " + std::to_string(kMaxParticles) + "], got " +
                std::to_string(num_particles));
  if (!(ess_threshold >= 0.0 && ess_threshold <= 1.0))
    return fail("ess-threshold: must be in [0, 1], got " + FormatNumber(ess_threshold));
  return true;
}

bool AdaptSpec::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (rule.empty()) return true;
  if (rule != "sage-husa" && rule != "innovation-matching")
    return fail("adapt: unknown rule '" + rule + "' (expected sage-husa or innovation-matching)");
  if (!adapt_q && !adapt_r) return fail("adapt-what: adapts neither q nor r");
  if (!(forgetting > 0 && forgetting < 1))
    return fail("forgetting: must be in (0, 1), got " + FormatNumber(forgetting));
  if (window < 1) return fail("window: must be >= 1, got " + std::to_string(window));
  if (!(eigen_floor >= 0)) return fail("adapt: the eigenvalue floor must be >= 0");
  return true;
}

}  // namespace estlab
