// Whether a fit may be called converged (TuneStatus), in plain types:
// compiled once, not per model. The optimiser's own word is one of four
// checks, in this order:
//
//   1. worse-than-start  NLL_tuned > NLL_initial (1 + 1e-12): the fit lost
//                        ground against the user's own guess;
//   2. no-convergence    the optimiser met no tolerance (iteration limit, line
//                        search); kept as it is, checks 3 and 4 skipped;
//   3. not-a-minimum     H, the Hessian of the NLL at the end point, restricted
//                        to the free parameters F (those not at a bound), in the
//                        relative units of adaptive/identifiability.h, has an
//                        eigenvalue lambda_min < -kNegativeRatio max|lambda|, and
//                        the NLL is lower by more than 1e-6 max(1, |NLL|) at a
//                        point theta +- t S v (t = 1e-3 .. 0.3, clamped into the
//                        bounds) along its eigenvector v, which the sentence
//                        names in parameter names ("0.71 log l1 - 0.7 log q_h1")
//                        with the lower NLL found. Where no lower point is found
//                        the negative curvature is the finite differences
//                        straddling a kink (max, min, abs in the model): the fit
//                        stays converged and a sentence in identifiability says
//                        the curvature there is unreliable;
//   4. at-bound          a parameter ended at a bound of its search box that is
//                        not its constraint (an upper bound; a lower bound of a
//                        parameter on its natural scale other than the 0 of
//                        >= 0). A log parameter's lower bound stands for its
//                        constraint's 0 (a variance or a > 0 parameter the data
//                        push to 0) and is flagged at_bound without failing;
// Between 2 and 3, unverified: H is not finite (the filter fails within one
// finite-difference step of the end point), so no minimum can be verified.
// (kNoConvergence, no tolerance met, is kept after check 1: the curvature of
// a point the optimiser did not finish with says nothing new.)
// A flat direction (|lambda| <= kNegativeRatio max|lambda|) is a valley of
// equal NLL, not a saddle: the fit is a minimum whose point the data do not
// pin down, said by the identifiability sentences and an infinite SE.
//
// Usage (TuneWith, after FinishTune):
//   ApplyVerdict(H, lower_is_constraint, lower, upper, nll, &result);
#ifndef ESTLAB_ADAPTIVE_TUNE_VERDICT_H_
#define ESTLAB_ADAPTIVE_TUNE_VERDICT_H_

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "adaptive/tuner.h"

namespace estlab {

// Relative eigenvalue below which curvature counts as downwards. The
// Hessian is central differences of the exact gradient (relative error about
// hessian_step^2), so a flat direction reads as +-1e-8 relative at most.
inline constexpr double kNegativeRatio = 1e-6;

// -1 when theta ends at or near its lower bound, +1 near its upper, else 0:
// within 0.1 on the log scale (a factor e^0.1 = 1.105 on the natural scale),
// within 1e-3 of the box width on the natural scale. An optimiser stopping
// by its tolerances lands short of a bound the likelihood pushes against
// (log q ending at -38.37 against -38.42), so "on the bound" alone misses it.
int NearBound(double theta, double lower, double upper, bool is_log);

// The smallest eigenvalue of S H S on the free parameters (S: the relative
// units of adaptive/identifiability.h, FisherScale) and its eigenvector
// (zero on the others); false when no parameter is free or H is not finite.
bool FreeCurvature(const Eigen::MatrixXd& H, const Eigen::VectorXd& scale,
                   const std::vector<bool>& free, double* lambda_min, double* lambda_max_abs,
                   Eigen::VectorXd* direction);

// Sets result->status and result->message from result (theta, at_bound,
// nll_initial, nll_tuned, status as the optimiser left it: kConverged or
// kNoConvergence) and H (empty: not computed, check 2 skipped).
// lower_is_constraint[i]: theta_i's lower bound stands for its constraint;
// nll(theta): the NLL at an admissible theta (+inf where the filter fails).
using NllAt = std::function<double(const std::vector<double>&)>;
void ApplyVerdict(const Eigen::MatrixXd& H, const std::vector<bool>& lower_is_constraint,
                  const std::vector<double>& lower, const std::vector<double>& upper,
                  const NllAt& nll, TuneResult* result);

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_TUNE_VERDICT_H_
