// estlab simulate: truth trajectories and noisy measurements.
#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "estlab_version.h"
#include "src/cli/commands.h"
#include "src/core/parse.h"
#include "src/io/json.h"
#include "src/io/output_file.h"
#include "src/options/filter_flags.h"
#include "src/options/sensor_rates.h"
#include "src/registry/registry.h"
#include "src/sim/input_signal.h"
#include "src/sim/simulator_impl.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {

constexpr const char* kExamples = R"(Examples:
  # Paper 003 double pendulum, CVODES truth, noisy angle measurements:
  estlab simulate --model double-pendulum --x0 theta1=0.785398,theta2=0.523599 \
      --t-end 10 --dt 0.01 --measure angles --meas-noise-var 0.0025,0.0016 --out traj.csv
  # Paper 002 pendulum with y = sin(theta), Euler truth with process noise:
  estlab simulate --model pendulum --param g=9.8 --x0 theta=0.785398 --t-end 5 --dt 0.0125 \
      --integrator euler --process-noise-var 1e-6,1e-4 --measure sin --meas-noise-var 0.09 \
      --seed 7 --out d.csv --json
  # Stiff Van der Pol with CVODES BDF:
  estlab simulate --model van-der-pol --x0 x=2 --t-end 3000 --dt 1 --out vdp.csv
  # Two sensor groups at their own rates: the cart's position at 1 Hz, the
  # pole's encoder every row (100 Hz); the position cells between are empty:
  estlab simulate --model cart-pole --x0 theta=3 --t-end 60 --dt 0.01 \
      --measure position,encoder --meas-noise-var 1e-4,1e-4 --sensor-rate position=1 --out mr.csv
  # Replay a recorded input: the times and the input column of pump.csv
  # (column 'volts' as the model's input u), noisy and noise-free outputs:
  estlab simulate --model two-tanks.model --data pump.csv --column u=volts \
      --x0 h1=0.1,h2=0.05 --measure level --meas-noise-var 1e-6 --out sim.csv
  # The same with the pump voltage interpolated linearly between samples:
  estlab simulate --model two-tanks.model --data pump.csv --column u=volts --input-hold linear \
      --x0 h1=0.1,h2=0.05 --measure level --out sim-linear.csv
  # A model with two inputs (voltage V, load force F): a multisine voltage and
  # a PRBS load, each with its own seed:
  estlab simulate --model examples/dc_cart/dc_cart.model --t-end 20 --dt 0.01 \
      --input 'multisine(rms=2, mean=6, band=0.05:2, sines=8, seed=1), prbs(amplitude=0.5, period=0.5, order=7, seed=2)' \
      --measure encoder-current --meas-noise-var 1e-6,1e-4 --out cart2.csv
  # A cart-pole pushed by a PRBS force (+-2 N, a new bit every 0.2 s), the
  # force written as column u:
  estlab simulate --model cart-pole --input 'prbs(amplitude=2, period=0.2, order=7)' \
      --t-end 10 --dt 0.02 --measure x-theta --meas-noise-var 1e-4,1e-4 --out cart.csv

Output: CSV with columns t,<states>[,z_<outputs>], one row per output time from
t = 0, values in %.17g; a sidecar <out>.json records model, parameters,
integrator, tolerances, x0, noise variances and seed. Process noise, when
given, is a draw N(0, diag(v)) added to the state after each output step.
With --data FILE the rows are at FILE's times (x0 at the first) and a model's
input is FILE's column named as the input, or 'u' (or --column u=NAME), held constant from each row to
the next (--input-hold zoh, the default) or following the line between the samples
(--input-hold linear); CVODES restarts at every sample where the input changes; the output then
has the input's column after the states and, with --meas-noise-var, the noise-free
outputs as y_<output> beside the noisy z_<output>.
On a CVODES failure the rows computed so far go to <out stem>.partial.csv
and the exit status is 1; bad input exits 2 and writes nothing.
)";

std::string PartialPath(const std::string& out) {
  const std::string ext = ".csv";
  if (out.size() > ext.size() && out.compare(out.size() - ext.size(), ext.size(), ext) == 0)
    return out.substr(0, out.size() - ext.size()) + ".partial.csv";
  return out + ".partial.csv";
}

std::string SidecarJson(const ModelEntry& model, const SimulationSpec& spec,
                        const std::string& integrator_name, const std::string& method,
                        const std::string& data_path, const std::string& input_text) {
  JsonWriter j;
  j.BeginObject();
  j.Key("estlab_version").Value(ESTLAB_VERSION).Key("git_commit").Value(ESTLAB_GIT_COMMIT);
  j.Key("model").Value(model.name);
  j.Key("params").BeginObject();
  for (size_t i = 0; i < model.params.size(); ++i)
    j.Key(model.params[i].name).Value(spec.params[i]);
  j.EndObject();
  j.Key("states").Value(model.states);
  j.Key("x0").Value(spec.x0);
  if (data_path.empty()) {  // k dt (with or without an input signal)
    j.Key("t_end").Value(spec.t_end).Key("dt").Value(spec.dt);
  } else {
    j.Key("data").Value(data_path).Key("t0").Value(spec.times.front());
    j.Key("t_end").Value(spec.times.back()).Key("rows").Value(long(spec.times.size()));
  }
  j.Key("integrator").Value(integrator_name);
  if (spec.transition.integrator == Integrator::kCvodes) {
    j.Key("method").Value(method);
    j.Key("rtol").Value(spec.transition.rtol).Key("atol").Value(spec.transition.atol);
    j.Key("max_steps").Value(spec.transition.max_steps);
  } else {
    j.Key("substeps").Value(spec.transition.substeps);
  }
  if (spec.inputs.empty() && spec.input.size() > 1)
    j.Key("input").Value(spec.input);
  else if (spec.inputs.empty())
    j.Key("input").Value(spec.input.empty() ? 0.0 : spec.input[0]);
  else if (data_path.empty())
    j.Key("input").Value(input_text + ", sampled at the output times");
  else
    j.Key("input").Value("recorded");
  j.Key("input_hold").Value(InputHoldName(spec.transition.input_hold));
  j.Key("process_noise_var").Value(spec.process_noise_var);
  if (!spec.measurement.empty()) {
    j.Key("measurement").Value(spec.measurement);
    j.Key("outputs").Value(model.FindMeasurement(spec.measurement).outputs);
  } else {
    j.Key("measurement").Null();
  }
  j.Key("meas_noise_var").Value(spec.meas_noise_var);
  j.Key("seed").Value(long(spec.seed));
  j.EndObject();
  return j.str() + "\n";
}

bool IsTunedFilterKey(const std::string& key) {
  for (const char* k : {"q", "q-diag", "q-white-accel", "r", "r-diag", "p0", "p0-diag",
                        "integrator", "substeps", "method", "rtol", "atol", "input-hold"})
    if (key == k) return true;
  return false;
}

// The `param = NAME=VALUE` lines of a tuned.ini (and its `x0 = NAME=VALUE,...`
// line into *x0); its filter noise, prior covariance and process-model lines
// (the filter's integrator and hold: the truth takes --integrator and
// --input-hold) are skipped, any other key is an error naming FILE:LINE.
std::vector<std::pair<std::string, double>> ConfigParams(
    const std::string& path, std::vector<std::pair<std::string, double>>* x0) {
  std::ifstream in(path);
  if (!in) throw InputError("--config: cannot read '" + path + "'");
  std::vector<std::pair<std::string, double>> out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string text = Trim(line.substr(0, line.find('#')));
    if (text.empty()) continue;
    const size_t eq = text.find('=');
    const std::string where = path + ":" + std::to_string(number);
    if (eq == std::string::npos)
      throw InputError(where + ": expected KEY = VALUE, got '" + text + "'");
    const std::string key = Trim(text.substr(0, eq)), value = Trim(text.substr(eq + 1));
    if (key == "param") {
      for (const auto& p : ParseAssignments({value}, where + ": param")) out.push_back(p);
    } else if (key == "x0") {
      for (const auto& p : ParseAssignments({value}, where + ": x0")) x0->push_back(p);
    } else if (!IsTunedFilterKey(key)) {
      throw InputError(where +
                       ": 'estlab simulate --config' reads 'param' and 'x0' lines (and skips a "
                       "tuned.ini's Q, R, P0 and filter integrator), not '" +
                       key + "'");
    }
  }
  return out;
}

// --input: a constant or a seeded signal (src/sim/input_signal.h) per
// input, comma-separated ("1.5,0"; "multisine(...), prbs(...)"), sampled at
// the output times k dt and written as the inputs' columns after the
// states. Recorded inputs come with --data.
void SetInput(const po::variables_map& vm, const ModelEntry& model, SimulationSpec* spec) {
  const std::string text = vm["input"].as<std::string>();
  if (!model.has_input()) {
    const InputSignal signal = ParseInputSignal(text, "--input");
    if (signal.kind != InputSignal::kConstant || signal.mean != 0)
      throw InputError("--input: model '" + model.name + "' has no input");
    return;
  }
  if (vm["input"].defaulted()) return;  // 0 for every input
  const std::vector<InputSignal> signals = ParseInputSignals(text, "--input", model.inputs);
  if (std::all_of(signals.begin(), signals.end(),
                  [](const InputSignal& s) { return s.kind == InputSignal::kConstant; })) {
    for (const InputSignal& s : signals) spec->input.push_back(s.mean);
    return;
  }
  spec->times = OutputTimes(*spec);
  for (size_t i = 0; i < signals.size(); ++i)
    if (const std::string why = signals[i].Covers(spec->times.front(), spec->times.back());
        !why.empty())
      throw InputError("--input: " + why);
  for (double t : spec->times)
    for (const InputSignal& s : signals) spec->inputs.push_back(s.At(t));
  spec->input_columns = model.inputs;
}

// --data FILE: the output times and (for a model with an input) the input
// schedule from FILE; --t-end and --dt then do not apply.
void UseRecordedSchedule(const po::variables_map& vm, const ModelEntry& model,
                         SimulationSpec* spec) {
  if (!vm["t-end"].defaulted() || !vm["dt"].defaulted())
    throw InputError("--data: the times come from the file; --t-end and --dt do not apply");
  if (!vm["input"].defaulted())
    throw InputError("--data: the input comes from the file; --input does not apply");
  const FilterData record =
      LoadInputRecord(vm["data"].as<std::string>(), model, ParseColumnRenames(vm));
  spec->times = record.t;
  spec->inputs = record.u;
  spec->input_columns = model.inputs;
}

}  // namespace

namespace {

// The options of `estlab simulate`, built once.
const po::options_description& SimulateDescriptionImpl() {
  static const po::options_description desc = [] {
    po::options_description desc("estlab simulate: integrate a model and write a trajectory CSV");
    desc.add_options()("help,h", "this text")("model", po::value<std::string>(),
                                              "model name (see 'estlab list')")(
        "param", po::value<std::vector<std::string>>()->composing(),
        "parameter override name=value (repeatable, or comma-separated)")(
        "x0", po::value<std::vector<std::string>>()->composing(),
        "initial state name=value,... (unnamed states start at 0)")(
        "t-end", po::value<std::string>()->default_value("10"), "final time [s]")(
        "dt", po::value<std::string>()->default_value("0.01"), "output step [s]")(
        "integrator", po::value<std::string>()->default_value("cvodes"),
        "cvodes | rk4 | euler | semi-implicit-euler | discrete (a discrete-time model's own map: "
        "its default and only choice)")(
        "method", po::value<std::string>()->default_value("default"),
        "CVODES method: bdf | adams | default (BDF for stiff models)")(
        "rtol", po::value<std::string>()->default_value("1e-10"), "CVODES relative tolerance")(
        "atol", po::value<std::string>()->default_value("1e-12"), "CVODES absolute tolerance")(
        "max-steps", po::value<long>()->default_value(500000),
        "CVODES maximum internal steps per output step")(
        "substeps", po::value<int>()->default_value(1),
        "fixed-step integrators: steps per output step")(
        "input", po::value<std::string>()->default_value("0"),
        "the input (cart-pole force F, dipc force u): a constant, or a seeded signal sampled "
        "at the output times and held to the next: multisine(rms=, mean=, band=f1:f2, sines=, "
        "seed=), prbs(amplitude=, mean=, period=, order=, seed=), steps(u0, t1:u1, ...), "
        "file(FILE[, column]) (FILE's t and u columns, held; --data replays FILE's own times); "
        "a model with several inputs takes one each, comma-separated, in their order")(
        "input-hold", po::value<std::string>()->default_value("zoh"),
        "how a recorded or sampled input goes from one sample to the next: zoh (held) | linear "
        "(the line between the samples)")("process-noise-var", po::value<std::string>(),
                                          "per-state variances of the noise added after each step")(
        "measure", po::value<std::string>(), "measurement name (adds z_<output> columns)")(
        "meas-noise-var", po::value<std::string>(), "per-output measurement noise variances")(
        "sensor-rate", po::value<std::string>(),
        "sensor groups' rates GROUP=HZ,... (others every row; the rest empty cells)")(
        "sensor-every", po::value<std::string>(),
        "sensor groups measured every K-th row: GROUP=K,...")(
        "seed", po::value<unsigned long>()->default_value(1), "random seed")(
        "config", po::value<std::string>(),
        "read 'param = NAME=VALUE' and 'x0 = NAME=VALUE,...' lines from a file (the tuned.ini of "
        "'estlab tune "
        "--estimate-param'; its Q/R lines are for 'estlab filter' and skipped); --param wins")(
        "data", po::value<std::string>(),
        "replay FILE: rows at its times, the model's input from its column (named as the "
        "input, or 'u'; held as --input-hold says)")(
        "column", po::value<std::vector<std::string>>()->composing(),
        "with --data: map a column, ours=[a*]theirs[+-b], e.g. u=volts")(
        "out", po::value<std::string>(), "output CSV path")("json",
                                                            "print a JSON summary on stdout");
    return desc;
  }();
  return desc;
}

// One simulation, checked.
struct SimulationJob {
  const ModelEntry* model = nullptr;
  SimulationSpec spec;
  std::string method;  // --method as given
};

// --integrator, --method, tolerances, substeps and --input-hold.
void SetTransition(const po::variables_map& vm, const ModelEntry& model, SimulationJob* job) {
  SimulationSpec& spec = job->spec;
  // A discrete-time model's own map is its default (and only) integrator.
  spec.transition.integrator = model.discrete_time && vm["integrator"].defaulted()
                                   ? Integrator::kDiscrete
                                   : ParseIntegrator(vm["integrator"].as<std::string>());
  if (const std::string e = model.CheckIntegrator(spec.transition.integrator); !e.empty())
    throw InputError("--integrator: " + e);
  const std::string method = job->method = vm["method"].as<std::string>();
  if (method == "bdf")
    spec.transition.method = CvodesMethod::kBdf;
  else if (method == "adams")
    spec.transition.method = CvodesMethod::kAdams;
  else if (method != "default")
    throw InputError("--method: unknown CVODES method '" + method + "' (bdf, adams, default)");
  spec.transition.rtol = ParseNumber(vm["rtol"].as<std::string>(), "--rtol");
  spec.transition.atol = ParseNumber(vm["atol"].as<std::string>(), "--atol");
  spec.transition.max_steps = vm["max-steps"].as<long>();
  spec.transition.substeps = vm["substeps"].as<int>();
  try {
    spec.transition.input_hold = ParseInputHold(vm["input-hold"].as<std::string>());
  } catch (const InputError& e) {
    throw InputError(std::string("--input-hold: ") + e.what());
  }
  std::string error;
  if (!spec.transition.IsValid(&error)) throw InputError(error);
}

// --process-noise-var, --measure with its noise and the sensors' rates.
void SetNoiseAndSensors(const po::variables_map& vm, const ModelEntry& model, SimulationSpec* out) {
  SimulationSpec& spec = *out;
  if (vm.count("process-noise-var")) {
    spec.process_noise_var =
        ParseList(vm["process-noise-var"].as<std::string>(), "--process-noise-var");
    RequireLength(spec.process_noise_var, model.states.size(), "--process-noise-var",
                  "one per state");
    RequireNonNegative(spec.process_noise_var, "--process-noise-var");
  }
  if (vm.count("measure")) {
    const MeasurementDesc& meas = model.FindMeasurement(vm["measure"].as<std::string>());
    spec.measurement = meas.name;  // "imu,gps": the measurement with those groups
    if (vm.count("meas-noise-var")) {
      spec.noise_free_outputs = vm.count("data") > 0;
      spec.meas_noise_var = ParseList(vm["meas-noise-var"].as<std::string>(), "--meas-noise-var");
      RequireLength(spec.meas_noise_var, meas.outputs.size(), "--meas-noise-var",
                    "one per output of '" + meas.name + "'");
      RequireNonNegative(spec.meas_noise_var, "--meas-noise-var");
    }
    auto text = [&](const char* key) { return vm.count(key) ? vm[key].as<std::string>() : ""; };
    spec.output_every =
        OutputEvery(meas, text("sensor-rate"), text("sensor-every"),
                    vm.count("data") ? 0.0  // the record's times
                                     : ParseNumber(vm["dt"].as<std::string>(), "--dt"),
                    "--sensor-rate", "--sensor-every");
  } else if (vm.count("meas-noise-var") || vm.count("sensor-rate") || vm.count("sensor-every")) {
    throw InputError("--meas-noise-var, --sensor-rate and --sensor-every need --measure");
  }
}

// Every check of the options (throws InputError); --data's file read.
SimulationJob PrepareSimulation(const po::variables_map& vm) {
  if (vm.count("column") && !vm.count("data")) throw InputError("--column needs --data");
  SimulationJob job;
  // A model file not yet in the cache compiles only its simulator.
  job.model =
      &FindModel(vm["model"].as<std::string>(), {.run = RunNeeds{.filter = -2, .simulate = true}});
  const ModelEntry& model = *job.model;
  SimulationSpec& spec = job.spec;
  std::vector<std::pair<std::string, double>> x0;
  std::vector<std::pair<std::string, double>> params =
      vm.count("config") ? ConfigParams(vm["config"].as<std::string>(), &x0)
                         : std::vector<std::pair<std::string, double>>{};
  if (vm.count("param")) {  // the command line wins
    for (const auto& p : ParseAssignments(vm["param"].as<std::vector<std::string>>(), "--param"))
      params.push_back(p);
  }
  spec.params = model.ResolveParams(params);
  if (vm.count("x0"))  // the command line wins
    for (const auto& p : ParseAssignments(vm["x0"].as<std::vector<std::string>>(), "--x0"))
      x0.push_back(p);
  spec.x0 = model.ResolveState(x0, "--x0");
  spec.t_end = ParseNumber(vm["t-end"].as<std::string>(), "--t-end");
  spec.dt = ParseNumber(vm["dt"].as<std::string>(), "--dt");
  if (spec.t_end < 0)
    throw InputError("--t-end must be >= 0, got " + vm["t-end"].as<std::string>());
  if (!(spec.dt > 0)) throw InputError("--dt must be > 0, got " + vm["dt"].as<std::string>());
  if (spec.t_end / spec.dt > 1e8) throw InputError("--t-end / --dt exceeds 1e8 output rows");
  if (vm.count("data")) UseRecordedSchedule(vm, model, &spec);
  SetTransition(vm, model, &job);
  SetInput(vm, model, &spec);
  SetNoiseAndSensors(vm, model, &spec);
  spec.seed = vm["seed"].as<unsigned long>();
  return job;
}

std::string MethodName(const SimulationJob& job) {
  return job.spec.transition.method == CvodesMethod::kDefault ? (job.model->stiff ? "bdf" : "adams")
                                                              : job.method;
}

std::string SidecarOf(const po::variables_map& vm, const SimulationJob& job) {
  return SidecarJson(*job.model, job.spec, IntegratorName(job.spec.transition.integrator),
                     MethodName(job), vm.count("data") ? vm["data"].as<std::string>() : "",
                     Trim(vm["input"].as<std::string>()));
}

// The --json summary.
std::string SimulationJson(const SimulationJob& job, const SimulationResult& result,
                           const std::string& out_path) {
  const ModelEntry& model = *job.model;
  const SimulationSpec& spec = job.spec;
  JsonWriter j;
  j.BeginObject().Key("model").Value(model.name).Key("out").Value(out_path);
  j.Key("integrator").Value(IntegratorName(spec.transition.integrator));
  j.Key("steps").Value(result.steps).Key("rows").Value(long(result.rows.size()));
  j.Key("rhs_evals").Value(result.stats.rhs_evals);
  j.Key("jacobian_evals").Value(result.stats.jacobian_evals);
  j.Key("internal_steps").Value(result.stats.internal_steps);
  j.Key("wall_s").Value(result.wall_s);
  j.Key("invariants").BeginObject();
  for (size_t i = 0; i < result.invariant_names.size(); ++i) {
    j.Key(result.invariant_names[i]).BeginObject();
    j.Key("initial").Value(result.invariant_initial[i]);
    j.Key("max_relative_drift").Value(result.invariant_drift[i]);
    j.EndObject();
  }
  j.EndObject();
  if (!result.invariant_names.empty() && result.invariant_names[0] == "energy")
    j.Key("energy_drift").Value(result.invariant_drift[0]);
  j.EndObject();
  return j.str();
}

po::variables_map ParseSimulateArgs(const std::vector<std::string>& args) {
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(SimulateDescriptionImpl()).run(), vm);
  po::notify(vm);
  return vm;
}

}  // namespace

const po::options_description& SimulateDescription() { return SimulateDescriptionImpl(); }

SimulateOutcome ComputeSimulation(const std::vector<std::string>& args) {
  const po::variables_map vm = ParseSimulateArgs(args);
  if (!vm.count("model")) throw InputError("--model is required (see 'estlab list')");
  const SimulationJob job = PrepareSimulation(vm);
  SimulateOutcome o;
  o.result = job.model->simulate(job.spec);
  o.sidecar_json = SidecarOf(vm, job);
  o.summary_json = SimulationJson(job, o.result, "");
  o.status = o.result.ok ? 0 : 1;
  o.error = o.result.error;
  return o;
}

int RunSimulate(const std::vector<std::string>& args) {
  const po::variables_map vm = ParseSimulateArgs(args);
  if (vm.count("help")) {
    std::cout << SimulateDescriptionImpl() << "\n" << kExamples;
    return 0;
  }
  if (!vm.count("model")) throw InputError("--model is required (see 'estlab list')");
  if (!vm.count("out")) throw InputError("--out is required");
  const std::vector<std::string> inputs = InputFiles(vm, {"config", "data"});
  RefuseOutputOverInput("--out", vm["out"].as<std::string>(), inputs);
  RefuseOutputOverInput("--out (its sidecar)", vm["out"].as<std::string>() + ".json", inputs);
  const SimulationJob job = PrepareSimulation(vm);
  const ModelEntry& model = *job.model;
  const SimulationSpec& spec = job.spec;
  const std::string out_path = vm["out"].as<std::string>();
  const bool json = vm.count("json") > 0;

  // Open both outputs before integrating so an unwritable path fails fast.
  OutputFile csv(out_path);
  OutputFile sidecar(out_path + ".json");

  const SimulationResult result = model.simulate(spec);
  const std::string method_name = MethodName(job);

  if (!result.ok) {
    OutputFile partial(PartialPath(out_path));
    WriteCsv(partial.stream(), result.columns, result.rows);
    partial.Commit();
    std::cerr << "estlab: error: " << result.error << "\n"
              << "estlab: the " << result.rows.size() << " rows computed before the failure are in "
              << PartialPath(out_path) << "\n";
    return 1;
  }
  WriteCsv(csv.stream(), result.columns, result.rows);
  sidecar.stream() << SidecarOf(vm, job);
  csv.Finish();  // both written before either is in place: both or neither
  sidecar.Finish();
  csv.Commit();
  sidecar.Commit();

  if (json) {
    std::cout << SimulationJson(job, result, out_path) << "\n";
  } else {
    std::cout << "model            " << model.name << "\n"
              << "integrator       " << IntegratorName(spec.transition.integrator)
              << (spec.transition.integrator == Integrator::kCvodes ? " (" + method_name + ")" : "")
              << "\n"
              << "output steps     " << result.steps
              << (!vm.count("data") ? "  (t = 0 .. " + FormatNumber(spec.t_end) +
                                          ", dt = " + FormatNumber(spec.dt) + ")"
                                    : "  (the times of " + vm["data"].as<std::string>() + ")")
              << "\n"
              << "rhs evaluations  " << result.stats.rhs_evals << "\n"
              << "internal steps   " << result.stats.internal_steps << "\n"
              << "wall time        " << std::setprecision(3) << result.wall_s << " s\n";
    for (size_t i = 0; i < result.invariant_names.size(); ++i) {
      std::string label = result.invariant_names[i] + " drift";
      label.resize(std::max<size_t>(label.size() + 1, 17), ' ');
      std::cout << std::setprecision(3) << label << "max |dI/I0| = " << result.invariant_drift[i]
                << "\n";
    }
    std::cout << "wrote            " << out_path << " and " << out_path << ".json\n";
  }
  return 0;
}

}  // namespace estlab::cli
