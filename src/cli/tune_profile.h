// `estlab tune --profile NAME[=LO:HI[:N]]`: the profile likelihood of one
// estimated model parameter. At each of N values p_i in [LO, HI] the
// parameter is fixed and every other estimated parameter, Q and R are
// re-optimised from the joint optimum:
//
//   PL(p_i) = min over the rest of NLL,   Delta_i = PL(p_i) - NLL(optimum)
//
// The likelihood-ratio 95 % interval is where Delta <= chi2_1(0.95) / 2 =
// 1.92 (read off the grid by linear interpolation; open at an end of the
// grid that stays below it). Defaults: the estimate +- 4 SE (x / 2 .. x 2
// when the SE is not finite), N = 21.
//
// Writes PREFIX.csv (NAME, nll, delta_nll, status) and the figure PREFIX.dat,
// .gp, .png, .svg.
#ifndef ESTLAB_SRC_CLI_TUNE_PROFILE_H_
#define ESTLAB_SRC_CLI_TUNE_PROFILE_H_

#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "src/registry/registry.h"

namespace estlab::cli {

struct ProfileRequest {
  std::string name;
  bool has_range = false;
  double lo = 0.0, hi = 0.0;
  int points = 21;
};
// At most this many grid points (each one a full re-fit).
inline constexpr long kMaxProfilePoints = 1000;

// Parses NAME[=LO:HI[:N]]; throws InputError naming the text (N in
// 3..kMaxProfilePoints).
ProfileRequest ParseProfileRequest(const std::string& text);

// Throws InputError when LO or HI violates the parameter's constraint
// (L > 0, b >= 0, ...), naming the value: checked before the fit, so that
// nothing is written.
void CheckProfileRequest(const ModelEntry& model, const ProfileRequest& request);

struct ProfileResult {
  std::string name;
  std::vector<double> values, nll;  // nll: +inf where the filter failed
  std::vector<std::string> status;
  double estimate = 0.0, nll_optimum = 0.0;
  double ci_lo = 0.0, ci_hi = 0.0;  // NaN: open at that end of the grid
};

// From best.tuned_spec (the joint optimum). Throws InputError when NAME is
// not among `options.estimate`.
ProfileResult ProfileLikelihood(const ModelEntry& model, const TunerOptions& options,
                                const std::vector<FilterData>& datasets, const TuneResult& best,
                                const ProfileRequest& request);

// PREFIX.csv and the figure; returns what it wrote (for the report), with
// *render_message set when gnuplot could not draw it.
std::vector<std::string> WriteProfile(const ProfileResult& profile, const std::string& prefix,
                                      std::string* render_message);

}  // namespace estlab::cli

#endif  // ESTLAB_SRC_CLI_TUNE_PROFILE_H_
