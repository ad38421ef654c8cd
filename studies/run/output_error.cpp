#include "studies/run/output_error.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "adaptive/identifiability.h"
#include "adaptive/initial_states.h"
#include "adaptive/theta_scale.h"
#include "src/core/types.h"

namespace estlab {
namespace {

double MeanStep(const FilterData& d) { return (d.t.back() - d.t.front()) / double(d.t.size() - 1); }

bool Uneven(const FilterData& d, size_t k, double dt) {
  return std::abs(d.t[k] - d.t[k - 1] - dt) > 1e-6 * dt + 1e-12;
}

// The data's sampling step; InputError unless evenly sampled.
double EvenStep(const FilterData& d) {
  // (Output error and --validate's free simulation both come here: the
  // messages name the windows, not the estimator.)
  if (d.t.size() < 2)
    throw InputError(d.path + ": free-simulation windows need at least two rows, the file has " +
                     std::to_string(d.t.size()));
  const double dt = MeanStep(d);
  for (size_t k = 1; k < d.t.size(); ++k) {
    if (Uneven(d, k, dt))
      throw InputError(d.path + ":" + std::to_string(d.lines[k]) +
                       ": free-simulation windows need evenly sampled data (step " +
                       FormatNumber(dt) + ", here " + FormatNumber(d.t[k] - d.t[k - 1]) +
                       "); estimate the initial state (--estimate-x0) to simulate the whole "
                       "record instead");
  }
  return dt;
}

// The free simulation of rows [first, first + count) of `d` from x0 at
// t[first], with d's input (zero-order hold) or the spec's constant one.
SimulationResult SimulateRows(const ModelEntry& model, const FilterSpec& spec, const FilterData& d,
                              size_t first, size_t count, const std::vector<double>& x0) {
  SimulationSpec s;
  s.params = spec.params;
  s.x0 = x0;
  s.times.assign(d.t.begin() + long(first), d.t.begin() + long(first + count));
  const long nu = d.nu;
  if (nu > 0)
    s.inputs.assign(d.u.begin() + long(first) * nu, d.u.begin() + long(first + count) * nu);
  s.input = spec.input;
  s.transition = spec.transition;
  s.measurement = spec.measurement;
  return model.simulate(s);
}

// The errors of a set of simulations (outputs fastest): a missing
// measurement is a zero error that `observed` marks 0, so that it neither
// moves the fit nor counts in an RMSE, a residual count or sigma.
struct Errors {
  std::vector<double> e;
  std::vector<char> observed;
  long Count() const { return long(std::count(observed.begin(), observed.end(), char(1))); }
};

// Appends the errors of rows [first + skip, first + count) of `d` against the
// simulation `r` of rows [first, first + count) (outputs fastest).
void AppendErrors(const MeasurementDesc& meas, const FilterData& d, const SimulationResult& r,
                  size_t first, size_t count, size_t skip, Errors* e) {
  const int m = int(meas.outputs.size());
  const size_t first_z = r.columns.size() - size_t(m);  // t, states, z_<outputs>
  for (size_t i = skip; i < count; ++i) {
    for (int j = 0; j < m; ++j) {
      const double z = d.z[(first + i) * m + j];
      const bool seen = std::isfinite(z);
      double err = seen ? z - r.rows[i][first_z + j] : 0.0;
      if (meas.angle_outputs[j]) err = WrapAngle(err);
      e->e.push_back(err);
      e->observed.push_back(seen ? 1 : 0);
    }
  }
}

// Where one run's simulations start: windows from its recorded states, or
// the whole record from x0.
struct RunStart {
  bool windows = false;
  std::vector<double> x0;  // the whole record's start
};

// Appends the free-simulation errors of one run to *e; false with *why when
// a simulation fails.
bool RunErrors(const ModelEntry& model, const FilterSpec& spec, const FilterData& d,
               const RunStart& start, double horizon, Errors* e, long* windows, std::string* why) {
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  const int n = int(model.states.size());
  const size_t rows = d.t.size();
  const size_t per =
      start.windows ? std::max<size_t>(2, size_t(std::llround(horizon / EvenStep(d))) + 1) : rows;
  for (size_t w = 0; w == 0 || w + 1 < rows; w += per - 1) {
    const size_t count = std::min(per, rows - w);
    const std::vector<double> x0 = start.windows
                                       ? std::vector<double>(d.truth.begin() + long(w * n),
                                                             d.truth.begin() + long((w + 1) * n))
                                       : start.x0;
    const SimulationResult r = SimulateRows(model, spec, d, w, count, x0);
    if (!r.ok || r.rows.size() < count) {
      *why = "the simulation from " + d.path + " row " + std::to_string(w) +
             " (t = " + FormatNumber(d.t[w]) + ") failed: " + r.error;
      return false;
    }
    ++*windows;
    AppendErrors(meas, d, r, w, count, w == 0 ? 0 : 1, e);  // window starts counted once
    if (count == rows) break;
  }
  return true;
}

// sqrt(mean e^2) per output over its observed errors (outputs fastest; NaN
// for an output never observed), scaled by the largest |e| so that errors
// near the largest double (a diverged record) give a finite RMSE rather
// than an overflowed inf.
std::vector<double> Rmse(const Errors& errors, int m) {
  const std::vector<double>& e = errors.e;
  std::vector<double> scale(m, 0.0), sum(m, 0.0);
  std::vector<long> n(m, 0);
  for (size_t i = 0; i < e.size(); ++i) {
    if (!errors.observed[i]) continue;
    scale[i % m] = std::max(scale[i % m], std::abs(e[i]));
    ++n[i % m];
  }
  for (size_t i = 0; i < e.size(); ++i) {
    const double s = scale[i % m];
    if (errors.observed[i] && s > 0) sum[i % m] += (e[i] / s) * (e[i] / s);
  }
  for (int j = 0; j < m; ++j)
    sum[j] = n[j] > 0 ? scale[j] * std::sqrt(sum[j] / double(n[j])) : std::nan("");
  return sum;
}

// theta -> (spec, each run's start): the parameters first, then the
// estimated x0 components of each x0 row (one row, or one per run).
struct ThetaMap {
  std::vector<int> index;  // into model.params
  std::vector<ThetaScale> scale;
  std::vector<int> x0_index;            // estimated states
  std::vector<std::vector<double>> x0;  // rows of whole initial states
  std::vector<RunStart> starts;         // per run (x0 filled by At)
  std::vector<size_t> x0_row;           // per run: its x0 row

  FilterSpec At(const FilterSpec& spec, const double* theta,
                std::vector<RunStart>* starts_at = nullptr) const {
    FilterSpec s = spec;
    for (size_t j = 0; j < index.size(); ++j) s.params[index[j]] = scale[j].Natural(theta[j]);
    std::vector<std::vector<double>> rows = x0;
    size_t at = index.size();
    for (std::vector<double>& row : rows)
      for (int i : x0_index) row[i] = theta[at++];
    if (!rows.empty()) s.x0 = rows[0];
    if (starts_at != nullptr) {
      *starts_at = starts;
      for (size_t r = 0; r < starts.size(); ++r)
        if (!starts[r].windows) (*starts_at)[r].x0 = rows[x0_row[r]];
    }
    return s;
  }
};

// The weight of each output's errors: w_j = sqrt(R_11 / R_jj) from the
// spec's R (the noise variances the user gives), so that outputs in other
// units or with other noise count as their noise says and the residual sd is
// in the first output's units; 1 for every output when R has no positive
// diagonal. A single output is never reweighted.
std::vector<double> OutputWeights(const FilterSpec& spec, int m) {
  std::vector<double> w(size_t(m), 1.0);
  if (spec.r.size() != size_t(m) * size_t(m)) return w;
  for (int j = 0; j < m; ++j)
    if (!(spec.r[size_t(j) * m + j] > 0) || !std::isfinite(spec.r[size_t(j) * m + j])) return w;
  for (int j = 1; j < m; ++j) w[j] = std::sqrt(spec.r[0] / spec.r[size_t(j) * m + j]);
  return w;
}

class SimulationErrors {
 public:
  SimulationErrors(const ModelEntry& model, const FilterSpec& spec, const ThetaMap& map,
                   const std::vector<FilterData>& runs, double horizon, std::vector<double> weights)
      : model_(model),
        spec_(spec),
        map_(map),
        runs_(runs),
        horizon_(horizon),
        weights_(std::move(weights)) {}
  // The weighted errors w_j e (OutputWeights).
  bool operator()(double const* const* parameters, double* residuals) const {
    Errors e;
    if (!At(parameters[0], &e)) return false;
    const size_t m = weights_.size();
    for (size_t i = 0; i < e.e.size(); ++i) residuals[i] = weights_[i % m] * e.e[i];
    return true;
  }
  bool At(const double* theta, Errors* e, long* windows = nullptr) const {
    std::vector<RunStart> starts;
    const FilterSpec s = map_.At(spec_, theta, &starts);
    long w = 0;
    for (size_t r = 0; r < runs_.size(); ++r)
      if (!RunErrors(model_, s, runs_[r], starts[r], horizon_, e, &w, &why_)) return false;
    if (windows != nullptr) *windows = w;
    return true;
  }
  const std::string& why() const { return why_; }

 private:
  const ModelEntry& model_;
  const FilterSpec& spec_;
  const ThetaMap& map_;
  const std::vector<FilterData>& runs_;
  double horizon_;
  std::vector<double> weights_;
  mutable std::string why_;
};

// The parameters of `estimate` into map and result (names, scales, bounds).
void MapParams(const ModelEntry& model, const FilterSpec& spec,
               const std::vector<EstimatedParam>& estimate, double bound_width, ThetaMap* map,
               OutputErrorResult* r, std::vector<double>* lower, std::vector<double>* upper) {
  std::vector<std::string> names;
  for (const ParamDesc& d : model.params) names.push_back(d.name);
  for (const EstimatedParam& e : estimate) {
    const int found = FindEstimatedParam(e.name, names, model.name);
    for (int i : map->index)
      if (i == found) throw InputError("--estimate-param: '" + e.name + "' is named twice");
    if (e.has_prior) throw InputError("--param-prior applies to --estimator ml only");
    const double v = spec.params[found];
    const ThetaScale s = ResolveThetaScale(e, model.params[found].constraint, v, bound_width);
    map->index.push_back(found);
    map->scale.push_back(s);
    r->names.push_back((s.is_log ? "log " : "") + e.name);
    r->is_log.push_back(s.is_log);
    r->param_names.push_back(e.name);
    r->param_initial.push_back(v);
    r->theta_initial.push_back(s.theta0);
    lower->push_back(s.lower);
    upper->push_back(s.upper);
  }
}

// Each run's start (windows or the whole record) and the estimated x0
// components into map and result; InputError for a state that is not one,
// a state named twice, x0_per_file with one run, or data with neither state
// columns nor a whole-record start.
void MapStarts(const ModelEntry& model, const FilterSpec& spec, const std::vector<FilterData>& runs,
               const OutputErrorOptions& options, ThetaMap* map, OutputErrorResult* r,
               std::vector<double>* lower, std::vector<double>* upper) {
  const InitialStates x0s = ResolveInitialStates(options.estimate_x0, options.x0_per_file,
                                                 runs.size(), model.states, model.name);
  map->x0_index = x0s.index;
  for (int i : x0s.index) r->x0_names.push_back(model.states[i]);
  const bool whole = !x0s.empty();
  map->x0.assign(std::max(x0s.rows, 1), spec.x0);
  for (const std::string& name : x0s.Names(model.states)) r->names.push_back(name);
  for (int row = 0; row < x0s.rows; ++row) {
    for (int i : x0s.index) {
      r->is_log.push_back(false);
      r->theta_initial.push_back(spec.x0[i]);
      lower->push_back(-std::numeric_limits<double>::infinity());
      upper->push_back(std::numeric_limits<double>::infinity());
    }
  }
  for (size_t k = 0; k < runs.size(); ++k) {
    map->starts.push_back({.windows = !whole && runs[k].has_truth, .x0 = {}});
    map->x0_row.push_back(options.x0_per_file ? k : 0);
  }
  for (const RunStart& s : map->starts)
    if (!s.windows && spec.x0_first_sample)
      throw InputError(
          "output-error over the whole record starts from x0: give --x0 "
          "(x0 = first-sample is not supported here) or --estimate-x0");
  const bool windows = map->starts[0].windows;
  r->start = windows ? "windows of the horizon from the recorded states"
             : whole ? (options.x0_per_file ? "the whole record from each file's estimated x0"
                                            : "the whole record from the estimated x0")
                     : "the whole record from the prior mean x0 (--x0)";
}

// The standard errors and estimates on the natural scale, from the Jacobian
// of the residuals at the fit.
void StandardErrors(const ceres::CRSMatrix& jac, const ThetaMap& map,
                    const std::vector<double>& lower, const std::vector<double>& upper,
                    OutputErrorResult* r) {
  const int k = int(map.index.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(jac.num_rows, jac.num_cols);
  for (int row = 0; row < jac.num_rows; ++row)
    for (int i = jac.rows[row]; i < jac.rows[row + 1]; ++i) J(row, jac.cols[i]) = jac.values[i];
  const Eigen::MatrixXd H = J.transpose() * J / (r->residual_sd * r->residual_sd);
  const FisherReport report = AnalyseFisher(H, r->theta, r->names, r->is_log, r->theta_initial);
  r->std_errors = report.std_errors;
  r->identifiability = report.sentences;
  for (int j = 0; j < k; ++j) {
    const double v = map.scale[j].Natural(r->theta[j]);
    r->param_values.push_back(v);
    r->param_std_errors.push_back(map.scale[j].is_log ? v * r->std_errors[j] : r->std_errors[j]);
    const double tol = 1e-6 * std::max(1.0, std::abs(r->theta[j]));
    r->at_bound.push_back(std::abs(r->theta[j] - lower[j]) <= tol ||
                          std::abs(r->theta[j] - upper[j]) <= tol);
  }
  int at = k;
  for (size_t row = 0; row < map.x0.size() && !map.x0_index.empty(); ++row) {
    std::vector<double> x0 = map.x0[row];
    std::vector<double> se(x0.size(), std::nan(""));
    for (int i : map.x0_index) {
      x0[i] = r->theta[at];
      se[i] = r->std_errors[at++];
    }
    r->x0.push_back(x0);
    r->x0_std_errors.push_back(se);
  }
}

}  // namespace

bool EvenlySampled(const FilterData& d) {
  if (d.t.size() < 2) return false;
  const double dt = MeanStep(d);
  for (size_t k = 1; k < d.t.size(); ++k)
    if (Uneven(d, k, dt)) return false;
  return true;
}

bool OutputErrorOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(horizon > 0 && std::isfinite(horizon)))
    return fail("--horizon must be > 0 s, got " + FormatNumber(horizon));
  if (max_iterations < 1 || !(theta_step > 0) || !(bound_width > 0))
    return fail("output-error: max iterations >= 1, a positive step and bound width");
  return true;
}

std::vector<double> FreeSimulationRmse(const ModelEntry& model, const FilterSpec& spec,
                                       const FilterData& data, double horizon) {
  if (!data.has_truth)
    throw InputError(data.path +
                     ": free simulation over windows starts each window from the recorded "
                     "state: the data need a column per state (map them with --column, e.g. "
                     "theta=angle-pi)");
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  Errors e;
  long windows = 0;
  std::string why;
  if (!RunErrors(model, spec, data, {.windows = true, .x0 = {}}, horizon, &e, &windows, &why))
    return std::vector<double>(m, std::nan(""));
  return Rmse(e, m);
}

FreeSimulation WholeRecordSimulation(const ModelEntry& model, const FilterSpec& spec,
                                     const FilterData& data, const std::vector<double>& x0) {
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  const size_t rows = data.t.size();
  FreeSimulation sim;
  if (rows == 0) {
    sim.why = data.path + " has no rows";
    return sim;
  }
  const SimulationResult r = SimulateRows(model, spec, data, 0, rows, x0);
  if (!r.ok || r.rows.size() < rows) {
    sim.why = "the simulation from " + data.path + " row 0 (t = " + FormatNumber(data.t[0]) +
              ") failed: " + r.error;
    return sim;
  }
  const size_t m = meas.outputs.size(), first_z = r.columns.size() - m;
  for (size_t k = 0; k < rows; ++k)
    for (size_t j = 0; j < m; ++j) sim.y.push_back(r.rows[k][first_z + j]);
  Errors e;
  AppendErrors(meas, data, r, 0, rows, 0, &e);
  sim.e = e.e;
  sim.ok = e.Count() > 0;
  if (sim.ok) {
    sim.rmse = Rmse(e, int(m));
  } else {
    sim.why = data.path + " has no finite measurement to compare with";
  }
  return sim;
}

std::vector<double> WholeRecordRmse(const ModelEntry& model, const FilterSpec& spec,
                                    const FilterData& data, const std::vector<double>& x0) {
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  const FreeSimulation sim = WholeRecordSimulation(model, spec, data, x0);
  return sim.ok ? sim.rmse : std::vector<double>(m, std::nan(""));
}

OutputErrorResult FitOutputError(const ModelEntry& model, const FilterSpec& spec,
                                 const std::vector<EstimatedParam>& estimate,
                                 const std::vector<FilterData>& runs,
                                 const OutputErrorOptions& options) {
  const auto clock_start = std::chrono::steady_clock::now();
  std::string error;
  if (!options.IsValid(&error)) throw InputError(error);
  if (estimate.empty() && options.estimate_x0.empty())
    throw InputError("--estimator output-error needs --estimate-param or --estimate-x0");
  if (runs.empty()) throw InputError("output-error needs a --data file");
  OutputErrorResult r;
  ThetaMap map;
  std::vector<double> lower, upper;
  MapParams(model, spec, estimate, options.bound_width, &map, &r, &lower, &upper);
  MapStarts(model, spec, runs, options, &map, &r, &lower, &upper);
  const int p = int(r.theta_initial.size());
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  const std::vector<double> weights = OutputWeights(spec, m);
  r.output_weights = weights;
  const SimulationErrors errors(model, spec, map, runs, options.horizon, weights);
  Errors e0;
  if (!errors.At(r.theta_initial.data(), &e0, &r.windows))
    throw InputError("output-error at the initial parameters: " + errors.why());
  r.residuals = e0.Count();  // the observed ones
  if (r.residuals == 0)
    throw InputError(
        "output-error: the data have no finite measurement to fit (every z cell "
        "is empty or NaN)");
  for (size_t i = 0; i < e0.e.size(); ++i)
    r.cost_initial += 0.5 * (weights[i % m] * e0.e[i]) * (weights[i % m] * e0.e[i]);

  ceres::NumericDiffOptions step;
  step.relative_step_size = options.theta_step;
  auto* cost = new ceres::DynamicNumericDiffCostFunction<SimulationErrors, ceres::CENTRAL>(
      new SimulationErrors(model, spec, map, runs, options.horizon, weights), ceres::TAKE_OWNERSHIP,
      step);
  cost->AddParameterBlock(p);
  cost->SetNumResiduals(int(e0.e.size()));
  std::vector<double> theta = r.theta_initial;
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, theta.data());
  for (int j = 0; j < p; ++j) {
    if (std::isfinite(lower[j])) problem.SetParameterLowerBound(theta.data(), j, lower[j]);
    if (std::isfinite(upper[j])) problem.SetParameterUpperBound(theta.data(), j, upper[j]);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.logging_type = ceres::SILENT;
  so.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  r.theta = theta;
  r.message = summary.message;
  r.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  r.ok = summary.IsSolutionUsable();
  r.fitted_spec = map.At(spec, theta.data());

  ceres::CRSMatrix jac;
  Errors e{.e = {}, .observed = e0.observed};  // the same cells are missing at every theta
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &r.cost, &e.e, nullptr, &jac);
  r.converged = r.ok && summary.termination_type == ceres::CONVERGENCE && r.cost <= r.cost_initial;
  if (r.ok && !r.converged && summary.termination_type == ceres::CONVERGENCE)
    r.message = "the final squared error " + FormatNumber(2 * r.cost) + " exceeds the initial " +
                FormatNumber(2 * r.cost_initial);
  for (size_t i = 0; i < e.e.size(); ++i) e.e[i] /= weights[i % m];  // back in each output's units
  r.rmse = Rmse(e, m);
  r.residual_sd = std::sqrt(2.0 * r.cost / double(std::max<long>(1, r.residuals - p)));
  for (int j = 0; j < m; ++j) r.residual_sds.push_back(r.residual_sd / weights[j]);
  StandardErrors(jac, map, lower, upper, &r);
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return r;
}

}  // namespace estlab
