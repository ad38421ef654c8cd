#include "studies/output_error.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "adaptive/identifiability.h"
#include "adaptive/theta_scale.h"
#include "src/core/types.h"

namespace estlab {
namespace {


// The data's sampling step; InputError unless evenly sampled.
double EvenStep(const FilterData& d) {
  if (d.t.size() < 2) throw InputError(d.path + ": output-error needs at least two rows");
  const double dt = (d.t.back() - d.t.front()) / double(d.t.size() - 1);
  for (size_t k = 1; k < d.t.size(); ++k) {
    if (std::abs(d.t[k] - d.t[k - 1] - dt) > 1e-6 * dt + 1e-12)
      throw InputError(d.path + ":" + std::to_string(d.lines[k]) +
                       ": output-error needs evenly sampled data (step " + FormatNumber(dt) +
                       ", here " + FormatNumber(d.t[k] - d.t[k - 1]) + ")");
  }
  return dt;
}

void CheckRun(const ModelEntry& model, const FilterData& d) {
  if (model.has_input) throw InputError("output-error: models with an input are not supported");
  if (!d.has_truth)
    throw InputError(d.path +
                     ": output-error and free simulation start each window from the "
                     "recorded state: the data need a column per state (map them with "
                     "--column, e.g. theta=angle-pi)");
}

// Appends the free-simulation errors of one run to *e (row-major, outputs
// fastest); false with *why when a simulation fails.
bool RunErrors(const ModelEntry& model, const FilterSpec& spec, const FilterData& d, double horizon,
               std::vector<double>* e, long* windows, std::string* why) {
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  const int n = int(model.states.size()), m = int(meas.outputs.size());
  const double dt = EvenStep(d);
  const size_t rows = d.t.size();
  const size_t per = std::max<size_t>(2, size_t(std::llround(horizon / dt)) + 1);
  for (size_t w = 0; w + 1 < rows; w += per - 1) {
    const size_t count = std::min(per, rows - w);
    SimulationSpec s;
    s.params = spec.params;
    s.x0.assign(d.truth.begin() + long(w * n), d.truth.begin() + long((w + 1) * n));
    s.t_end = double(count - 1) * dt;
    s.dt = dt;
    s.transition = spec.transition;
    s.measurement = spec.measurement;
    const SimulationResult r = model.simulate(s);
    if (!r.ok || r.rows.size() < count) {
      *why = "the simulation from " + d.path + " row " + std::to_string(w) +
             " (t = " + FormatNumber(d.t[w]) + ") failed: " + r.error;
      return false;
    }
    ++*windows;
    const size_t first_z = r.columns.size() - size_t(m);  // t, states, z_<outputs>
    for (size_t i = (w == 0 ? 0 : 1); i < count; ++i) {   // window starts counted once
      for (int j = 0; j < m; ++j) {
        const double z = d.z[(w + i) * m + j];
        double err = std::isfinite(z) ? z - r.rows[i][first_z + j] : 0.0;
        if (meas.angle_outputs[j]) err = WrapAngle(err);
        e->push_back(err);
      }
    }
  }
  return true;
}

struct ThetaMap {
  std::vector<int> index;  // into model.params
  std::vector<ThetaScale> scale;
  FilterSpec At(const FilterSpec& spec, const double* theta) const {
    FilterSpec s = spec;
    for (size_t j = 0; j < index.size(); ++j) s.params[index[j]] = scale[j].Natural(theta[j]);
    return s;
  }
};

class SimulationErrors {
 public:
  SimulationErrors(const ModelEntry& model, const FilterSpec& spec, const ThetaMap& map,
                   const std::vector<FilterData>& runs, double horizon)
      : model_(model), spec_(spec), map_(map), runs_(runs), horizon_(horizon) {}
  bool operator()(double const* const* parameters, double* residuals) const {
    std::vector<double> e;
    if (!Errors(parameters[0], &e)) return false;
    std::copy(e.begin(), e.end(), residuals);
    return true;
  }
  bool Errors(const double* theta, std::vector<double>* e, long* windows = nullptr) const {
    const FilterSpec s = map_.At(spec_, theta);
    long w = 0;
    for (const FilterData& d : runs_)
      if (!RunErrors(model_, s, d, horizon_, e, &w, &why_)) return false;
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
  mutable std::string why_;
};

std::vector<double> Rmse(const std::vector<double>& e, int m) {
  std::vector<double> sum(m, 0.0);
  for (size_t i = 0; i < e.size(); ++i) sum[i % m] += e[i] * e[i];
  for (double& v : sum) v = std::sqrt(v / double(e.size() / size_t(m)));
  return sum;
}

}  // namespace

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
  CheckRun(model, data);
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  std::vector<double> e;
  long windows = 0;
  std::string why;
  if (!RunErrors(model, spec, data, horizon, &e, &windows, &why) || e.empty())
    return std::vector<double>(m, std::nan(""));
  return Rmse(e, m);
}

OutputErrorResult FitOutputError(const ModelEntry& model, const FilterSpec& spec,
                                 const std::vector<EstimatedParam>& estimate,
                                 const std::vector<FilterData>& runs,
                                 const OutputErrorOptions& options) {
  const auto clock_start = std::chrono::steady_clock::now();
  std::string error;
  if (!options.IsValid(&error)) throw InputError(error);
  if (estimate.empty()) throw InputError("--estimator output-error needs --estimate-param");
  for (const FilterData& d : runs) CheckRun(model, d);
  OutputErrorResult r;
  ThetaMap map;
  std::vector<double> lower, upper;
  std::vector<std::string> names;
  for (const ParamDesc& d : model.params) names.push_back(d.name);
  for (const EstimatedParam& e : estimate) {
    const int found = FindEstimatedParam(e.name, names, model.name);
    for (int i : map.index)
      if (i == found) throw InputError("--estimate-param: '" + e.name + "' is named twice");
    if (e.has_prior) throw InputError("--param-prior applies to --estimator ml only");
    const double v = spec.params[found];
    const ThetaScale s =
        ResolveThetaScale(e, model.params[found].constraint, v, options.bound_width);
    map.index.push_back(found);
    map.scale.push_back(s);
    r.names.push_back((s.is_log ? "log " : "") + e.name);
    r.is_log.push_back(s.is_log);
    r.param_names.push_back(e.name);
    r.param_initial.push_back(v);
    r.theta_initial.push_back(s.theta0);
    lower.push_back(s.lower);
    upper.push_back(s.upper);
  }
  const int p = int(map.index.size());
  const int m = int(model.FindMeasurement(spec.measurement).outputs.size());
  const SimulationErrors errors(model, spec, map, runs, options.horizon);
  std::vector<double> e0;
  if (!errors.Errors(r.theta_initial.data(), &e0, &r.windows))
    throw InputError("output-error at the initial parameters: " + errors.why());
  r.residuals = long(e0.size());

  ceres::NumericDiffOptions step;
  step.relative_step_size = options.theta_step;
  auto* cost = new ceres::DynamicNumericDiffCostFunction<SimulationErrors, ceres::CENTRAL>(
      new SimulationErrors(model, spec, map, runs, options.horizon), ceres::TAKE_OWNERSHIP, step);
  cost->AddParameterBlock(p);
  cost->SetNumResiduals(int(e0.size()));
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
  r.converged = summary.termination_type == ceres::CONVERGENCE;
  r.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  r.ok = summary.IsSolutionUsable();
  r.fitted_spec = map.At(spec, theta.data());

  // sigma^2 (J^T J)^-1 through the Fisher analysis of H = J^T J / sigma^2.
  double final_cost = 0.0;
  ceres::CRSMatrix jac;
  std::vector<double> e;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &final_cost, &e, nullptr, &jac);
  r.rmse = Rmse(e, m);
  const double dof = double(std::max<long>(1, r.residuals - p));
  r.residual_sd = std::sqrt(2.0 * final_cost / dof);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(jac.num_rows, jac.num_cols);
  for (int row = 0; row < jac.num_rows; ++row)
    for (int k = jac.rows[row]; k < jac.rows[row + 1]; ++k) J(row, jac.cols[k]) = jac.values[k];
  const Eigen::MatrixXd H = J.transpose() * J / (r.residual_sd * r.residual_sd);
  const FisherReport report = AnalyseFisher(H, r.theta, r.names, r.is_log);
  r.std_errors = report.std_errors;
  r.identifiability = report.sentences;
  for (int j = 0; j < p; ++j) {
    const double v = map.scale[j].Natural(theta[j]);
    r.param_values.push_back(v);
    r.param_std_errors.push_back(map.scale[j].is_log ? v * r.std_errors[j] : r.std_errors[j]);
    const double tol = 1e-6 * std::max(1.0, std::abs(theta[j]));
    r.at_bound.push_back(std::abs(theta[j] - lower[j]) <= tol ||
                         std::abs(theta[j] - upper[j]) <= tol);
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock_start).count();
  return r;
}

}  // namespace estlab
