#include "src/cli/tune_output_error.h"

#include <algorithm>
#include <iomanip>
#include <iostream>

#include "src/cli/tune_x0.h"
#include "src/io/json.h"

namespace estlab::cli {
namespace {

const char* StatusName(const OutputErrorResult& r) {
  return r.ok ? (r.converged ? "converged" : "no-convergence") : "failed";
}

}  // namespace

X0Report FitX0(const ModelEntry& model, const FilterSpec& spec, const OutputErrorResult& r,
               const std::vector<FilterData>& runs) {
  return MakeX0Report(model.states, r.x0_names,
                      std::vector<std::vector<double>>(r.x0.size(), spec.x0), r.x0, r.x0_std_errors,
                      runs);
}

void PrintOutputError(const ModelEntry& model, const FilterSpec& spec, const OutputErrorResult& r,
                      const std::vector<FilterData>& runs, double horizon,
                      const std::vector<Validation>& validations, const std::string& out_path) {
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  std::cout << std::setprecision(6) << "model         " << model.name << ", measurement "
            << spec.measurement << "\nestimator     output-error least squares, free simulation"
            << " over " << r.start;
  if (r.start.find("windows") != std::string::npos) std::cout << " (" << horizon << " s)";
  std::cout << "\ndata          " << r.windows << " free simulation(s), " << r.residuals
            << " residuals\nstatus        " << StatusName(r) << "\noptimiser     " << r.message
            << " (" << r.iterations << " iterations)\n";
  std::cout << "\n  model parameter               initial     estimate         SE\n";
  for (size_t j = 0; j < r.param_names.size(); ++j) {
    std::cout << "  " << std::left << std::setw(26) << r.param_names[j] << std::right
              << std::setw(12) << r.param_initial[j] << " " << std::setw(12) << r.param_values[j]
              << " " << std::setw(10) << r.param_std_errors[j]
              << (r.at_bound[j] ? "  at a bound" : "") << "\n";
  }
  PrintX0(FitX0(model, spec, r, runs));
  for (const std::string& s : r.identifiability) std::cout << "  note: " << s << "\n";
  std::cout << "\nresidual sd   ";
  if (r.residual_sds.size() > 1) {  // weighted by R: each output's in its own units
    for (size_t j = 0; j < r.residual_sds.size(); ++j)
      std::cout << (j ? ", " : "") << meas.outputs[j] << " " << r.residual_sds[j];
    std::cout << "  (outputs weighted by 1/sqrt(R_jj), --init-r-diag)";
  } else {
    std::cout << r.residual_sd;
  }
  std::cout << "\nfit RMSE      ";
  for (size_t j = 0; j < r.rmse.size(); ++j)
    std::cout << (j ? ", " : "") << meas.outputs[j] << " " << r.rmse[j];
  std::cout << "\nwall time     " << r.wall_s << " s\n";
  for (const Validation& v : validations) PrintValidation(v, meas.outputs, horizon);
  if (!out_path.empty()) std::cout << "wrote         " << out_path << "\n";
}

std::string OutputErrorJson(const ModelEntry& model, const FilterSpec& spec,
                            const OutputErrorResult& r, const std::vector<FilterData>& runs,
                            double horizon, const std::vector<Validation>& validations,
                            const std::string& out_path) {
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  JsonWriter j;
  j.BeginObject().Key("model").Value(model.name).Key("measurement").Value(spec.measurement);
  j.Key("estimator").Value("output-error").Key("horizon").Value(horizon);
  j.Key("start").Value(r.start);
  j.Key("status").Value(StatusName(r));
  j.Key("message").Value(r.message);
  j.Key("tuned").BeginObject().Key("params").Object(r.param_names, r.param_values);
  const X0Report x0 = FitX0(model, spec, r, runs);
  WriteTunedX0Json(&j, x0);
  j.EndObject();
  j.Key("std_errors").Object(r.param_names, r.param_std_errors);
  WriteX0DetailJson(&j, x0);
  j.Key("params_initial").Object(r.param_names, r.param_initial);
  j.Key("parameters").Value(r.names).Key("theta").Value(r.theta);
  j.Key("identifiability").Value(r.identifiability);
  j.Key("cost_initial").Value(r.cost_initial).Key("cost").Value(r.cost);
  j.Key("residual_sd").Value(r.residual_sd).Key("fit_rmse").Object(meas.outputs, r.rmse);
  j.Key("residual_sds").Object(meas.outputs, r.residual_sds);
  j.Key("output_weights").Object(meas.outputs, r.output_weights);
  j.Key("windows").Value(r.windows).Key("residuals").Value(r.residuals);
  j.Key("iterations").Value(r.iterations).Key("wall_s").Value(r.wall_s);
  if (!validations.empty()) {
    j.Key("validation").BeginArray();
    for (const Validation& v : validations) WriteValidationJson(&j, v, meas.outputs);
    j.EndArray();
  }
  if (!out_path.empty()) j.Key("out").Value(out_path);
  j.EndObject();
  return j.str();
}

}  // namespace estlab::cli
