// Noise identification inside a Monte Carlo run (`tune-per-run = true`): the
// run's own measurements are all the tuner sees, as when a user tunes one
// recording; the filter then runs on the same measurements with the result.
// How close the identified noise is to the truth's:
//
//   id_q_err = ||Q^ - Q||_F / ||Q||_F   (per-step covariances, row-major)
//   id_r_err = ||R^ - R||_F / ||R||_F
//
// and, per element, the ratios Q^_ii / Q_ii and R^_jj / R_jj (bias shows as
// a ratio away from 1, which a norm hides).
//
// Usage:
//   const RunIdentification id = IdentifyInRun(sc, combo, data, run_seed);
//   if (id.failure.empty()) spec = id.spec;   // else the run is tune_failed
//
// WARNING: the fit is in-sample: the filter is scored on the data it was
// tuned on. With a handful of noise parameters and hundreds of measurements
// the optimism is small, but it is not zero.
#ifndef ESTLAB_STUDIES_RUN_STUDY_IDENTIFICATION_H_
#define ESTLAB_STUDIES_RUN_STUDY_IDENTIFICATION_H_

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "studies/config/study_config.h"

namespace estlab {

struct RunIdentification {
  bool attempted = false;  // the tuner ran (not when the run's truth failed)
  std::string failure;     // "" when the tuner gave a usable Q/R
  FilterSpec spec;         // the combo's spec with the identified Q/R
  double q_err = std::numeric_limits<double>::quiet_NaN();  // NaN: Q not tuned
  double r_err = std::numeric_limits<double>::quiet_NaN();  // NaN: R not tuned
  // Per element: identified over true variance, Q^_ii / Q_ii and R^_jj / R_jj
  // (NaN for a side not tuned or a zero true variance).
  std::vector<double> q_ratio, r_ratio;
  int iterations = 0;
  bool converged = false;
  bool at_bound = false;
  double wall_s = 0.0;
};

// Tunes `combo` (tune_per_run) on `data` alone; the tuner's multi-start
// seed comes from `seed`. Never throws for a failing tuner: failure says why.
RunIdentification IdentifyInRun(const ScenarioConfig& sc, const Combo& combo,
                                const FilterData& data, uint64_t seed);

// a_ii / b_ii of two n x n row-major matrices (NaN where b_ii = 0; all NaN
// when the sizes differ).
std::vector<double> DiagonalRatios(const std::vector<double>& a, const std::vector<double>& b);

// ||a - b||_F / ||b||_F; NaN when the sizes differ, a is empty or b is zero.
double RelativeFrobeniusError(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_STUDY_IDENTIFICATION_H_
