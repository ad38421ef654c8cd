// estlab filter: run one filter over a data file.
#include <boost/program_options.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <optional>
#include <variant>

#include "src/cli/commands.h"
#include "src/cli/plot_run.h"
#include "src/filters/filter_options.h"
#include "src/io/json.h"
#include "src/io/output_file.h"
#include "src/options/filter_flags.h"
#include "src/options/truth_flags.h"
#include "src/registry/registry.h"
#include "src/run/degeneracy.h"
#include "studies/report/run_figures.h"

namespace po = boost::program_options;

namespace estlab::cli {

// The particle smoother keeps M trajectories of every row: checked before
// anything is allocated (1e9 once ended in std::bad_alloc).
constexpr int kMaxSmootherTrajectories = 100000;
constexpr double kMaxSmootherBytes = 4.0 * 1073741824.0;  // their states: 4 GiB

namespace {

constexpr const char* kExamples = R"(Examples:
  # Simulate, then filter the pendulum with y = sin(theta) (paper 002 setting):
  estlab simulate --model pendulum --param g=9.8 --x0 theta=0.785398 --t-end 5 --dt 0.0125 \
      --measure sin --meas-noise-var 0.09 --out d.csv
  estlab filter --model pendulum --param g=9.8 --measure sin --filter ukf --data d.csv \
      --integrator euler --x0 theta=0.785398 --p0-diag 0.1,0.1 --q-white-accel 1 \
      --r-diag 0.09 --out est.csv
  # Particle filter with residual resampling, JSON summary:
  estlab filter --model pendulum --param g=9.8 --measure sin --filter pf --particles 1000 \
      --resample residual --data d.csv --integrator euler --x0 theta=0.785398 \
      --p0-diag 0.1,0.1 --q-white-accel 1 --r-diag 0.09 --out est_pf.csv --json
  # The Q and R that 'estlab tune --out tuned.ini' found (the command line wins):
  estlab filter --model pendulum --param g=9.8 --measure sin --filter ukf --data d.csv \
      --integrator euler --x0 theta=0.785398 --p0-diag 0.1,0.1 --config tuned.ini --out est.csv
  # Adaptive UKF (Sage-Husa on R) on a file with other column names:
  estlab filter --model pendulum --measure angle --filter ukf --adapt sage-husa \
      --adapt-what r --data lab.csv --column z_theta=angle_rad --q-diag 1e-6,1e-4 \
      --r-diag 0.01 --out est.csv
  # Two sensor groups at their own rates (estlab simulate --sensor-rate position=1),
  # an R per group; the summary gives each group's NIS:
  estlab filter --model cart-pole --measure position,encoder --filter ekf --data mr.csv \
      --input 0 --x0 theta=3 --q-diag 1e-8,1e-6,1e-8,1e-6 --r-diag position=1e-4 \
      --r-diag encoder=1e-4 --out est.csv
  # Only the summary (no per-step file):
  estlab filter --model pendulum --param g=9.8 --measure sin --filter ekf --data d.csv \
      --integrator euler --x0 theta=0.785398 --p0-diag 0.1,0.1 --q-white-accel 1 --r-diag 0.09

Data: a CSV with a 't' column and one 'z_<output>' column per output of the
measurement (what 'estlab simulate --measure' writes); --column ours=theirs maps
other names, --column ours=[a*]theirs[+-b] also converts (theta=angle-pi,
theta=0.0174533*angle_deg; a and b numbers or pi). Truth: columns named like the states
are the truth only when the file says so (d.csv.json, written by 'estlab simulate') or
--truth theta,omega names them (--no-truth: never); then the errors, RMSE/MAE and NEES
are computed, and the summary says which columns were used. An empty or NaN measurement cell
is missing: the row updates with its other components (docs/multirate.md). A measurement
of sensor groups (see 'estlab list') takes --measure GROUP,GROUP and R per group
(--r-diag GROUP=values, --r GROUP=matrix, one each; 0 between groups). Models with an input read the input's column (named
as the model's input, or 'u'; --column maps another), held constant from each row to
the next (zero-order hold); without the column, --input must give a constant. The
prior holds at --t0 (default: the first row's time; a --t0 later than
the first row is refused).

Output: with --out, est.csv with t, <state>_est, <state>_var [, cov_<a>_<b>],
nu_<output>, S_<output> [, S_<a>_<b>] (the innovation covariance; off-diagonal
entries with --full-cov), nis, loglik [, <state>_err, nees]; a summary table on
stdout, or JSON with --json. --plot DIR draws the run (estimates with +-2 sd,
measurements and truth; innovations with +-2 sqrt(S); NIS with its chi-square
bounds; the whitened innovations' autocorrelation) as PNG + SVG with their
gnuplot scripts and data; 'estlab figures est.csv' draws the same later.
NIS check: when the mean NIS is more than 2x its upper 95% bound, or less than
half its lower bound, the summary says so in one line with the usual causes
(model parameters, Q/R: 'estlab tune', angle conventions: --column).

Adaptation (--adapt): 'N clip(s)' counts the adapted Q and R matrices (one
each per update, Q and R apart) whose eigenvalues had to be raised to the
floor to stay positive definite; with --adapt-what qr it can reach twice the
number of updates.

Particle filters: the summary gives the effective sample size (ESS). When it
stays below max(2, 1 % of the particles) for 10 updates in a row the filter
has collapsed onto one particle: status "degenerate" with hints, exit 1
(--allow-degenerate: exit 0).

Without --out only the summary is printed. A filter that diverges exits 1
naming the step and time; est.csv keeps every row computed before.
)";

constexpr const char* kSmoothExamples = R"(Examples:
  # Simulate the pendulum, then smooth it with the unscented RTS smoother (URTS):
  estlab simulate --model pendulum --param g=9.81 --t-end 5 --dt 0.01 --x0 theta=1.5 \
      --measure sin --meas-noise-var 0.1 --process-noise-var 3e-9,1e-4 --out d.csv
  estlab smooth --model pendulum --param g=9.81 --measure sin --filter ukf --data d.csv \
      --integrator euler --p0-diag 1,1 --q-white-accel 0.01 --r-diag 0.1 --out smoothed.csv
  # The extended RTS smoother with the lag-one covariances (for EM), JSON summary:
  estlab smooth --model pendulum --param g=9.81 --measure sin --filter ekf --data d.csv \
      --integrator euler --p0-diag 1,1 --q-white-accel 0.01 --r-diag 0.1 --full-cov \
      --out smoothed.csv --json
  # The particle smoother (forward filtering, backward simulation of 200 trajectories):
  estlab smooth --model pendulum --param g=9.81 --measure sin --filter pf --particles 2000 \
      --smoother-trajectories 200 --data d.csv --integrator euler --p0-diag 1,1 \
      --q-white-accel 0.01 --r-diag 0.1 --out smoothed_pf.csv

Smoothers: kf -> rts (exact), ekf -> erts, iekf -> iekf-rts, ukf -> urts,
ckf -> ckf-rts, ghkf -> ghkf-rts (the Gaussian RTS smoother with each filter's
prediction cross-covariance), pf -> pf-bs (forward filtering, backward
simulation; needs a positive definite Q). Every option of 'estlab filter'
applies (data, columns, --config, adaptation).

Output: with --out, smoothed.csv with t, <state>_est, <state>_var
[, cov_<a>_<b> and lag1_<a>_<b> = Cov(a_k, b_k+1 | all data) with --full-cov]
[, <state>_err, nees] of the smoothed estimates (pf-bs: the mean and variance of
its trajectories, no lag-one). The summary (and --json) gives the smoother's
RMSE, MAE and NEES, and the forward filter's under "filter"; the log-likelihood
and NIS are the forward filter's. A filter that diverges exits 1 naming the
step; the rows before it are smoothed and written.
)";

// "Far" outside the 95% bounds of the mean NIS: above kNisFarFactor times the
// upper bound or below the lower bound divided by it. The bounds of a mean
// over hundreds of updates are narrow (about 0.86 .. 1.14 for one output and
// 400 updates), so a well-tuned filter often lands just outside them; a
// factor 2 off is a filter whose S does not describe its innovations.
constexpr double kNisFarFactor = 2.0;

// One line when the mean NIS is far outside its bounds, naming the usual
// causes; nothing otherwise.
void PrintNisWarning(const FilterSummary& s) {
  if (s.updates == 0 || !std::isfinite(s.mean_nis)) return;
  const bool above = s.mean_nis > kNisFarFactor * s.nis_bounds95[1];
  const bool below = s.mean_nis < s.nis_bounds95[0] / kNisFarFactor;
  if (!above && !below) return;
  std::cout << "NIS check       the mean NIS is far " << (above ? "above" : "below")
            << " its 95% bounds (" << (above ? "> 2x the upper" : "< 1/2 the lower")
            << " bound): the innovations are " << (above ? "larger" : "smaller")
            << " than S predicts. Usual causes: wrong model parameters (--param); Q or R too "
            << (above ? "small" : "large")
            << " (try 'estlab tune'); angles in another convention than the model's (see "
               "--column, e.g. theta=angle-pi)\n";
}

// Per sensor group: its updates and mean NIS with bounds (nothing for a
// measurement without groups).
void PrintGroupNis(const FilterSummary& s) {
  for (const FilterSummary::GroupNis& g : s.group_nis) {
    std::cout << "  " << std::left << std::setw(14) << g.group << std::right << g.mean_nis
              << "   (95% bounds " << g.nis_bounds95[0] << " .. " << g.nis_bounds95[1] << ", "
              << g.updates << " updates)\n";
  }
}

// adapt_clips counts adapted matrices, not steps: at each update the adapter
// (src/filters/noise_adapter.h) replaces Q and/or R and counts one clip for
// each of them that had an eigenvalue raised to the floor, so with
// --adapt-what qr the count can reach twice the number of updates.
void PrintAdaptClips(const FilterSummary& s, const AdaptSpec& adapt) {
  const int per_update = int(adapt.adapt_q) + int(adapt.adapt_r);
  std::cout << "adaptation      " << s.adapt_clips << " clip(s): adapted "
            << (per_update == 2 ? "Q or R matrices"
                : adapt.adapt_q ? "Q matrices"
                                : "R matrices")
            << " with an eigenvalue raised to the floor " << adapt.eigen_floor
            << " to stay positive definite (one count per adapted matrix; " << per_update
            << " matri" << (per_update == 2 ? "ces" : "x") << " per update, " << s.updates
            << " updates)\n";
}

// The particle filter's effective sample size; nothing for other filters.
void PrintEss(const FilterSummary& s) {
  if (s.particles == 0) return;
  std::cout << "ESS             mean " << s.mean_ess << ", smallest " << s.min_ess << " of "
            << s.particles << " particles; " << s.collapsed_updates << " of " << s.updates
            << " updates collapsed (ESS < " << DegeneracyMonitor::Threshold(s.particles) << ")\n";
}

// When some truth cells are missing: the rows each state's RMSE is over.
void PrintTruthRows(const FilterSummary& s) {
  bool partial = false;
  for (long n : s.truth_rows) partial = partial || n < s.steps;
  if (!partial) return;
  std::cout << "  (over the rows with finite truth:";
  for (size_t i = 0; i < s.truth_rows.size(); ++i)
    std::cout << (i ? ", " : " ") << s.states[i] << " " << s.truth_rows[i] << " of " << s.steps;
  std::cout << ")\n";
}

void PrintSummary(const FilterSummary& s, const AdaptSpec& adapt, const std::string& truth,
                  const std::string& out_path) {
  std::cout << std::setprecision(5);
  const FilterSummary* f = s.forward.get();  // smoother: the forward filter's
  if (f != nullptr) {
    std::cout << "smoother      " << s.filter << " (forward filter " << f->filter << ")\n";
  } else {
    std::cout << "filter        " << s.filter << "\n";
  }
  std::cout << "steps         " << s.steps << " (" << s.updates << " updates)\nstatus        "
            << s.status << "\ntruth         " << truth << "\n";
  if (!s.rmse.empty()) {
    std::cout << "\n  state          RMSE          MAE" << (f ? "   filter RMSE" : "") << "\n";
    for (size_t i = 0; i < s.states.size(); ++i) {
      std::cout << "  " << std::left << std::setw(12) << s.states[i] << std::right << std::setw(12)
                << s.rmse[i] << "  " << std::setw(12) << s.mae[i];
      if (f != nullptr && i < f->rmse.size()) std::cout << "  " << std::setw(12) << f->rmse[i];
      std::cout << "\n";
    }
    PrintTruthRows(s);
    std::cout << "\n";
  }
  std::cout << "log-likelihood  " << s.loglik << (f ? "   (the forward filter's)" : "") << "\n";
  std::cout << "mean NIS        " << s.mean_nis << "   (95% bounds " << s.nis_bounds95[0] << " .. "
            << s.nis_bounds95[1] << ")\n";
  PrintGroupNis(s.group_nis.empty() && f != nullptr ? *f : s);
  PrintNisWarning(s);
  if (!s.rmse.empty()) {
    std::cout << "mean NEES       " << s.mean_nees << "   (95% bounds " << s.nees_bounds95[0]
              << " .. " << s.nees_bounds95[1] << ")";
    if (f != nullptr) std::cout << "   filter " << f->mean_nees;
    std::cout << "\n";
  }
  if (s.adapt_clips > 0) PrintAdaptClips(s, adapt);
  PrintEss(f != nullptr ? *f : s);
  std::cout << "wall time       " << s.wall_s << " s (filter loop " << s.us_per_step
            << " us/step; reading the data " << s.read_s << " s)\n";
  if (!out_path.empty()) std::cout << "wrote           " << out_path << "\n";
}

}  // namespace

namespace {

// `extra` adds keys at the end of the top-level object.
void WriteSummaryJson(const FilterSummary& s, JsonWriter& j,
                      const std::function<void(JsonWriter&)>& extra = {}) {
  j.BeginObject();
  if (s.forward) {
    j.Key("smoother").Value(s.filter).Key("filter");
    WriteSummaryJson(*s.forward, j);  // the forward filter's, nested
  } else {
    j.Key("filter").Value(s.filter);
  }
  j.Key("rmse").BeginObject();
  for (size_t i = 0; i < s.rmse.size(); ++i) j.Key(s.states[i]).Value(s.rmse[i]);
  j.EndObject().Key("mae").BeginObject();
  for (size_t i = 0; i < s.mae.size(); ++i) j.Key(s.states[i]).Value(s.mae[i]);
  j.EndObject().Key("truth_rows").BeginObject();
  for (size_t i = 0; i < s.truth_rows.size(); ++i) j.Key(s.states[i]).Value(s.truth_rows[i]);
  j.EndObject();
  j.Key("loglik").Value(s.loglik).Key("updates").Value(s.updates);
  j.Key("mean_nis").Value(s.mean_nis);
  j.Key("nis_bounds95").Value(std::vector<double>{s.nis_bounds95[0], s.nis_bounds95[1]});
  if (!s.group_nis.empty()) {
    j.Key("group_nis").BeginObject();
    for (const FilterSummary::GroupNis& g : s.group_nis) {
      j.Key(g.group)
          .BeginObject()
          .Key("updates")
          .Value(g.updates)
          .Key("mean_nis")
          .Value(g.mean_nis);
      j.Key("nis_bounds95").Value(std::vector<double>{g.nis_bounds95[0], g.nis_bounds95[1]});
      j.EndObject();
    }
    j.EndObject();
  }
  j.Key("mean_nees").Value(s.mean_nees);
  j.Key("nees_bounds95").Value(std::vector<double>{s.nees_bounds95[0], s.nees_bounds95[1]});
  j.Key("steps")
      .Value(s.steps)
      .Key("wall_s")
      .Value(s.wall_s)
      .Key("loop_s")
      .Value(s.loop_s)
      .Key("us_per_step")
      .Value(s.us_per_step)
      .Key("read_s")
      .Value(s.read_s)
      .Key("write_s")
      .Value(s.write_s);
  j.Key("status").Value(s.status);
  if (!s.ok) j.Key("message").Value(s.message);
  j.Key("adapt_clips").Value(s.adapt_clips);
  if (s.particles > 0) {
    j.Key("ess").BeginObject().Key("particles").Value(long(s.particles));
    j.Key("mean").Value(s.mean_ess).Key("min").Value(s.min_ess);
    j.Key("collapsed_updates").Value(s.collapsed_updates).Key("degenerate").Value(s.degenerate);
    j.EndObject();
  }
  if (extra) extra(j);
  j.EndObject();
}

}  // namespace

// The keys of `estlab filter --json`; for a smoother, "smoother" names it, its
// rmse, mae and NEES are the smoothed estimates' and "filter" holds the
// forward filter's summary.
std::string FilterSummaryJson(const FilterSummary& s) {
  JsonWriter j;
  WriteSummaryJson(s, j);
  return j.str();
}

namespace {

// The summary JSON and "truth": the columns used and where that came from
// (null when none).
std::string SummaryJsonWithTruth(const FilterSummary& s, const TruthChoice& truth, bool has_truth) {
  JsonWriter j;
  WriteSummaryJson(s, j, [&](JsonWriter& w) {
    w.Key("truth");
    if (!has_truth) {
      w.Null();
      return;
    }
    w.BeginObject().Key("columns").Value(truth.names).Key("source").Value(truth.source);
    w.EndObject();
  });
  return j.str();
}

}  // namespace

namespace {

// `estlab filter` and `estlab smooth`: the same options and checks; smooth
// adds --smoother-trajectories and writes the smoothed rows. Built once.
const po::options_description& FilterDescription(bool smooth) {
  static const auto make = [](bool smooth) {
    po::options_description desc(
        smooth ? "estlab smooth: run a filter forward, then its smoother backward (RTS for the "
                 "Gaussian filters, backward simulation for the particle filter)"
               : "estlab filter: run a Kalman-family or particle filter over a data file");
    desc.add_options()("help,h", "this text")(
        "data", po::value<std::string>(),
        "data CSV: t, z_<output> (an empty cell is a missing component: the row updates with "
        "the others), the inputs")(
        "out", po::value<std::string>(),
        "per-step output CSV (optional: without it only the summary; never an input file)")(
        "json", "print a JSON summary")(
        "plot", po::value<std::string>(),
        "draw the run into folder DIR: PNG + SVG, their gnuplot scripts and data")(
        "allow-degenerate", "pf: exit 0 even when the particle filter degenerates");
    AddTruthOptions(&desc);
    if (smooth)
      desc.add_options()("smoother-trajectories", po::value<int>()->default_value(100),
                         "pf: backward-simulated trajectories of the particle smoother "
                         "(2..100000; memory: M x rows x states x 8 bytes)");
    AddFilterOptions(&desc);
    AddConfigOption(&desc);
    return desc;
  };
  static const po::options_description filter = make(false), smoother = make(true);
  return smooth ? smoother : filter;
}

po::variables_map ParseFilterArgs(const std::vector<std::string>& args, bool smooth) {
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(FilterDescription(smooth)).run(), vm);
  MergeConfigFiles(&vm);
  po::notify(vm);
  return vm;
}

// One filter or smoother run, checked and loaded.
struct FilterJob {
  const ModelEntry* model = nullptr;
  const MeasurementDesc* meas = nullptr;
  FilterSpec spec;
  TruthChoice truth;
  std::string data_path;
  FilterData data;
  double read_s = 0.0;  // reading and checking the data
};

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// --smoother-trajectories and the particle smoother's Q.
void CheckSmootherOptions(const FilterRequest& r, const ModelEntry& model, FilterSpec* spec) {
  spec->smooth = true;
  spec->smoother_trajectories = r.smoother_trajectories;
  if (spec->smoother_trajectories < 2 || spec->smoother_trajectories > kMaxSmootherTrajectories)
    throw InputError("--smoother-trajectories must be in 2.." +
                     std::to_string(kMaxSmootherTrajectories) + ", got " +
                     std::to_string(spec->smoother_trajectories));
  if (r.smoother_trajectories_given && spec->kind() != FilterKind::kPf)
    throw InputError(std::string("--smoother-trajectories applies to the particle smoother "
                                 "(--filter pf), not ") +
                     FilterKindName(spec->kind()));
  // The particle smoother weighs by the transition density: a fixed Q must
  // be positive definite (a white-noise-acceleration Q is checked per step).
  if (spec->kind() == FilterKind::kPf && !spec->q_white_accel)
    CheckCovariance(spec->q, int(model.states.size()),
                    "Q (the particle smoother needs a positive definite process noise)", false);
}

// The particle smoother's memory, checked before any of it exists: its M
// backward trajectories (M x rows x states doubles) and the filtered clouds
// it keeps for them (particles x rows x (2 states + 1) doubles: each step's
// particles, their predicted means and weights, particle_smoother.h).
void CheckSmootherMemory(const FilterJob& job) {
  const double rows = double(job.data.t.size()), states = double(job.model->states.size());
  const int particles = std::get<ParticleOptions>(job.spec.filter).num_particles;
  auto refuse_over = [&](double bytes, const std::string& what, const std::string& fix) {
    if (bytes <= kMaxSmootherBytes) return;
    throw InputError(what + " over " + std::to_string(job.data.t.size()) + " rows of " +
                     job.data_path + " would take " + FormatNumber(bytes / 1073741824.0) +
                     " GiB (at most " + FormatNumber(kMaxSmootherBytes / 1073741824.0) +
                     "): " + fix + ", or a shorter record");
  };
  refuse_over(double(job.spec.smoother_trajectories) * rows * states * 8.0,
              "--smoother-trajectories " + std::to_string(job.spec.smoother_trajectories),
              "fewer trajectories");
  refuse_over(ParticleSmootherBytes(particles, rows, int(states)),
              "the particle smoother's clouds of --particles " + std::to_string(particles),
              "fewer particles");
}

// Every check of the options and the data (throws InputError), then the data.
FilterJob PrepareFilter(const FilterRequest& r) {
  if (r.model.empty()) throw InputError("--model is required (see 'estlab list')");
  if (r.data.empty()) throw InputError("--data is required");
  FilterJob job;
  // A model file not yet in the cache compiles only what this run needs.
  job.model = &FindModel(r.model, {.run = RunNeedsOf(r.settings, r.smooth)});
  const ModelEntry& model = *job.model;
  job.spec = BuildFilterSpec(r.settings, model);
  if (r.smooth) CheckSmootherOptions(r, model, &job.spec);
  job.data_path = r.data;
  job.truth = ResolveTruth(r.truth, r.no_truth, job.data_path, model);
  job.meas = &model.FindMeasurement(job.spec.measurement);
  const auto read_start = std::chrono::steady_clock::now();
  job.data =
      LoadFilterData(job.data_path, model, *job.meas, ParseColumnMaps(r.settings.GetAll("column")),
                     job.truth.read, r.settings.Given("input"));
  job.read_s = SecondsSince(read_start);
  CheckPriorTime(job.spec, job.data);
  if (r.smooth && job.spec.kind() == FilterKind::kPf) CheckSmootherMemory(job);
  return job;
}

// The request that the parsed options make.
FilterRequest RequestFromOptions(const po::variables_map& vm, bool smooth) {
  FilterRequest r;
  auto text = [&](const char* key) { return vm.count(key) ? vm[key].as<std::string>() : ""; };
  r.model = text("model");
  r.settings = SettingsFromVariablesMap(vm);
  r.data = text("data");
  if (vm.count("truth")) r.truth = vm["truth"].as<std::string>();
  r.no_truth = vm.count("no-truth") > 0;
  r.smooth = smooth;
  if (smooth) {
    r.smoother_trajectories = vm["smoother-trajectories"].as<int>();
    r.smoother_trajectories_given = !vm["smoother-trajectories"].defaulted();
  }
  r.allow_degenerate = vm.count("allow-degenerate") > 0;
  return r;
}

// The exit status of a finished run: 1 for a numerical failure, or a
// degenerate particle filter without --allow-degenerate (*error says why;
// *warning when it is allowed).
int FilterStatus(const FilterSummary& s, bool allow_degenerate, std::string* error,
                 std::string* warning) {
  if (!s.ok) {
    *error = s.message;
    return 1;
  }
  if (s.degenerate) {  // a smoother's summary carries its forward filter's
    if (!allow_degenerate) {
      *error = s.message + " (--allow-degenerate: exit 0)";
      return 1;
    }
    *warning = s.message;
  }
  return 0;
}

int RunFilterOrSmooth(const std::vector<std::string>& args, bool smooth) {
  const po::variables_map vm = ParseFilterArgs(args, smooth);
  if (vm.count("help")) {
    std::cout << FilterDescription(smooth) << "\n" << (smooth ? kSmoothExamples : kExamples);
    return 0;
  }
  if (vm.count("out") && vm.count("model") && vm.count("data"))
    RefuseOutputOverInput("--out", vm["out"].as<std::string>(), InputFiles(vm, {"data", "config"}));
  if (vm.count("plot") && vm.count("model") && vm.count("data"))
    CheckFigureFolder(vm["plot"].as<std::string>());
  const FilterJob job = PrepareFilter(RequestFromOptions(vm, smooth));
  // Open the output first so an unwritable path fails before the work.
  const std::string out_path = vm.count("out") ? vm["out"].as<std::string>() : "";
  std::optional<OutputFile> out;
  if (!out_path.empty()) out.emplace(out_path);
  FilterRunOutput result = job.model->run_filter(job.spec, job.data);
  result.summary.read_s = job.read_s;
  if (out) {
    const auto write_start = std::chrono::steady_clock::now();
    WriteCsv(out->stream(), result.columns, result.rows);
    out->Commit();
    result.summary.write_s = SecondsSince(write_start);
  }
  if (vm.count("json")) {
    std::cout << SummaryJsonWithTruth(result.summary, job.truth, job.data.has_truth) << "\n";
  } else {
    PrintSummary(result.summary, job.spec.adapt, job.truth.Describe(job.data.has_truth), out_path);
  }
  int status = 0;
  if (vm.count("plot")) {
    const PlotRequest plot{.dir = vm["plot"].as<std::string>(),
                           .what = result.summary.filter + " on " +
                                   std::filesystem::path(job.data_path).filename().string(),
                           .json = vm.count("json") > 0};
    if (!PlotRun(*job.model, *job.meas, job.data, result, plot)) status = 1;
  }
  std::string error, warning;
  if (FilterStatus(result.summary, vm.count("allow-degenerate") > 0, &error, &warning) != 0) {
    std::cerr << "estlab: error: " << error << "\n";
    if (out && !result.summary.ok)
      std::cerr << "estlab: the " << result.rows.size() << " rows computed before are in "
                << out_path << "\n";
    return 1;
  }
  if (!warning.empty()) std::cerr << "estlab: warning: " << warning << "\n";
  return status;
}

}  // namespace

const po::options_description& CommandOptions(const std::string& command) {
  if (command == "filter" || command == "smooth") return FilterDescription(command == "smooth");
  if (command == "simulate") return SimulateDescription();
  if (command == "tune") return TuneDescription();
  throw InputError("no options of command '" + command + "'");
}

FilterRequest FilterRequestFromArgs(const std::vector<std::string>& args, bool smooth) {
  return RequestFromOptions(ParseFilterArgs(args, smooth), smooth);
}

FilterOutcome ComputeFilter(const FilterRequest& request) {
  const FilterJob job = PrepareFilter(request);
  FilterOutcome o;
  o.run = job.model->run_filter(job.spec, job.data);
  o.run.summary.read_s = job.read_s;
  o.truth = job.truth;
  o.has_truth = job.data.has_truth;
  o.status = FilterStatus(o.run.summary, request.allow_degenerate, &o.error, &o.warning);
  return o;
}

std::string FilterOutcome::SummaryJson() const {
  return SummaryJsonWithTruth(run.summary, truth, has_truth);
}

int RunFilterCommand(const std::vector<std::string>& args) {
  return RunFilterOrSmooth(args, false);
}
int RunSmoothCommand(const std::vector<std::string>& args) { return RunFilterOrSmooth(args, true); }

}  // namespace estlab::cli
