#include "src/cli/tune_validate.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "src/core/parse.h"
#include "src/io/memory_files.h"
#include "src/options/filter_flags.h"
#include "src/options/truth_flags.h"
#include "studies/run/output_error.h"

namespace estlab::cli {
namespace {

namespace po = boost::program_options;

// The text between the brackets after "key": ('[' or '{'), or "" when absent.
std::string JsonBracketed(const std::string& text, const std::string& key, char open) {
  const size_t at = text.find("\"" + key + "\"");
  if (at == std::string::npos) return "";
  size_t i = text.find(':', at);
  if (i == std::string::npos) return "";
  i = text.find_first_not_of(" \t\r\n", i + 1);
  if (i == std::string::npos || text[i] != open) return "";
  const size_t end = text.find(open == '[' ? ']' : '}', i);
  return end == std::string::npos ? "" : text.substr(i + 1, end - i - 1);
}

// The numbers of "key": [a, b, ...] in a JSON text (null -> NaN); false when
// the key is absent.
bool JsonNumberArray(const std::string& text, const std::string& key, std::vector<double>* out) {
  if (text.find("\"" + key + "\"") == std::string::npos) return false;
  const std::string inner = JsonBracketed(text, key, '[');
  out->clear();
  std::stringstream items(inner);
  std::string item;
  while (std::getline(items, item, ',')) {
    const std::string v = Trim(item);
    if (v.empty()) continue;
    out->push_back(v == "null" ? std::nan("") : ParseNumber(v, key));
  }
  return true;
}

// The simulation's parameters ("params": {"g": 9.81, ...}) in the model's
// order; empty when the sidecar has none or misses one.
std::vector<double> SidecarParams(const std::string& text, const ModelEntry& model) {
  const std::string inner = JsonBracketed(text, "params", '{');
  std::vector<double> out;
  for (const ParamDesc& p : model.params) {
    const size_t at = inner.find("\"" + p.name + "\"");
    if (at == std::string::npos) return {};
    const size_t colon = inner.find(':', at);
    const size_t end = inner.find(',', colon);
    out.push_back(ParseNumber(Trim(inner.substr(colon + 1, end - colon - 1)), "params"));
  }
  return out;
}

// `data` is scored against its truth when it has one; the free simulation
// starts from the recorded states of `recorded` (its state columns, truth
// or not).
ValidationRun RunOn(const ModelEntry& model, const FilterSpec& spec, const FilterData& data,
                    const FilterData& recorded, const std::vector<std::string>& outputs,
                    int burn_in, double horizon) {
  const FilterRunOutput out = model.run_filter(spec, data);
  // The burn-in counts updates, as the tuner's; rows without an update are
  // few in recorded data, so skip that many rows.
  ValidationRun r{out.summary, ComputeNoTruthMetrics(out, outputs, burn_in), {}, {}};
  if (recorded.has_truth && EvenlySampled(recorded))
    r.free_rmse = FreeSimulationRmse(model, spec, recorded, horizon);
  if (out.summary.x0.size() == model.states.size())
    r.whole_rmse = WholeRecordRmse(model, spec, recorded, out.summary.x0);
  return r;
}

Validation ValidateOne(const po::variables_map& vm, const std::string& path,
                       const ModelEntry& model, const FilterSpec& spec, const FilterSpec& tuned,
                       int burn_in, double horizon) {
  Validation v;
  v.path = path;
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  // The state columns when the file has them (the free simulation's start
  // points); scored as truth only when the file or --truth says so.
  const FilterData recorded =
      LoadFilterData(path, model, meas, ParseColumnRenames(vm), true, ConstantInputGiven(vm));
  FilterData data = recorded;
  if (!ResolveTruth(vm, path, model).read) {
    data.has_truth = false;
    data.truth.clear();
  }
  CheckPriorTime(spec, data);
  for (size_t j = 0; j < meas.outputs.size(); ++j) {  // as the training files (tuner.h)
    bool any = false;
    for (size_t k = 0; k < data.t.size() && !any; ++k)
      any = std::isfinite(data.z[k * meas.outputs.size() + j]);
    if (!any)
      throw InputError(path + ": measurement column z_" + meas.outputs[j] +
                       " has no value (all missing)");
  }
  v.initial = RunOn(model, spec, data, recorded, meas.outputs, burn_in, horizon);
  v.tuned = RunOn(model, tuned, data, recorded, meas.outputs, burn_in, horizon);
  v.states = model.states;
  v.x0 = v.tuned.summary.x0;

  // The true noise: --true-q-diag / --true-r-diag, else the simulate sidecar
  // (whose parameters are then the true ones too).
  const int n = int(model.states.size()), m = int(meas.outputs.size());
  std::vector<double> q_diag, r_diag, params, x0;
  std::string source;
  if (const std::optional<std::string> text = ReadSidecar(path)) {
    const bool has_q = JsonNumberArray(*text, "process_noise_var", &q_diag);
    const bool has_r = JsonNumberArray(*text, "meas_noise_var", &r_diag);
    if (has_q && q_diag.empty()) q_diag.assign(n, 0.0);  // simulated without process noise
    if (has_q || has_r) source = path + ".json";
    params = SidecarParams(*text, model);
    if (!JsonNumberArray(*text, "x0", &x0) || x0.size() != size_t(n)) x0.clear();
  }
  if (vm.count("true-q-diag")) {
    q_diag = ParseList(vm["true-q-diag"].as<std::string>(), "--true-q-diag");
    RequireLength(q_diag, n, "--true-q-diag", "one per state");
    source = "--true-q-diag/--true-r-diag";
  }
  if (vm.count("true-r-diag")) {
    r_diag = ParseList(vm["true-r-diag"].as<std::string>(), "--true-r-diag");
    RequireLength(r_diag, m, "--true-r-diag", "one per output");
    source = "--true-q-diag/--true-r-diag";
  }
  if (q_diag.size() == size_t(n) && r_diag.size() == size_t(m)) {
    RequireNonNegative(q_diag, "true process noise");
    RequireNonNegative(r_diag, "true measurement noise");
    FilterSpec oracle = spec;
    if (!params.empty()) oracle.params = params;
    if (!x0.empty() && !params.empty()) {  // the simulation's start: the true prior mean
      oracle.x0 = x0;
      oracle.x0_first_sample = false;
    }
    oracle.q_white_accel = false;
    oracle.q.assign(n * n, 0.0);
    for (int i = 0; i < n; ++i) oracle.q[i * n + i] = q_diag[i];
    oracle.r.assign(m * m, 0.0);
    for (int i = 0; i < m; ++i) oracle.r[i * m + i] = r_diag[i];
    v.oracle = RunOn(model, oracle, data, recorded, meas.outputs, burn_in, horizon);
    v.oracle_source = source;
  }
  return v;
}

}  // namespace

std::vector<Validation> ValidateAll(const po::variables_map& vm, const ModelEntry& model,
                                    const FilterSpec& spec, const FilterSpec& tuned, int burn_in,
                                    double horizon) {
  if (model.run_filter == nullptr)
    throw InputError("--validate: the filter runner of model '" + model.name +
                     "' is not available");
  std::vector<Validation> out;
  for (const std::string& path : vm["validate"].as<std::vector<std::string>>())
    out.push_back(ValidateOne(vm, path, model, spec, tuned, burn_in, horizon));
  return out;
}

void PrintValidation(const Validation& v, const std::vector<std::string>& outputs, double horizon) {
  std::cout << "\nvalidation on " << v.path << "\n  prior mean  ";
  for (size_t i = 0; i < v.x0.size() && i < v.states.size(); ++i)
    std::cout << (i ? ", " : "") << v.states[i] << " = " << v.x0[i];
  std::cout << "  (the whole-file free simulation's start; inputs held between samples)";
  std::cout << "\n  setting    NLL/step    mean NIS (95% bounds)          pred RMSE ("
            << outputs.size() << ")   free-sim RMSE over " << horizon
            << " s   free-sim RMSE whole file   mean NEES   RMSE\n";
  auto row = [&](const char* name, const ValidationRun& r) {
    const NoTruthMetrics& m = r.metrics;
    std::cout << "  " << std::left << std::setw(9) << name << std::right << std::setw(10)
              << m.nll_per_step << "  " << std::setw(9) << m.mean_nis << " (" << m.nis_bounds95[0]
              << " .. " << m.nis_bounds95[1] << ")  ";
    for (size_t i = 0; i < m.pred_rmse.size(); ++i) std::cout << (i ? ", " : "") << m.pred_rmse[i];
    std::cout << "  ";
    for (size_t i = 0; i < r.free_rmse.size(); ++i) std::cout << (i ? ", " : "") << r.free_rmse[i];
    if (r.free_rmse.empty()) std::cout << "- (needs state columns, evenly sampled)";
    std::cout << "  ";
    for (size_t i = 0; i < r.whole_rmse.size(); ++i)
      std::cout << (i ? ", " : "") << r.whole_rmse[i];
    if (r.whole_rmse.empty()) std::cout << "-";
    const FilterSummary& s = r.summary;
    if (!s.rmse.empty()) {
      std::cout << "  " << std::setw(9) << s.mean_nees << "  ";
      for (size_t i = 0; i < s.rmse.size(); ++i) std::cout << (i ? ", " : "") << s.rmse[i];
    }
    std::cout << (s.ok ? "" : "  (" + s.status + ")") << "\n";
  };
  row("initial", v.initial);
  row("tuned", v.tuned);
  if (v.oracle) row("true", *v.oracle);
}

namespace {

void WriteRun(JsonWriter* j, const ValidationRun& r, const std::vector<std::string>& outputs) {
  const FilterSummary& s = r.summary;
  const NoTruthMetrics& m = r.metrics;
  j->BeginObject().Key("status").Value(s.status);
  if (!s.ok) j->Key("message").Value(s.message);
  j->Key("updates").Value(m.updates);
  j->Key("nll_per_step").Value(m.nll_per_step);
  j->Key("mean_nis").Value(m.mean_nis);
  j->Key("nis_bounds95").Value(std::vector<double>{m.nis_bounds95[0], m.nis_bounds95[1]});
  j->Key("pred_rmse").Object(outputs, m.pred_rmse);
  if (!r.free_rmse.empty()) j->Key("free_rmse").Object(outputs, r.free_rmse);
  if (!r.whole_rmse.empty()) j->Key("whole_rmse").Object(outputs, r.whole_rmse);
  if (!s.rmse.empty()) {
    j->Key("rmse").BeginObject();
    for (size_t i = 0; i < s.rmse.size(); ++i) j->Key(s.states[i]).Value(s.rmse[i]);
    j->EndObject().Key("truth_rows").BeginObject();
    for (size_t i = 0; i < s.truth_rows.size(); ++i) j->Key(s.states[i]).Value(s.truth_rows[i]);
    j->EndObject();
    j->Key("mean_nees").Value(s.mean_nees);
    j->Key("nees_bounds95").Value(std::vector<double>{s.nees_bounds95[0], s.nees_bounds95[1]});
  }
  j->EndObject();
}

}  // namespace

void WriteValidationJson(JsonWriter* j, const Validation& v,
                         const std::vector<std::string>& outputs) {
  j->BeginObject().Key("data").Value(v.path);
  j->Key("x0").BeginObject();
  for (size_t i = 0; i < v.x0.size() && i < v.states.size(); ++i)
    j->Key(v.states[i]).Value(v.x0[i]);
  j->EndObject();
  j->Key("initial");
  WriteRun(j, v.initial, outputs);
  j->Key("tuned");
  WriteRun(j, v.tuned, outputs);
  j->Key("oracle");
  if (v.oracle) {
    WriteRun(j, *v.oracle, outputs);
    j->Key("oracle_source").Value(v.oracle_source);
  } else {
    j->Null();
  }
  j->EndObject();
}

}  // namespace estlab::cli
