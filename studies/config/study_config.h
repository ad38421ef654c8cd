// Monte Carlo study configurations: a `studies/*.ini` file read with
// Boost.Program_options' config-file parser (unknown keys are errors), checked
// completely before any run starts. Errors are InputError("FILE:LINE: ...")
// naming the section and key.
//
// Usage:
//   StudyConfig config = LoadStudyConfig("studies/paper002_pendulum_mc.ini");
//   for (const ScenarioConfig& s : config.scenarios)
//     for (const Combo& c : s.combos) use(c.spec);   // one FilterSpec per filter x noise
//
// File format (full reference with examples: docs/studies.md):
//
//   # comments start with '#'
//   [study]
//   name = paper002_pendulum_mc      # required; [A-Za-z0-9_-]
//   description = ...                # optional free text
//   seed = 2002                      # study seed (default 1)
//   runs = 100                       # Monte Carlo runs per scenario (default 10)
//   jobs = 2                         # worker threads (default 1; --jobs overrides)
//   keep-runs = 0,1                  # runs whose time series are written (default 0)
//   step-metrics-every = 2           # per-step errors kept every k steps (default:
//                                    # at most ~100 points per run)
//
//   [scenario.NAME]                  # one or more; NAME = [A-Za-z0-9_-]+
//   model = pendulum                 # see `estlab list`
//   params = g=9.8,L=1               # parameter overrides (default: model defaults)
//   x0 = theta=0.7853981633974483    # truth initial state (unnamed states 0)
//   truth-x0 = fixed                 # fixed | sample (x0 + N(0, P0) per run)
//   dt = 0.0125                      # sampling interval
//   steps = 400                      # measurements per run (t = dt .. steps dt)
//   truth-integrator = cvodes        # cvodes (default) | rk4 | euler | semi-implicit-euler
//   truth-rtol = 1e-10               # CVODES tolerances (defaults 1e-10, 1e-12),
//   truth-atol = 1e-12               #   truth-method = bdf | adams | default,
//   truth-substeps = 1               #   fixed-step substeps per dt
//   process-noise = white-accel 1    # none (default) | diag v1,v2,.. | white-accel qc
//                                    #   | matrix a,b;c,d  (per-step covariance)
//   measurement = sin                # measurement name of the model (required), or
//                                    #   its sensor groups: position,encoder
//   sensor-rate = position=1         # sensor groups' rates in Hz (a whole number of
//   sensor-every = position=100      #   rows of dt), or every k-th row; the others
//                                    #   every row; missing between (docs/multirate.md)
//   meas-noise-var = 0.09            # one variance per output (default 0)
//   meas-noise = gaussian            # gaussian (default) | poisson: Poisson counts
//                                    #   with lambda = meas-noise-var (paper 004)
//   measure-at-t0 = false            # true: also a measurement at t = 0
//   prior-x0 = theta=0.785398        # filter prior mean (default: x0)
//   prior-p0-diag = 0.1,0.1          # or prior-p0 = a,b;c,d (default I)
//   input = 0                        # constant input (models with an input), or a
//                                    #   seeded signal sampled at the output times:
//                                    #   multisine(rms=, mean=, band=f1:f2, sines=, seed=)
//                                    #   | prbs(amplitude=, mean=, period=, order=, seed=)
//                                    #   | steps(u0, t1:u1, ...) | file(FILE[, column])
//                                    #   (src/sim/input_signal.h)
//
//   # Recorded runs instead of simulated ones (docs/studies.md "Recorded data"):
//   data = ../examples/data/multiarm/single/validate_*.csv   # glob or a, b list,
//                                    #   relative to this file; one run per file
//   tune-data = ../examples/data/multiarm/single/train_*.csv # what `tuned` fits on
//   column = z_theta=theta-pi        # ours=[a*]theirs[+-b], comma-separated
//   truth = none                     # none (default) | columns: state-named
//                                    #   columns are truth (RMSE, NEES)
//   burn-in = 50                     # rows of each run left out of the NIS and
//                                    #   the metrics that need no truth (default 0)
//   # With data, x0, truth-*, dt, steps, process-noise, meas-noise*, measure-at-t0,
//   # sensor-* are errors, and no noise section may use the oracle.
//
//   Any scenario value may list alternatives separated by '|', each with an
//   optional label:  x0 = pi4: theta=0.785398 | pi2: theta=1.570796
//   The scenario then expands to the product of all alternatives, named
//   NAME.label1.label2... (labels default to the value when it is a plain
//   word or number, else KEYi).
//
//   [filter.NAME]
//   kind = ukf                       # kf | ekf | iekf | ukf | ckf | ghkf | pf, or a smoother:
//                                    # rts | erts | iekf-rts | urts | ckf-rts | ghkf-rts | pf-bs
//                                    # (the filter forward, its smoother backward; pf-bs: 100
//                                    # trajectories; metrics are the smoothed estimates', the
//                                    # NLL/NIS columns empty: the likelihood is the filter's)
//   integrator = euler               # process model, and every other option of
//   alpha = 1e-3                     # `estlab filter` that is not about the data
//   particles = 1000                 # or the model: substeps, method, rtol, atol,
//   resample = residual              # max-steps, linearize-at, iterations, beta,
//                                    # kappa, gh-order, sigma-update, jitter, adapt,
//                                    # adapt-what, forgetting, window, ess-threshold
//   scenarios = a,b                  # optional: only these scenario sections
//
//   [noise.NAME]                     # Q/R settings, each filter runs with each
//   q = oracle                       # oracle = the truth's noise
//   r = oracle                       # (r = oracle-std: R = diag(sqrt(var)), paper
//                                    #  003's defect, for paper-faithful runs only)
//   role = hand                      # hand | tuned | oracle | other (default: inferred)
//   # or, as in `estlab filter`: q-diag | q (matrix a,b;c,d) | q-white-accel,
//   #   r-diag | r (matrix); exactly one Q and one R key.
//   scenarios = a,b                  # optional: only these scenario sections
//   filters = ekf,ukf                # optional: only these filters
//
//   [noise.tuned]                    # the likelihood tuner (ModelEntry::tune), once
//   q = tuned                        #   per scenario x filter before the runs, on
//   r = tuned                        #   tune-datasets trajectories with their own seeds
//   init-q-white-accel = 0.1         # start (also init-q-diag, init-q, init-r-diag,
//   init-r-diag = 0.05               #   init-r; default: the oracle); its shape is the
//   q-param = white-accel            #   parameterisation unless q-param / r-param say
//   tune-datasets = 3                #   diag | full | white-accel | scalar
//   tune-starts = 2                  # multi-start (default 1); tune-burn-in = 0
//   params = tuned L,b               # also fit these model parameters (from the
//   param-bounds = b=0:5             #   scenario's params), as estlab tune
//   param-prior = L=normal:1:0.1     #   --estimate-param; the filters run with them
//   tune-estimator = ml              # ml (default) | em | als (estlab tune --estimator;
//                                    #   em: at most tune-max-iterations, default 1000)
//   tune-max-iterations = 200        # optimiser / EM iterations
//   tune-tolerance = 1e-6            # em: stop at this relative NLL change (default 1e-9)
//   tune-solver = least-squares      # ml: lbfgs (default) | least-squares; every other
//                                    #   key of `estlab tune`'s tuner key table as
//                                    #   tune-<key> (tune-lags, tune-bound-width, ...)
//   tune-per-run = true              # every run fits its own Q/R on its own measurements
//                                    #   (default false: once before the runs); runs.csv
//                                    #   gets id_status, id_q_err, id_r_err, ...
//   init-scale = 0.01                # start from this multiple of the oracle (robustness)
//
//   [report]                         # optional: the paper's numbers and claims
//   paper = 002
//   title = EKF, UKF and PF on a pendulum with sin measurement
//   reference = SCEN/FILTER/NOISE METRIC mean=0.1721 var=0.1722 | Table 1
//   claim = rmse_theta: pf < ekf | PF has the lowest error
//   note = free text copied into report.md (repeatable)
//   tables = rmse,mse                # per-state tables per scenario (rmse, mse, mae)
//   overview = mae_theta,mae_theta1  # rows of the overview over scenarios
//
// WARNING: the seed of run i of scenario s is DeriveSeed({seed, s, i}) with s
// the index of the (expanded) scenario in file order: reordering scenario
// sections changes every seed. Filters and noise settings get their particle
// filter seed from the run seed and their names, so adding a filter does not
// change the others' results.
#ifndef ESTLAB_STUDIES_CONFIG_STUDY_CONFIG_H_
#define ESTLAB_STUDIES_CONFIG_STUDY_CONFIG_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "adaptive/tuner.h"
#include "src/options/column_map.h"
#include "src/registry/registry.h"
#include "src/run/filter_spec.h"

namespace estlab {

// The largest counts a study config accepts (ParseCount): runs per study,
// steps per run (and burn-in, step-metrics-every), truth substeps.
inline constexpr int kMaxRuns = 100000000;
inline constexpr int kMaxSteps = 100000000;
inline constexpr int kMaxSubsteps = 100000;
// What one simulated run may hold: its truth and its filter's records,
// about 8 (4 + 3n + 2n^2 + 3m + 2m^2) bytes a step for n states and m
// outputs (the model's widest measurement); `steps` beyond it is refused
// before anything runs (a run that ran out of memory was a failed run of a
// complete study).
inline constexpr double kMaxRunBytes = 4.0 * 1073741824.0;

struct StudySettings {
  std::string name;
  std::string description;
  uint64_t seed = 1;
  int runs = 10;
  int jobs = 1;
  std::vector<int> keep_runs = {0};
  int step_metrics_every = 0;  // 0 = automatic (about 100 points per run)
};

// One filter x noise combination of a scenario, with its spec ready to run
// (seed and prior time are set per run).
struct Combo {
  int filter = 0;  // index into StudyConfig::filters
  int noise = 0;   // index into StudyConfig::noises
  FilterSpec spec;
  // Noise `tuned`: before the runs, ModelEntry::tune fits Q and/or R (the
  // other is kFixed) from spec's values on `tune_datasets` trajectories of
  // the scenario simulated with their own seeds, and spec takes the result.
  bool tune = false;
  TunerOptions tuner;
  int tune_datasets = 0;
  std::string tune_failure;  // set by the runner when no tuned Q/R came out
  // tune-per-run = true: no tuning before the runs; every run fits its own
  // Q/R on its own measurements (the way a user tunes one recording) and
  // filters them with the result; runs.csv gets the identification columns
  // (IdentificationColumns, study_results.h).
  bool tune_per_run = false;
};

struct ScenarioConfig {
  std::string name;                                          // expanded name, e.g. "pend.pi4.q1e-4"
  std::string section;                                       // "scenario.pend"
  std::vector<std::pair<std::string, std::string>> choices;  // varied key -> label
  const ModelEntry* model = nullptr;
  std::string model_source;  // the model's name or file path (relative to the working folder)
  SimulationSpec truth;      // seed and (with truth-x0 = sample) x0 set per run
  bool sample_x0 = false;
  int steps = 0;
  bool measure_at_t0 = false;
  std::string truth_description;  // e.g. "cvodes rtol 1e-10, white-accel qc 1"
  // The truth's noise per step, row-major: the oracle Q and R.
  std::vector<double> oracle_q;
  bool oracle_q_white_accel = false;
  double oracle_qc = 0.0;
  std::vector<double> oracle_r;
  // meas-noise = poisson: the measurement noise is Poisson(lambda_j) counts
  // (mean and variance lambda_j = meas-noise-var) added to output j, as paper
  // 004 does; the simulator then draws none and the runner adds the counts.
  bool poisson_meas = false;
  std::vector<double> poisson_lambda;
  std::vector<double> prior_x0, prior_p0;
  std::vector<Combo> combos;  // filter-major, in file order

  // `data =`: recorded runs instead of simulated ones. Run i is the i-th
  // file (sorted glob expansion, in list order), read when the config is
  // loaded; `tuned` noise fits on the tune-data files. There is no oracle,
  // and truth only with `truth = columns` (recorded state-like columns are
  // often derived, not measured: they are not taken as truth by default).
  bool recorded = false;
  bool has_truth = true;  // simulated: always
  // `burn-in = N`: the first N rows of each recorded run are left out of
  // mean_nis, nis_in95 and the metrics that need no truth (study_metrics.h).
  int burn_in = 0;
  std::vector<ColumnMap> columns;
  std::vector<FilterData> data_runs, tune_runs;
};

// Runs of a scenario: its number of files when recorded, else `runs`.
inline int ScenarioRuns(const ScenarioConfig& sc, int runs) {
  return sc.recorded ? int(sc.data_runs.size()) : runs;
}

struct FilterConfig {
  std::string name;
  std::string kind;
  std::string description;             // "ukf alpha=1e-3 integrator=euler"
  std::vector<std::string> scenarios;  // empty = all
};

// A noise setting's part in the hand / auto / oracle comparison of
// report.md: kTuned (q or r = tuned), kOracle (q = r = oracle), kHand
// (anything else) or kOther (kept out of it); the `role` key overrides the
// inferred one.
enum class NoiseRole { kHand, kTuned, kOracle, kOther };

// "hand", "tuned", "oracle", "other": the `role` key's words, and the text
// report.md prints.
const char* NoiseRoleName(NoiseRole role);
// The role a word names; false for any other text.
bool ParseNoiseRole(const std::string& text, NoiseRole* role);

struct NoiseConfig {
  std::string name;
  std::string description;  // "Q oracle, R diag 0.09"
  NoiseRole role = NoiseRole::kHand;
  std::vector<std::string> scenarios;  // empty = all
  std::vector<std::string> filters;    // empty = all
  // tune-estimator (ml | em | als) and tune-per-run of a tuned setting.
  std::string estimator = "ml";
  bool per_run = false;
  std::string init_scale;  // the init-scale text, "" when not given
};

// A number from the paper, to be printed beside ours in report.md.
struct ReferenceValue {
  std::string scenario, filter, noise;                // '*' matches any
  std::string metric;                                 // a runs.csv column, e.g. rmse_theta
  std::vector<std::pair<std::string, double>> stats;  // mean, var, std, ...
  std::string source;
};

// "METRIC: A OP B": compares the mean of METRIC of filter A and filter B
// (FILTER or FILTER/NOISE) in every scenario (and noise setting) where both ran.
struct Claim {
  std::string metric;
  std::string a, b;
  std::string op;  // < <= > >=
  std::string text;
};

struct StudyConfig {
  std::string path;
  std::string text;  // the file as read
  StudySettings study;
  std::vector<ScenarioConfig> scenarios;
  std::vector<FilterConfig> filters;
  std::vector<NoiseConfig> noises;
  std::string paper, title;
  std::vector<std::string> notes;
  std::vector<ReferenceValue> references;
  std::vector<Claim> claims;
  // [report] tables = rmse,mse,mae: the per-state tables of each scenario
  // section (default rmse); overview = METRIC,...: the rows of the overview
  // table over scenarios (default the RMSE of each scenario's first state).
  std::vector<std::string> tables = {"rmse"};
  std::vector<std::string> overview;
  // Union of the scenarios' state names, in order of first appearance: the
  // rmse_/mae_ columns of runs.csv.
  std::vector<std::string> state_columns;
  // Union of the recorded scenarios' measured outputs: runs.csv gets the
  // columns that need no truth (nll_per_step, nis_lo95, nis_hi95 and
  // pred_rmse_OUTPUT) only when this is not empty, so that studies on
  // simulated data keep their files.
  std::vector<std::string> output_columns;
  // Some noise setting has tune-per-run = true: runs.csv and timing.csv get
  // the identification columns (study_results.h), the report its section.
  bool identification = false;
  // With identification: the union of the measured outputs of the scenarios
  // with tune-per-run settings (the id_r_OUTPUT columns of runs.csv).
  std::vector<std::string> identification_outputs;
};

// Reads and validates `path` completely (every FilterSpec is built and every
// filter is tried on a two-step dry run). Throws InputError "FILE:LINE: ...".
StudyConfig LoadStudyConfig(const std::string& path);
// Same from text (`path` is used in messages).
StudyConfig ParseStudyConfig(const std::string& text, const std::string& path);

// The truth's white-noise-acceleration covariance over one step dt,
// qc [[dt^3/3, dt^2/2], [dt^2/2, dt]] on the model's (position, rate) pairs
// (n x n, row-major; src/core/white_accel.h, the filters' q-white-accel).
std::vector<double> WhiteAccelCovariance(const ModelEntry& model, double qc, double dt);

// 64-bit FNV-1a of the text: identifies a configuration in results folders.
uint64_t ConfigHash(const std::string& text);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_CONFIG_STUDY_CONFIG_H_
