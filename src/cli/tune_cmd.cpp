// estlab tune: tune Q and R by maximum innovation likelihood (Ceres), then
// optionally compare initial, tuned and true noise on a validation file.
#include <algorithm>
#include <boost/program_options.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <unistd.h>

#include "adaptive/initial_states.h"
#include "src/cli/commands.h"
#include "src/cli/plot_run.h"
#include "src/cli/tune_output_error.h"
#include "src/cli/tune_profile.h"
#include "src/cli/tune_validate.h"
#include "src/core/parse.h"
#include "src/io/json.h"
#include "src/io/output_file.h"
#include "src/options/estimate_flags.h"
#include "src/options/filter_flags.h"
#include "src/options/truth_flags.h"
#include "src/registry/registry.h"
#include "studies/report/run_figures.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {

constexpr const char* kExamples = R"(Examples:
  # Simulate training and validation data (white-noise acceleration is the
  # filter's model; the simulator adds diagonal process noise per step):
  estlab simulate --model pendulum --x0 theta=0.785398 --t-end 20 --dt 0.01 --integrator rk4 \
      --process-noise-var 1e-6,1e-4 --measure sin --meas-noise-var 0.01 --seed 1 --out train.csv
  estlab simulate --model pendulum --x0 theta=0.785398 --t-end 20 --dt 0.01 --integrator rk4 \
      --process-noise-var 1e-6,1e-4 --measure sin --meas-noise-var 0.01 --seed 2 --out valid.csv
  # Tune a diagonal Q and R of the EKF from guesses 100x off, validate:
  estlab tune --model pendulum --measure sin --filter ekf --integrator rk4 --data train.csv \
      --x0 theta=0.785398 --p0-diag 1e-4,1e-4 --init-q-diag 1e-4,1e-2 --init-r-diag 1 \
      --validate valid.csv --out tuned.ini
  # then filter with the tuned noise:
  estlab filter --model pendulum --measure sin --filter ekf --integrator rk4 --data valid.csv \
      --x0 theta=0.785398 --p0-diag 1e-4,1e-4 --config tuned.ini --out est.csv
  # (--config tuned.ini also works here: its Q/R become the initial values.)
  # White-noise-acceleration qc and a scalar R, UKF, 4 starts, least squares, JSON:
  estlab tune --model double-pendulum --measure angles --filter ukf --alpha 1 --data a.csv \
      --data b.csv --x0 theta1=0.785398,theta2=0.523599 --init-q-white-accel 0.1 \
      --init-r-scalar 0.01 --starts 4 --burn-in 20 --solver least-squares --json
  # The same by expectation-maximisation (the EKF's RTS smoother as E-step;
  # the report adds the likelihood tuner's NLL from EM's solution), and by
  # autocovariance least squares on 15 lags of the innovations:
  estlab tune --model pendulum --measure sin --filter ekf --integrator rk4 --data train.csv \
      --x0 theta=0.785398 --p0-diag 1e-4,1e-4 --init-q-diag 1e-4,1e-2 --init-r-diag 1 \
      --estimator em --tolerance 1e-9 --out tuned_em.ini
  estlab tune --model pendulum --measure sin --filter ekf --integrator rk4 --data train.csv \
      --x0 theta=0.785398 --p0-diag 1e-4,1e-4 --init-q-diag 1e-4,1e-2 --init-r-diag 1 \
      --estimator als --lags 15 --burn-in 100
  # Estimate the length and damping with Q and R (prediction-error ML), the
  # damping kept in [0, 5], its profile likelihood drawn (profile_L.png), and
  # write them for 'estlab filter --config':
  estlab tune --model pendulum --measure angle --filter ekf --integrator rk4 --data train.csv \
      --x0 theta=0.785398 --p0-diag 1e-4,1e-4 --param L=0.8,b=0.1 --estimate-param L,b \
      --param-bounds b=0:5 --init-q-white-accel 1e-3 --init-r-diag 1e-3 --profile L \
      --out tuned.ini
  # Real recordings: several pieces, each from its own first sample, angles
  # from upright shifted to estlab's pendulum, two held-out pieces:
  estlab tune --model pendulum --measure angle --filter ekf --integrator rk4 \
      --data train_1.csv --data train_2.csv --column z_theta=theta-pi --x0 first-sample \
      --p0-diag 0.01,100 --burn-in 50 --param L=0.15,b=0.05 --estimate-param L,b \
      --init-q-white-accel 1 --init-r-diag 1e-6 --validate validate_1.csv --validate validate_2.csv

Physical parameters (--estimate-param): the named model parameters join
Q and R in theta, from their --param values: log p for a parameter that must
be > 0, p itself otherwise (a >= 0 one gets the bound 0). --param-bounds
gives natural-scale bounds (else initial value * e^+-bound-width on the log
scale), --param-prior adds 1/2 ((p - mean) / sd)^2 to the NLL. Gradients are
exact (AD through the filter and the fixed-step integrator; with cvodes,
CVODES forward sensitivities, as for Q and R). The report gives each estimate with its
standard error from the observed Fisher information (the Hessian of the NLL),
and names every direction that the data do not pin down ("g and L are not
separately identifiable: the data pin down only g/L = ..."). The kf is not
supported (it linearises once, at the nominal parameters); the model's
parameters must be generic over the scalar (built-in: pendulum; every model
file).

Initial states (--estimate-x0 h1,h2): with ml the named entries of the
filter's prior mean x0 join theta (natural scale, unbounded, from --x0; the
prior covariance stays --p0-diag or --p0: give a small one when the records start at
a fixed unknown state), with exact gradients through the whole run; with
output-error they are where the free simulation starts. One x0 is shared by
every --data file, or with --x0-per-file each file has its own while the
parameters and the noise are shared. The report, --json ("tuned": {"x0":
...}, "x0_std_errors", or "x0_per_file") and tuned.ini (x0 and p0 lines that
simulate, filter and smooth --config read) give x0 with standard errors.
With em, x0 is the prior mean too, re-estimated in each M-step from the
smoothed first row (the prior must sit at the first row); ALS does not
estimate x0.

Tuning: minimises NLL = 1/2 sum_k [log det S_k + nu_k^T S_k^-1 nu_k + m log 2 pi]
over the innovations nu_k (covariance S_k) of every dataset after --burn-in
updates. Parameters are log-variances (diag, scalar, white-accel's log qc) or
a log-Cholesky factor (full); --q-param/--r-param default to the shape of the
--init-* option given (q-white-accel -> white-accel, q -> full, q-scalar ->
scalar, q-diag -> diag). 'fixed' keeps the initial matrix. The KF, EKF, IEKF,
UKF, CKF and GHKF are supported (not the PF). Gradients are exact (automatic
differentiation through the filter) with a fixed-step --integrator; with
cvodes, CVODES forward sensitivities in theta of the state (and, for the
EKF, of the flow Jacobian's variational system) carry the same derivatives,
with CVODES run at rtol <= 1e-10, atol <= 1e-12.

Estimators: ml (default) minimises that NLL (projected L-BFGS, or Ceres'
Levenberg-Marquardt with --solver least-squares). em alternates the filter's
smoother (kf -> RTS, ekf -> ERTS, ukf/ckf/ghkf -> sigma-point RTS)
with the closed-form maximiser of Q and R for each --q-param/--r-param; exact
for the kf, where the NLL never rises from one iteration to the next, and an
approximation otherwise (the report counts rises and gives the ml NLL reached
from EM's solution). It stops when the relative NLL change is at most
--tolerance (1e-9) or after --max-iterations (1000); progress per iteration
on a terminal. als (Odelson, Rajamani & Rawlings 2006) runs the filter once
with the initial Q and R (a suboptimal gain), and fits Q and R by least
squares to the innovation autocovariances at lags 0..--lags-1 after
--burn-in updates; kf and ekf (linearised along its own estimates), every
row measured. Its report says which elements of Q and R the lags identify;
it has no standard errors. em and als take one start and no --estimate-param;
em takes no --burn-in. A key of another estimator (--lags with em, --solver
with als, ...) is an error, never ignored. Every tuner key above may also be
a line of a --config file (estimator = em, starts = 4, ...; the command line
wins) and, as tune-<key> (q-param, r-param as they are), of a study's
[noise.*] section. --form is the old name of --solver.

Bounds: each log parameter within its initial value +- --bound-width (20),
or within --log-lower .. --log-upper (one value for all, or one per
parameter). No point outside the bounds or a parameter's constraint is ever
evaluated (a projected L-BFGS; least squares: Ceres' bounded blocks).
Multi-start: start 1 is the initial guess, the others a Latin hypercube
drawn from --seed: Q's and R's log parameters within +- --start-spread (2)
of it, each --estimate-param parameter within its --param-bounds (log scale
for a > 0 one) or, without both bounds, within +- --start-spread on the log
scale (> 0) or +- max(|p|, 1e-3) * spread / 2. --jobs N runs the starts on
N threads; the result is the same for any N. Every start is reported: its
NLL at its point ("nll_start"; start 1's is nll_initial), after the
common-scale search that shifts Q and R by e^s before the optimiser starts
("scale_shift", "nll_scaled"), and at its end. Starts are numbered from 1
everywhere: the text's "start N", the JSON "message" and "best_start"; the
JSON "starts" array lists them in that order.

Status: 'converged' only when the optimiser met a tolerance, the tuned NLL
is no worse than the initial guess's, the Hessian of the NLL has no
negative curvature on the parameters not at a bound, and no parameter ended
against its search box. Otherwise the status says what it is:
not-a-minimum (the direction named in parameter names), worse-than-start,
at-bound (a search-box bound, not a constraint: a variance or a > 0
parameter pushed to its lower log bound, or a >= 0 parameter at 0, is a
constrained minimum and stays converged, flagged 'at a bound'),
no-convergence (iteration limit, line search), unverified (the Hessian is
not finite at the end: the filter fails within a finite-difference step of
it) or all-starts-diverged. Each
prints the report, a sentence on stderr and exits 1; --out is written only
with --keep-best, and then says in the file that it is not a verified fit.
The convergence trace ("trace" in the JSON, the progress line and the
--plot figure) is the NLL of every accepted iterate, each an admissible
point.

Output: a table (or --json) with the tuned Q and R, the NLL before and after,
the optimiser's termination, and the standard error of every log parameter from the
curvature of the NLL; a parameter with SE > 1 is 'poorly identified by this
data'. --out writes the tuned noise as 'q-diag = ...' / 'q = ...' /
'q-white-accel = ...' and 'r-diag = ...' / 'r = ...' lines, the option names of
'estlab filter', and 'param = NAME=VALUE' for every estimated parameter.
--validate (repeatable) runs the filter on held-out files with the initial,
the tuned and (from <file>.json written by 'estlab simulate', or
--true-q-diag/--true-r-diag) the true noise, and reports per file the NLL per
step, the mean NIS with its 95 % bounds and the one-step-ahead prediction
RMSE of every output (after --burn-in), and RMSE and NEES against truth
columns when the file has them. --x0 first-sample gives every --data and
--validate file its own prior mean: its first measured value of each state
an output of the same name measures (the others 0); the validation report
gives each file's prior. Truth columns are read as 'estlab filter' reads them
(the file's .json from 'estlab simulate', or --truth; --no-truth). A
parameter 'at a bound' ended within 0.1 (log scale) of its search box: the
data push it further, so its estimate and SE are the box's.

Progress: on a terminal, stderr shows one line per optimiser iteration
(start k/N, iteration, NLL or least-squares cost, its change, elapsed time);
piped or redirected it is silent, and stdout holds only the report (--json:
only the JSON). --plot DIR draws the tuned filter on the first --validate
file (else the first --data file) as 'estlab filter --plot' does, plus the
tuner's objective by iteration (convergence) and the tuned model's free
simulation on that file with its errors (free-simulation: no filter, from the
run's prior mean, as the validation's whole-file RMSE).
)";

// --init-q-scalar s -> init-q-diag "s,s,..." in the settings (the user's own
// text repeated, so BuildFilterSpec reads exactly what was written).
void ExpandScalarOption(const po::variables_map& vm, const std::string& scalar_opt,
                        const std::string& diag_opt, const std::vector<std::string>& others, int n,
                        FilterSettings* settings) {
  if (!vm.count(scalar_opt)) return;
  for (const auto& o : others) {
    if (settings->Given(o)) throw InputError("give only one of --" + scalar_opt + " and --" + o);
  }
  const std::string text = vm[scalar_opt].as<std::string>();
  const double s = ParseNumber(text, "--" + scalar_opt);
  if (!(s > 0)) throw InputError("--" + scalar_opt + " must be > 0");
  std::string diag;
  for (int i = 0; i < n; ++i) diag += (i ? "," : "") + text;
  settings->Set(diag_opt, diag);
}

// The key the initial guess of Q ("q") or R ("r") came from, without "init-"
// (NoiseParamOfGuess: its shape is the default parameterisation); "" when none.
std::string GuessKey(const po::variables_map& vm, const std::string& which) {
  for (const char* tail : {"-white-accel", "-scalar", "", "-diag"})
    if (vm.count("init-" + which + std::string(tail))) return which + std::string(tail);
  return "";
}

// A full R's covariance of two outputs that no row observes together
// (sensors at their own rates, a row per sensor) is a parameter the
// likelihood does not depend on: a note before the fit, naming the pairs.
void NoteNeverCoObserved(const TunerOptions& options, const MeasurementDesc& meas,
                         const std::vector<FilterData>& datasets) {
  const int m = int(meas.outputs.size());
  std::vector<bool> full(size_t(m),
                         options.r_param_groups.empty() && options.r_param == NoiseParam::kFull);
  std::vector<int> block(size_t(m), 0);  // full blocks of groups: pairs within one
  for (size_t g = 0; g < meas.groups.size(); ++g) {
    const OutputGroup& group = meas.groups[g];
    for (int j = group.first; j < group.first + group.count; ++j) block[size_t(j)] = int(g);
    for (const auto& [name, kind] : options.r_param_groups)
      if (name == group.name)
        for (int j = group.first; j < group.first + group.count; ++j)
          full[size_t(j)] = kind == NoiseParam::kFull;
  }
  std::vector<bool> together(size_t(m * m), false);
  for (const FilterData& d : datasets)
    for (size_t k = 0; k < d.t.size(); ++k)
      for (int a = 0; a < m; ++a)
        for (int b = a + 1; b < m; ++b)
          if (std::isfinite(d.z[k * size_t(m) + size_t(a)]) &&
              std::isfinite(d.z[k * size_t(m) + size_t(b)]))
            together[size_t(a * m + b)] = true;
  std::string pairs;
  for (int a = 0; a < m; ++a)
    for (int b = a + 1; b < m; ++b) {
      const bool tuned = full[size_t(a)] && full[size_t(b)] &&
                         (options.r_param_groups.empty() || block[size_t(a)] == block[size_t(b)]);
      if (!tuned || together[size_t(a * m + b)]) continue;
      pairs += pairs.empty() ? "R(" : ", R(";
      pairs += meas.outputs[size_t(a)];
      pairs += ',';
      pairs += meas.outputs[size_t(b)];
      pairs += ')';
    }
  if (pairs.empty()) return;
  std::cerr << "estlab: note: no row observes both outputs of " << pairs
            << ": the likelihood does not depend on their covariance (docs/multirate.md); tune "
               "them diagonal (--r-param diag, or diag for their sensor groups)\n";
}

bool IsDiagonal(const std::vector<double>& a, int n) {
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (i != j && a[i * n + j] != 0.0) return false;
  return true;
}

std::string DiagText(const std::vector<double>& a, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) {
    if (i) out += ',';
    out += FormatDouble(a[i * n + i]);
  }
  return out;
}

std::string MatrixText(const std::vector<double>& a, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) {
    if (i) out += ";";
    for (int j = 0; j < n; ++j) {
      if (j) out += ',';
      out += FormatDouble(a[i * n + j]);
    }
  }
  return out;
}

// The `estlab filter` option lines of a tuned covariance.
std::string IniLine(const std::string& symbol, NoiseParam param, bool white_accel, double qc,
                    const std::vector<double>& a, int n) {
  if (white_accel) return symbol + "-white-accel = " + FormatDouble(qc) + "\n";
  const bool diag = param == NoiseParam::kDiag || param == NoiseParam::kScalar ||
                    (param == NoiseParam::kFixed && IsDiagonal(a, n));
  if (diag) return symbol + "-diag = " + DiagText(a, n) + "\n";
  return symbol + " = " + MatrixText(a, n) + "\n";
}

// With an estimated x0, the prior covariance it was fitted with (else a
// --config reader would pair the x0 with its own default P0): "" otherwise.
std::string X0PriorLine(const FilterSpec& spec, size_t x0_rows, int n) {
  if (x0_rows == 0) return "";
  return IniLine("p0", NoiseParam::kFixed, false, 0.0, spec.p0, n);
}

// The process model the tuned Q is per step of (a Q tuned for RK4 at this
// dt is not the Q of Euler, nor of the other input hold): `--config`
// readers take it too, and their command line wins.
std::string ProcessModelLines(const ModelEntry& model, const FilterSpec& spec) {
  const TransitionOptions& t = spec.transition;
  std::string out = "integrator = ";
  out += IntegratorName(t.integrator);
  out += "\n";
  if (t.integrator == Integrator::kCvodes) {
    out += "method = ";
    out += t.method == CvodesMethod::kBdf     ? "bdf"
           : t.method == CvodesMethod::kAdams ? "adams"
                                              : "default";
    out += "\nrtol = " + FormatDouble(t.rtol) + "\natol = " + FormatDouble(t.atol) + "\n";
  } else {
    out += "substeps = " + std::to_string(t.substeps) + "\n";
  }
  if (model.has_input()) {
    out += "input-hold = ";
    out += InputHoldName(t.input_hold);
    out += "\n";
  }
  return out;
}

void WriteMatrix(JsonWriter* j, const std::vector<double>& a, int n) {
  j->BeginArray();
  for (int i = 0; i < n; ++i)
    j->Value(std::vector<double>(a.begin() + i * n, a.begin() + (i + 1) * n));
  j->EndArray();
}

// {"qc": ..} | {"diag": [..]} | {"scalar": ..} | {"matrix": [[..]]}, plus "param".
void WriteTuned(JsonWriter* j, NoiseParam param, bool white_accel, double qc,
                const std::vector<double>& a, int n,
                const std::vector<std::pair<std::string, NoiseParam>>& groups = {}) {
  j->BeginObject().Key("param").Value(groups.empty() ? NoiseParamName(param) : "per-group");
  if (!groups.empty()) {
    j->Key("groups").BeginObject();
    for (const auto& [name, kind] : groups) j->Key(name).Value(NoiseParamName(kind));
    j->EndObject();
    param = NoiseParam::kFixed;  // diag when diagonal, else the matrix
  }
  if (white_accel) {
    j->Key("qc").Value(qc);
  } else if (param == NoiseParam::kScalar) {
    j->Key("scalar").Value(a[0]);
  } else if (param == NoiseParam::kDiag || (param == NoiseParam::kFixed && IsDiagonal(a, n))) {
    std::vector<double> d;
    for (int i = 0; i < n; ++i) d.push_back(a[i * n + i]);
    j->Key("diag").Value(d);
  } else {
    j->Key("matrix");
    WriteMatrix(j, a, n);
  }
  j->EndObject();
}

// The estimated physical parameters, on their natural scale, and what the
// observed Fisher information says about them.
void PrintPhysical(const TuneResult& r) {
  if (!r.param_names.empty()) {
    std::cout << "\n  model parameter               initial     estimate         SE\n";
    const size_t first = r.names.size() - r.param_names.size();
    for (size_t j = 0; j < r.param_names.size(); ++j) {
      std::cout << "  " << std::left << std::setw(26) << r.param_names[j] << std::right
                << std::setw(12) << r.param_initial[j] << " " << std::setw(12) << r.param_values[j]
                << " " << std::setw(10) << r.param_std_errors[j]
                << (r.at_bound[first + j] ? "  at a bound" : "") << "\n";
    }
  }
  for (const std::string& s : r.identifiability) std::cout << "  note: " << s << "\n";
}

// Every start: where it began (the user's point, then after the common-scale
// shift), where it ended, and how.
void PrintStarts(const TuneResult& r) {
  std::cout << "starts        NLL at start -> scaled -> end (iterations, optimiser)\n";
  for (size_t s = 0; s < r.starts.size(); ++s) {
    const TuneStart& st = r.starts[s];
    std::cout << "  " << std::setw(3) << s + 1 << (int(s) == r.best_start ? "*" : " ") << " "
              << std::setw(12) << st.nll_start << " -> " << std::setw(12) << st.nll_scaled << " -> "
              << std::setw(12) << st.nll_end << "  (" << st.iterations << ", "
              << (st.ok ? (st.converged ? "converged" : "not converged") : "failed") << ")\n";
  }
}

// The tuned initial states, as every estimator reports them (tune_x0.h).
X0Report TunedX0(const ModelEntry& model, const TuneResult& r,
                 const std::vector<FilterData>& datasets) {
  return MakeX0Report(model.states, r.x0_names, r.x0_initial, r.x0, r.x0_std_errors, datasets);
}

void PrintHuman(const ModelEntry& model, const FilterSpec& spec, const TuneResult& r,
                const std::vector<FilterData>& datasets, const std::vector<Validation>& validations,
                double horizon, const std::string& out_path) {
  const int n = int(model.states.size());
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  std::cout << std::setprecision(6);
  std::cout << "model         " << model.name << ", measurement " << spec.measurement << ", filter "
            << FilterKindName(spec.kind()) << (spec.iterated() ? " (iterated)" : "")
            << "\ndata          " << datasets.size() << " dataset(s), " << r.updates
            << " innovations after burn-in\nestimator     " << r.estimator
            << (r.solver.empty() ? "" : " (" + r.solver + ")") << ", " << r.starts.size()
            << " start(s), status " << TuneStatusName(r.status) << "\n";
  if (!r.IsSolutionUsable()) {
    std::cout << "              " << r.message << "\n";
    return;
  }
  if (r.estimator == std::string("als")) {
    std::cout << "ALS           " << r.termination << " (" << r.iterations << " iterations)\n";
  } else if (r.estimator == std::string("em")) {
    std::cout << "EM            " << r.termination << " (" << r.iterations << " iterations"
              << (r.nll_increases ? ", NLL rose at " + std::to_string(r.nll_increases) : "")
              << ")\n";
  } else {
    std::cout << "optimiser     " << r.termination << " (" << r.iterations << " iterations, start "
              << r.best_start + 1 << ")\n";
  }
  std::cout << "NLL           initial " << r.nll_initial << "   tuned " << r.nll_tuned << "\n";
  if (!r.IsConverged()) std::cout << "NOT CONVERGED " << r.message << "\n";
  if (r.starts.size() > 1) PrintStarts(r);
  if (!std::isnan(r.nll_ml_from_em))
    std::cout << "              ml from EM's solution " << r.nll_ml_from_em << " (EM - ml "
              << r.nll_tuned - r.nll_ml_from_em << ")\n";
  std::cout << "\n";
  std::cout << "  parameter                     initial        tuned    SE(log)\n";
  for (size_t i = 0; i < r.names.size(); ++i) {
    std::cout << "  " << std::left << std::setw(26) << r.names[i] << std::right << std::setw(12)
              << r.theta_initial[i] << " " << std::setw(12) << r.theta[i] << " " << std::setw(10)
              << r.std_errors[i]
              << (r.poorly_identified[i] ? "  poorly identified by this data" : "")
              << (r.at_bound[i] ? "  at a bound" : "") << "\n";
  }
  if (std::find(r.at_bound.begin(), r.at_bound.end(), true) != r.at_bound.end())
    std::cout << "  at a bound: within 0.1 (log scale) of the search box (initial +- "
                 "--bound-width, --log-lower/--log-upper, --param-bounds). The data push it "
                 "further, so the estimate and its SE are the box's: widen the box, or fix the "
                 "parameter (--q-param/--r-param fixed, or leave it out of --estimate-param)\n";
  PrintPhysical(r);
  PrintX0(TunedX0(model, r, datasets));
  std::cout << "\ntuned Q"
            << (r.q_white_accel ? " (qc = " + FormatNumber(r.qc) +
                                      ", shown at dt = " + FormatNumber(r.dt_ref) + ")"
                                : "")
            << "\n";
  for (int i = 0; i < n; ++i) {
    std::cout << "  ";
    for (int j = 0; j < n; ++j) std::cout << std::setw(13) << r.q[i * n + j];
    std::cout << "\n";
  }
  std::cout << "tuned R\n";
  for (int i = 0; i < m; ++i) {
    std::cout << "  ";
    for (int j = 0; j < m; ++j) std::cout << std::setw(13) << r.r[i * m + j];
    std::cout << "\n";
  }
  std::cout << "wall time     " << r.wall_s << " s\n";
  const std::vector<std::string>& outputs = model.FindMeasurement(spec.measurement).outputs;
  for (const Validation& v : validations) PrintValidation(v, outputs, horizon);
  if (!out_path.empty()) std::cout << "wrote         " << out_path << "\n";
}

void WriteProfileJson(JsonWriter* j, const ProfileResult& p, const std::vector<std::string>& files);

std::string ResultJson(const ModelEntry& model, const FilterSpec& spec, const TuneResult& r,
                       const std::vector<FilterData>& datasets,
                       const std::vector<Validation>& validations, const std::string& out_path,
                       const std::optional<ProfileResult>& profile,
                       const std::vector<std::string>& profile_files) {
  const int n = int(model.states.size());
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  JsonWriter j;
  j.BeginObject().Key("model").Value(model.name).Key("measurement").Value(spec.measurement);
  j.Key("filter").Value(FilterKindName(spec.kind())).Key("estimator").Value(r.estimator);
  j.Key("solver").Value(r.solver);
  // "form": the solver of ml, else the estimator (the key before issue 33).
  j.Key("form").Value(r.solver.empty() ? r.estimator : r.solver);
  j.Key("status").Value(TuneStatusName(r.status)).Key("message").Value(r.message);
  if (r.IsSolutionUsable()) {
    j.Key("tuned").BeginObject().Key("q");
    WriteTuned(&j, r.q_param, r.q_white_accel, r.qc, r.q, n);
    j.Key("r");
    WriteTuned(&j, r.r_param, false, 0.0, r.r, m, r.r_param_groups);
    j.Key("params").Object(r.param_names, r.param_values);
    const X0Report x0 = TunedX0(model, r, datasets);
    WriteTunedX0Json(&j, x0);
    j.EndObject();
    j.Key("std_errors").Object(r.param_names, r.param_std_errors);
    WriteX0DetailJson(&j, x0);
    j.Key("params_initial").Object(r.param_names, r.param_initial);
    j.Key("q_matrix");
    WriteMatrix(&j, r.q, n);
    if (r.q_white_accel) j.Key("q_matrix_dt").Value(r.dt_ref);
    j.Key("r_matrix");
    WriteMatrix(&j, r.r, m);
  }
  j.Key("parameters").Value(r.names);
  j.Key("theta_initial").Value(r.theta_initial).Key("theta").Value(r.theta);
  j.Key("std_errors_log").Value(r.std_errors);
  std::vector<std::string> poor;
  for (size_t i = 0; i < r.poorly_identified.size(); ++i)
    if (r.poorly_identified[i]) poor.push_back(r.names[i]);
  j.Key("poorly_identified").Value(poor);
  std::vector<std::string> at_bound;
  for (size_t i = 0; i < r.at_bound.size(); ++i)
    if (r.at_bound[i]) at_bound.push_back(r.names[i]);
  j.Key("at_bound").Value(at_bound);
  j.Key("correlation").Value(r.correlation);
  j.Key("fisher_eigenvalues").Value(r.fisher_eigenvalues);
  j.Key("identifiability").Value(r.identifiability);
  j.Key("nll_initial").Value(r.nll_initial).Key("nll_tuned").Value(r.nll_tuned);
  j.Key("updates").Value(r.updates);
  j.Key("iterations").Value(r.iterations).Key("termination").Value(r.termination);
  j.Key("trace").Value(r.trace);
  j.Key("wall_s").Value(r.wall_s);
  if (r.estimator == std::string("em")) {
    j.Key("em").BeginObject().Key("nll_history").Value(r.nll_history);
    j.Key("iteration_wall_s").Value(r.iteration_wall_s).Key("nll_increases").Value(r.nll_increases);
    j.Key("nll_ml_from_em").Value(r.nll_ml_from_em).EndObject();
  }
  if (r.best_start >= 0) j.Key("best_start").Value(r.best_start + 1);  // from 1, as the text
  j.Key("starts").BeginArray();
  for (const auto& s : r.starts) {
    j.BeginObject().Key("theta_start").Value(s.theta_start).Key("nll_start").Value(s.nll_start);
    j.Key("scale_shift").Value(s.scale_shift).Key("theta_scaled").Value(s.theta_scaled);
    j.Key("nll_scaled").Value(s.nll_scaled).Key("theta_end").Value(s.theta_end);
    j.Key("nll_end").Value(s.nll_end).Key("iterations").Value(s.iterations);
    j.Key("ok").Value(s.ok).Key("converged").Value(s.converged);
    j.Key("termination").Value(s.termination).EndObject();
  }
  j.EndArray();
  if (!validations.empty()) {
    j.Key("validation").BeginArray();
    for (const Validation& v : validations)
      WriteValidationJson(&j, v, model.FindMeasurement(spec.measurement).outputs);
    j.EndArray();
  }
  if (!out_path.empty()) j.Key("out").Value(out_path);
  if (profile) {
    j.Key("profile");
    WriteProfileJson(&j, *profile, profile_files);
  }
  j.EndObject();
  return j.str();
}

void WriteProfileJson(JsonWriter* j, const ProfileResult& p,
                      const std::vector<std::string>& files) {
  j->BeginObject().Key("name").Value(p.name).Key("values").Value(p.values);
  j->Key("nll").Value(p.nll).Key("status").Value(p.status);
  j->Key("ci95").Value(std::vector<double>{p.ci_lo, p.ci_hi}).Key("files").Value(files);
  j->EndObject();
}

void PrintProfile(const ProfileResult& p, const std::vector<std::string>& files,
                  const std::string& message) {
  std::cout << "\nprofile likelihood of " << p.name << " (others re-optimised)\n"
            << "  " << std::setw(12) << p.name << "   NLL - NLL(optimum)\n";
  for (size_t i = 0; i < p.values.size(); ++i) {
    std::cout << "  " << std::setw(12) << p.values[i] << "   " << std::setw(12)
              << p.nll[i] - p.nll_optimum << (p.status[i] == "converged" ? "" : "  " + p.status[i])
              << "\n";
  }
  auto end = [](double v) { return std::isnan(v) ? std::string("open") : FormatNumber(v); };
  std::cout << "  95 % likelihood-ratio interval: " << end(p.ci_lo) << " .. " << end(p.ci_hi)
            << (std::isnan(p.ci_lo) || std::isnan(p.ci_hi)
                    ? " (open: the profile stays below 1.92 to that end of the grid)"
                    : "")
            << "\n";
  for (const std::string& f : files) std::cout << "wrote         " << f << "\n";
  if (!message.empty()) std::cout << "  " << message << "\n";
}

// One line per optimiser iteration, rewritten in place on the terminal:
// "start 2/5  iteration 14  NLL -54082.3  change -0.0213  elapsed 3.1 s".
std::function<void(const TuneProgress&)> ProgressLine() {
  const auto t0 = std::chrono::steady_clock::now();
  return [t0](const TuneProgress& p) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::ostringstream line;
    line << std::setprecision(6);
    if (p.starts > 0) {
      line << "start " << p.start << "/" << p.starts;
    } else {
      line << p.phase;
    }
    line << "  iteration " << p.iteration << "  " << p.objective << " " << p.value << "  change "
         << std::setprecision(3) << p.change << "  elapsed " << std::fixed << std::setprecision(1)
         << elapsed << " s";
    // \r and padding: the line is rewritten in place; \x1b[K clears the rest.
    std::cerr << "\r" << line.str() << "\x1b[K" << std::flush;
  };
}

// Records every start's objective by iteration (for the convergence
// figure) and prints the progress line on a terminal.
struct ProgressLog {
  std::vector<std::vector<double>> by_start;  // [start - 1]; EM and ALS: [0]
  std::function<void(const TuneProgress&)> line;

  std::function<void(const TuneProgress&)> Callback() {
    return [this](const TuneProgress& p) {
      if (std::string(p.phase) != "ml from EM's solution") {
        const size_t i = p.starts > 0 ? size_t(p.start - 1) : 0;
        if (by_start.size() <= i) by_start.resize(i + 1);
        by_start[i].push_back(p.value);
      }
      if (line) line(p);
    };
  }
};

// `tune --plot DIR`: the tuned filter run on the first --validate file (else
// the first --data file), drawn as 'estlab filter --plot' draws it, with the
// tuner's convergence and the free simulation of the tuned model on that
// file. False when the figures could not be rendered.
bool PlotTuned(const po::variables_map& vm, const ModelEntry& model, const FilterSpec& tuned,
               const std::vector<double>& history, const std::string& objective) {
  const std::string path = vm.count("validate")
                               ? vm["validate"].as<std::vector<std::string>>().front()
                               : vm["data"].as<std::vector<std::string>>().front();
  const MeasurementDesc& meas = model.FindMeasurement(tuned.measurement);
  const FilterData data =
      LoadFilterData(path, model, meas, ParseColumnRenames(vm), ResolveTruth(vm, path, model).read,
                     ConstantInputGiven(vm));
  const FilterRunOutput run = model.run_filter(tuned, data);
  PlotRequest plot{.dir = vm["plot"].as<std::string>(),
                   .what = "tuned " + run.summary.filter + " on " +
                           std::filesystem::path(path).filename().string(),
                   .history = history,
                   .objective = objective,
                   .json = vm.count("json") > 0};
  // The free simulation from the run's prior mean, as the validation's
  // whole-file RMSE starts it (tune_validate.cpp).
  FreeSimulation sim;
  if (run.summary.x0.size() == model.states.size()) {
    sim = WholeRecordSimulation(model, tuned, data, run.summary.x0);
    plot.simulation = sim.ok ? &sim : nullptr;
    plot.sim_what =
        "free simulation on " + std::filesystem::path(path).filename().string() + " from x0 = (";
    for (size_t i = 0; i < model.states.size(); ++i)
      plot.sim_what += (i ? ", " : "") + model.states[i] + " = " + FormatNumber(run.summary.x0[i]);
    plot.sim_what += ")";
    if (!sim.ok) std::cerr << "estlab: note: no free-simulation figure: " << sim.why << "\n";
  }
  return PlotRun(model, meas, data, run, plot);
}

// The output-error branch of `estlab tune`: fit, validate, write --out (only
// a converged fit, or with --keep-best the best point named as such), report.
int TuneOutputError(const po::variables_map& vm, const ModelEntry& model, const FilterSpec& spec,
                    const TunerOptions& options, const std::vector<FilterData>& datasets,
                    double horizon, std::optional<OutputFile>* out, const std::string& out_path) {
  const int n = int(model.states.size());
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  OutputErrorOptions oe;
  oe.horizon = horizon;
  oe.max_iterations = options.max_iterations;
  oe.bound_width = options.bound_width;
  oe.estimate_x0 = options.estimate_x0;
  oe.x0_per_file = options.x0_per_file;
  const OutputErrorResult fit = FitOutputError(model, spec, options.estimate, datasets, oe);
  std::vector<Validation> validations;
  if (fit.ok && vm.count("validate"))
    validations = ValidateAll(vm, model, spec, fit.fitted_spec, options.burn_in, horizon);
  const bool write_out = *out && (fit.converged || (fit.ok && vm.count("keep-best")));
  if (write_out) {
    std::ostream& o = (*out)->stream();
    o << "# estlab tune --estimator output-error: model " << model.name << ", " << fit.start
      << "; Q and R are the initial ones (output-error does not fit noise)\n";
    if (!fit.converged)
      o << "# NOT A VERIFIED FIT (--keep-best): the best admissible point found; " << fit.message
        << "\n";
    o << ProcessModelLines(model, spec);
    o << IniLine("q", NoiseParam::kFixed, spec.q_white_accel, spec.qc, spec.q, n);
    o << IniLine("r", NoiseParam::kFixed, false, 0.0, spec.r, m);
    for (size_t i = 0; i < fit.param_names.size(); ++i)
      o << "param = " << fit.param_names[i] << "=" << FormatDouble(fit.param_values[i]) << "\n";
    o << X0IniLines(FitX0(model, spec, fit, datasets)) << X0PriorLine(spec, fit.x0.size(), n);
    (*out)->Commit();
  }
  const std::string wrote = write_out ? out_path : "";
  if (vm.count("json")) {
    std::cout << OutputErrorJson(model, spec, fit, datasets, horizon, validations, wrote) << "\n";
  } else {
    PrintOutputError(model, spec, fit, datasets, horizon, validations, wrote);
  }
  if (!fit.converged) {
    std::cerr << "estlab: error: output-error: " << (fit.ok ? "no-convergence: " : "failed: ")
              << fit.message
              << (*out && !write_out ? "; no --out file written (--keep-best writes the best "
                                       "point found)"
                                     : "")
              << "\n";
    return 1;
  }
  if (vm.count("plot") && !PlotTuned(vm, model, fit.fitted_spec, {}, "")) return 1;
  return 0;
}

}  // namespace

namespace {

// The options of `estlab tune`, built once.
const po::options_description& TuneDescriptionImpl() {
  static const po::options_description desc = [] {
    po::options_description desc("estlab tune: tune Q and R by maximum innovation likelihood");
    desc.add_options()("help,h", "this text")("data",
                                              po::value<std::vector<std::string>>()->composing(),
                                              "training data CSV (repeatable)")(
        "init-q-scalar", po::value<std::string>(), "initial Q = s I")(
        "init-r-scalar", po::value<std::string>(), "initial R = s I")(
        "keep-best",
        "write --out even when the fit is not verified converged (the best admissible point, "
        "named as such in the file)")(
        "estimate-param", po::value<std::string>(),
        "also estimate these model parameters (NAME,NAME...; initial values from --param)")(
        "param-bounds", po::value<std::string>(),
        "bounds of estimated parameters, natural scale: NAME=LO:HI[,...]")(
        "param-prior", po::value<std::string>(),
        "Gaussian priors of estimated parameters: NAME=normal:MEAN:SD[,...]")(
        "estimate-x0", po::value<std::string>(),
        "also estimate these initial states (NAME,NAME...; initial values from --x0): ml and em, "
        "the filter's prior mean (its covariance stays --p0-diag); output-error, the start of "
        "the simulation over the whole record")(
        "x0-per-file",
        "with --estimate-x0: each --data file its own initial state (the "
        "parameters shared)")(
        "plot", po::value<std::string>(),
        "draw the tuned filter on the first --validate (else --data) file into folder DIR, with "
        "the convergence")("horizon", po::value<std::string>()->default_value("0.5"),
                           "s: output-error windows and the validation's free-simulation RMSE")(
        "profile", po::value<std::string>(),
        "profile likelihood of an estimated parameter: NAME[=LO:HI[:N]] (default +-4 SE, 21; "
        "N <= 1000; LO and HI inside the parameter's constraint)")(
        "profile-out", po::value<std::string>(),
        "prefix of the profile's CSV and figure (default profile_NAME)")(
        "validate", po::value<std::vector<std::string>>()->composing(),
        "validation data CSV (repeatable)")("true-q-diag", po::value<std::string>(),
                                            "validation: true Q diagonal (else <validate>.json)")(
        "true-r-diag", po::value<std::string>(),
        "validation: true R diagonal (else <validate>.json)")(
        "out", po::value<std::string>(),
        "write the tuned Q/R as 'estlab filter' options (tuned.ini; never an input file)")(
        "json", "print a JSON summary");
    AddTunerOptions(&desc);
    AddFilterOptions(&desc, "init-");
    AddTruthOptions(&desc);
    AddConfigOption(&desc);
    return desc;
  }();
  return desc;
}

}  // namespace

const po::options_description& TuneDescription() { return TuneDescriptionImpl(); }

int RunTune(const std::vector<std::string>& args) {
  const po::options_description& desc = TuneDescriptionImpl();
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).run(), vm);
  MergeConfigFiles(&vm, "init-");
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << desc << "\n" << kExamples;
    return 0;
  }
  if (!vm.count("model")) throw InputError("--model is required (see 'estlab list')");
  if (!vm.count("data")) throw InputError("--data is required (one or more training files)");
  if (vm.count("out"))
    RefuseOutputOverInput("--out", vm["out"].as<std::string>(),
                          InputFiles(vm, {"data", "validate", "config"}));
  if (vm.count("plot")) CheckFigureFolder(vm["plot"].as<std::string>());
  std::optional<ProfileRequest> profile_request;
  std::string profile_prefix;
  if (vm.count("profile")) {
    profile_request = ParseProfileRequest(vm["profile"].as<std::string>());
    profile_prefix = vm.count("profile-out") ? vm["profile-out"].as<std::string>()
                                             : "profile_" + profile_request->name;
    RefuseOutputOverInput("--profile-out", profile_prefix + ".csv",
                          InputFiles(vm, {"data", "validate", "config"}));
  } else if (vm.count("profile-out")) {
    throw InputError("--profile-out needs --profile");
  }
  auto text = [&](const char* key) { return vm.count(key) ? vm[key].as<std::string>() : ""; };
  for (const char* key : {"estimate-param", "estimate-x0", "param-bounds", "param-prior"})
    if (vm.count(key) && Trim(text(key)).empty())  // once ignored silently
      throw InputError(std::string("--") + key +
                       " is empty: name what it applies to, or leave it out");
  TunerOptions options =
      BuildTunerOptions(TunerSettingsFromVariablesMap(vm), GuessKey(vm, "q"), GuessKey(vm, "r"));
  const EstimatorInfo& estimator = InfoOf(options.estimator);
  // Output error simulates: a model file needs no tuner compiled for it.
  const bool output_error = !estimator.tuner;
  options.estimate_x0 = ParseEstimatedStates(text("estimate-x0"));
  options.x0_per_file = vm.count("x0-per-file") > 0;
  std::string error;  // before a model file compiles: a wrong estimator for x0 says so at once
  if (!options.IsValid(&error)) throw InputError(error);
  // A model file not yet in the cache compiles the tuner and, for the tuned
  // run's rows, only the filter it tunes (output error: the whole entry).
  ModelNeeds needs{.tuner = !output_error};
  if (!output_error) needs.run = RunNeedsOf(SettingsFromVariablesMap(vm, "init-"), false);
  const ModelEntry& model = FindModel(vm["model"].as<std::string>(), needs);
  if (model.tune == nullptr && !output_error)
    throw InputError("model '" + model.name + "' has no tuner");
  if (!vm.count("measure")) throw InputError("--measure is required (see 'estlab list')");
  const MeasurementDesc& meas = model.FindMeasurement(vm["measure"].as<std::string>());
  const int n = int(model.states.size()), m = int(meas.outputs.size());
  FilterSettings settings = SettingsFromVariablesMap(vm, "init-");
  ExpandScalarOption(vm, "init-q-scalar", "init-q-diag",
                     {"init-q-diag", "init-q", "init-q-white-accel"}, n, &settings);
  ExpandScalarOption(vm, "init-r-scalar", "init-r-diag", {"init-r-diag", "init-r"}, m, &settings);
  const FilterSpec spec = estlab::BuildFilterSpec(settings, model);

  options.seed = SeedOf(settings);
  const double horizon = ParseNumber(vm["horizon"].as<std::string>(), "--horizon");
  if (!(horizon > 0)) throw InputError("--horizon must be > 0 s, got " + FormatNumber(horizon));
  options.estimate =
      ParseEstimatedParams(text("estimate-param"), text("param-bounds"), text("param-prior"));

  if (!options.IsValid(&error)) throw InputError(error);

  std::vector<FilterData> datasets;
  const auto renames = ParseColumnRenames(vm);
  for (const auto& path : vm["data"].as<std::vector<std::string>>()) {
    // Output-error starts its free simulations from the recorded states:
    // there the state columns are the method's input, not truth to score.
    const bool states = output_error || ResolveTruth(vm, path, model).read;
    datasets.push_back(LoadFilterData(path, model, meas, renames, states, ConstantInputGiven(vm)));
    CheckPriorTime(spec, datasets.back());
  }
  // The initial states named, checked against the model before any work.
  ResolveInitialStates(options.estimate_x0, options.x0_per_file, datasets.size(), model.states,
                       model.name);
  NoteNeverCoObserved(options, meas, datasets);
  if (vm.count("validate") && model.run_filter == nullptr)
    throw InputError("--validate: the filter runner is not available");
  // Open the output first so an unwritable path fails before the work.
  const std::string out_path = vm.count("out") ? vm["out"].as<std::string>() : "";
  std::optional<OutputFile> out;
  if (!out_path.empty()) out.emplace(out_path);

  if (profile_request) {
    bool named = false;
    for (const EstimatedParam& e : options.estimate)
      named = named || e.name == profile_request->name;
    if (!named)
      throw InputError("--profile: '" + profile_request->name + "' is not in --estimate-param");
    CheckProfileRequest(model, *profile_request);
  }
  if (output_error) {
    if (profile_request) throw InputError("--profile applies to --estimator ml");
    return TuneOutputError(vm, model, spec, options, datasets, horizon, &out, out_path);
  }
  // Progress only on a terminal (stderr; --json keeps stdout clean anyway).
  ProgressLog log;
  if (isatty(STDERR_FILENO)) log.line = ProgressLine();
  options.progress = log.Callback();
  const TuneResult result = model.tune(spec, options, datasets);
  if (log.line) std::cerr << "\n";
  options.progress = nullptr;  // the profile's re-optimisations stay quiet
  std::optional<ProfileResult> profile;
  std::vector<std::string> profile_files;
  std::string profile_message;
  if (result.IsSolutionUsable() && profile_request) {
    profile = ProfileLikelihood(model, options, datasets, result, *profile_request);
    profile_files = WriteProfile(*profile, profile_prefix, &profile_message);
  }
  std::vector<Validation> validations;
  if (result.IsSolutionUsable() && vm.count("validate"))
    validations = ValidateAll(vm, model, spec, result.tuned_spec, options.burn_in, horizon);
  const bool write_out =
      out && (result.IsConverged() || (result.IsSolutionUsable() && vm.count("keep-best")));
  if (write_out) {
    out->stream() << "# estlab tune: model " << model.name << ", measurement " << spec.measurement
                  << ", filter " << FilterKindName(spec.kind()) << ", NLL "
                  << FormatDouble(result.nll_initial) << " -> " << FormatDouble(result.nll_tuned)
                  << " (" << TuneStatusName(result.status) << ")\n";
    if (!result.IsConverged())
      out->stream() << "# NOT A VERIFIED FIT (--keep-best): the best admissible point found; "
                    << result.message << "\n";
    out->stream() << ProcessModelLines(model, spec);
    out->stream() << IniLine("q", result.q_param, result.q_white_accel, result.qc, result.q, n);
    out->stream() << IniLine("r",
                             result.r_param_groups.empty() ? result.r_param : NoiseParam::kFixed,
                             false, 0.0, result.r, m);
    for (size_t i = 0; i < result.param_names.size(); ++i)
      out->stream() << "param = " << result.param_names[i] << "="
                    << FormatDouble(result.param_values[i]) << "\n";
    out->stream() << X0IniLines(TunedX0(model, result, datasets))
                  << X0PriorLine(spec, result.x0.size(), n);
    out->Commit();
  }
  if (vm.count("json")) {
    std::cout << ResultJson(model, spec, result, datasets, validations, write_out ? out_path : "",
                            profile, profile_files)
              << "\n";
  } else {
    PrintHuman(model, spec, result, datasets, validations, horizon, write_out ? out_path : "");
    if (profile) PrintProfile(*profile, profile_files, profile_message);
  }
  if (!result.IsConverged()) {
    std::cerr << "estlab: error: tune: status " << TuneStatusName(result.status) << ": "
              << result.message
              << (out && !write_out ? "; no --out file written (--keep-best writes the best "
                                      "admissible point)"
                                    : "")
              << "\n";
    return 1;
  }
  if (vm.count("plot")) {
    // From the start point (iteration 0): EM's history, or the best start's
    // NLL at every accepted iterate (both forms trace the NLL).
    const std::vector<double> history =
        result.nll_history.empty() ? result.trace : result.nll_history;
    if (!PlotTuned(vm, model, result.tuned_spec, history, "NLL")) return 1;
  }
  return 0;
}

}  // namespace estlab::cli
