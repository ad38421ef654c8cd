// The estimators of `estlab tune` and of a study's `tune-estimator`, as one
// table, the way src/run/filter_kinds.h registers the filter kinds. Each row
// says the estimator's name, what it estimates, the filters it accepts, its
// own settings keys (src/options/tuner_settings.h) and its defaults; the
// command line, the study configuration, the settings' checks and `tune
// --help` all read them from here, so no list of estimator names is written
// twice. A light header: no templates, compiled once.
//
//   ml            prediction-error maximum likelihood: the innovation NLL of
//                 adaptive/likelihood.h minimised by a solver (MlSolver):
//                   lbfgs          projected L-BFGS (adaptive/bounded_lbfgs.h)
//                   least-squares  Levenberg-Marquardt on whitened residuals
//                 adaptive/ml.h
//   em            expectation-maximisation, the RTS smoother as E-step
//                 (adaptive/em.h)
//   als           autocovariance least squares on a suboptimal filter's
//                 innovations (adaptive/als.h)
//   output-error  free simulation against the measurements, least squares
//                 (studies/run/output_error.h; no filter, not a TuneModel run)
//
// Adding an estimator "foo" (a dry run, the files it touches):
//   1. adaptive/foo.h: RunFoo(const Objective<Model, Meas>&, const
//      TuneProblem&, TuneResult*) (adaptive/tune_problem.h), filling the one
//      TuneResult; included by adaptive/tuner_impl.h.
//   2. Its row: the enum value and the row of kEstimators (estimators.cpp),
//      and the case in TuneWith's switch (tuner_impl.h; the switch is
//      exhaustive: a missing case does not compile under -Werror).
//   3. Its test: tests/adaptive/foo_test.cpp against an independent reference.
// Its keys, if any, are rows of the tuner key table (tuner_settings.cpp)
// with `only = {Estimator::kFoo}`.
#ifndef ESTLAB_ADAPTIVE_ESTIMATORS_H_
#define ESTLAB_ADAPTIVE_ESTIMATORS_H_

#include <string>
#include <vector>

#include "src/run/filter_kinds.h"
#include "src/run/filter_spec.h"

namespace estlab {

enum class Estimator { kMl, kEm, kAls, kOutputError };
enum class MlSolver { kLbfgs, kLeastSquares };

struct EstimatorInfo {
  Estimator id;
  const char* name;     // as the user writes it
  const char* summary;  // one line for --help and the docs
  // Defaults: iterations of its optimiser (or EM iterations).
  int default_max_iterations;
  // What it estimates: Q and R; physical parameters; initial states.
  bool noise, params, x0;
  // Whether it takes more than one start, and a burn-in.
  bool multi_start, burn_in;
  // Runs through ModelEntry::tune (needs the model's compiled tuner; output
  // error simulates and needs none).
  bool tuner;
  // Offered by studies (tune-estimator = NAME).
  bool in_studies;
  // The filters it runs: accepts(spec) and the same in words.
  bool (*accepts)(const FilterSpec& spec);
  const char* filters;
};

// Every estimator, in help order.
const std::vector<EstimatorInfo>& Estimators();
const EstimatorInfo& InfoOf(Estimator estimator);
const char* EstimatorName(Estimator estimator);
// The estimator called `name`; throws InputError "KEY: expected ml, em,
// als or output-error, got 'NAME'" (only those offered by studies when
// studies_only).
Estimator ParseEstimator(const std::string& name, const std::string& key,
                         bool studies_only = false);
// "ml | em | als | output-error" (or "ml, em or als" with joiner ", " and
// last " or "), the studies' only when studies_only.
std::string EstimatorNames(const std::string& joiner, const std::string& last,
                           bool studies_only = false);

// lbfgs | least-squares; throws InputError naming `key`.
MlSolver ParseMlSolver(const std::string& name, const std::string& key);
const char* MlSolverName(MlSolver solver);

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_ESTIMATORS_H_
