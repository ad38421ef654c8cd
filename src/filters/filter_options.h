// The options of each filter kind, in one light header (no Eigen templates
// beyond Core): the alternatives of FilterSpec::filter (src/run/filter_kinds.h),
// what each filter's constructor validates with its IsValid. IsValidFor(n)
// adds the checks that need the model's state dimension n.
#ifndef ESTLAB_FILTERS_FILTER_OPTIONS_H_
#define ESTLAB_FILTERS_FILTER_OPTIONS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "src/filters/sigma_rules.h"

namespace estlab {

struct EkfOptions {
  // 1 = EKF; > 1 = iterated EKF with this many Gauss-Newton iterations.
  int iterations = 1;

  bool IsValid(std::string* error) const;
  bool IsValidFor(int /*n*/, std::string* error) const { return IsValid(error); }
};

// The bytes the particle smoother keeps (particle_smoother.h): every step's
// cloud, `particles` x `rows` x (2 states + 1) doubles. `estlab smooth` and a
// study's pf-bs refuse a run that would keep over 4 GiB before it starts.
inline double ParticleSmootherBytes(double particles, double rows, int states) {
  return particles * rows * (2.0 * states + 1.0) * 8.0;
}

struct KfOptions {
  // x*; empty = the prior mean given to Initialize().
  std::vector<double> operating_point;
  // u*, one value per model input; empty = 0 for every input.
  std::vector<double> operating_input;

  bool IsValid(std::string* error) const;
  // IsValid, and an operating point (when given) of n components.
  bool IsValidFor(int n, std::string* error) const;
};

enum class ResampleScheme { kMultinomial, kSystematic, kStratified, kResidual };

// Parses "multinomial", "systematic", "stratified", "residual"; throws InputError.
ResampleScheme ParseResampleScheme(const std::string& name);
const char* ResampleSchemeName(ResampleScheme scheme);

struct ParticleOptions {
  int num_particles = 1000;
  ResampleScheme resample = ResampleScheme::kSystematic;
  // Resample when ESS < ess_threshold * N; 1 = every step, 0 = never.
  double ess_threshold = 0.5;
  uint64_t seed = 1;

  bool IsValid(std::string* error) const;
  bool IsValidFor(int /*n*/, std::string* error) const { return IsValid(error); }
};

// Online noise adaptation of the sigma-point filter (noise_adapter.h).
struct AdaptSpec {
  std::string rule;  // "" (off), "sage-husa", "innovation-matching"
  bool adapt_q = false;
  bool adapt_r = true;
  double forgetting = 0.97;  // Sage-Husa b
  int window = 30;           // innovation matching N
  double eigen_floor = 1e-10;

  // Messages start with the option key ("forgetting: must be in (0, 1)").
  bool IsValid(std::string* error) const;
};

}  // namespace estlab

#endif  // ESTLAB_FILTERS_FILTER_OPTIONS_H_
