#include "src/options/filter_flags.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>

#include "src/core/parse.h"
#include "src/io/csv_reader.h"

namespace po = boost::program_options;

namespace estlab::cli {

void AddFilterOptions(po::options_description* desc, const std::string& np) {
  // One option a line.
  // clang-format off
  desc->add_options()
      ("model", po::value<std::string>(), "model name (see 'estlab list')")
      ("measure", po::value<std::string>(), "measurement name of the model")
      ("filter", po::value<std::string>()->default_value("ukf"), "kf | ekf | iekf | ukf | ckf | ghkf | pf")
      ("param", po::value<std::vector<std::string>>()->composing(), "model parameter name=value (repeatable)")
      ("t0", po::value<std::string>(), "time of the prior (default: the first row's time)")
      ("integrator", po::value<std::string>()->default_value("rk4"), "process model: rk4 | euler | semi-implicit-euler | cvodes")
      ("substeps", po::value<int>()->default_value(1), "fixed-step integrators: steps per measurement interval")
      ("method", po::value<std::string>()->default_value("default"), "CVODES method: bdf | adams | default")
      ("rtol", po::value<std::string>()->default_value("1e-8"), "CVODES relative tolerance")
      ("atol", po::value<std::string>()->default_value("1e-10"), "CVODES absolute tolerance")
      ("max-steps", po::value<long>()->default_value(500000), "CVODES maximum steps per interval")
      ("x0", po::value<std::vector<std::string>>()->composing(), "prior mean name=value,... (others 0)")
      ("p0-diag", po::value<std::string>(), "prior covariance diagonal (default 1 for every state)")
      ("p0", po::value<std::string>(), "prior covariance matrix \"a,b;c,d\"")
      ((np + "q-diag").c_str(), po::value<std::string>(), "process noise Q diagonal (per step)")
      ((np + "q").c_str(), po::value<std::string>(), "process noise Q matrix \"a,b;c,d\" (per step)")
      ((np + "q-white-accel").c_str(), po::value<std::string>(), "Q = qc [[dt^3/3, dt^2/2], [dt^2/2, dt]] per (position, rate) pair, dt of each step")
      ((np + "r-diag").c_str(), po::value<std::string>(), "measurement noise R diagonal")
      ((np + "r").c_str(), po::value<std::string>(), "measurement noise R matrix")
      ("linearize-at", po::value<std::vector<std::string>>()->composing(), "kf: operating point name=value,... (default: the prior mean)")
      ("iterations", po::value<int>()->default_value(1), "ekf: update iterations (> 1 = iterated EKF; 'iekf' sets 3 by default)")
      ("alpha", po::value<std::string>()->default_value("1e-3"), "ukf: spread alpha")
      ("beta", po::value<std::string>()->default_value("2"), "ukf: prior knowledge beta")
      ("kappa", po::value<std::string>()->default_value("0"), "ukf: secondary scaling kappa")
      ("gh-order", po::value<int>()->default_value(3), "ghkf: Gauss-Hermite order p (p^n points)")
      ("sigma-update", po::value<std::string>()->default_value("redraw"), "propagate (reuse propagated points) | redraw (new points from x-, P-)")
      ("jitter", po::value<std::string>()->default_value("0"), "sigma-point: add jitter*I to P, P- and S (paper 003: 1e-3)")
      ("adapt", po::value<std::string>(), "adaptive sigma-point filter: sage-husa | innovation-matching")
      ("adapt-what", po::value<std::string>()->default_value("r"), "q | r | qr")
      ("forgetting", po::value<std::string>()->default_value("0.97"), "sage-husa forgetting factor b")
      ("window", po::value<int>()->default_value(30), "innovation-matching window N")
      ("particles", po::value<int>()->default_value(1000), "pf: number of particles")
      ("resample", po::value<std::string>()->default_value("systematic"), "pf: multinomial | systematic | stratified | residual")
      ("ess-threshold", po::value<std::string>()->default_value("0.5"), "pf: resample when ESS < threshold * N (1 = every step)")
      ("seed", po::value<unsigned long>()->default_value(1), "pf: random seed")
      ("input", po::value<std::string>()->default_value("0"), "constant input when the data has no 'u' column")
      ("column", po::value<std::vector<std::string>>()->composing(), "map a column: ours=theirs, e.g. z_theta=angle_rad")
      ("full-cov", "write every covariance entry, not only the diagonal");
  // clang-format on
}

std::vector<std::pair<std::string, std::string>> ParseColumnRenames(const po::variables_map& vm) {
  std::vector<std::pair<std::string, std::string>> out;
  if (!vm.count("column")) return out;
  for (const auto& item : vm["column"].as<std::vector<std::string>>()) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
      throw InputError("--column: expected ours=theirs, got '" + item + "'");
    out.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return out;
}

void CheckCovariance(const std::vector<double>& a, int n, const std::string& what,
                     bool allow_semidefinite) {
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = a[i * n + j];
  const double scale = std::max(1e-300, A.cwiseAbs().maxCoeff());
  if ((A - A.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale)
    throw InputError(what + " is not symmetric");
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  const double min_eig = eig.eigenvalues().minCoeff();
  if (allow_semidefinite
          ? min_eig < -1e-12 * scale
          : !(Eigen::LLT<Eigen::MatrixXd>(A).info() == Eigen::Success && min_eig > 0)) {
    throw InputError(what + " is not positive " + (allow_semidefinite ? "semi-" : "") +
                     "definite (smallest eigenvalue " + FormatNumber(min_eig) + ")");
  }
}

void AddConfigOption(po::options_description* desc) {
  desc->add_options()("config", po::value<std::vector<std::string>>()->composing(),
                      "read filter options from FILE ('key = value' lines, e.g. tuned.ini from "
                      "'estlab tune --out'); the command line wins (repeatable)");
}

void MergeConfigFiles(po::variables_map* vm, const std::string& np) {
  if (!vm->count("config")) return;
  const std::vector<std::string> files = (*vm)["config"].as<std::vector<std::string>>();
  auto given = [&](const std::string& key) { return vm->count(key) && !(*vm)[key].defaulted(); };
  const std::vector<std::string> q_keys = {"q-diag", "q", "q-white-accel", "q-scalar"};
  const std::vector<std::string> r_keys = {"r-diag", "r", "r-scalar"};
  auto any_given = [&](const std::vector<std::string>& keys) {
    for (const auto& k : keys)
      if (given(np + k)) return true;
    return false;
  };
  const bool cmd_q = any_given(q_keys), cmd_r = any_given(r_keys);
  po::options_description file_desc;
  AddFilterOptions(&file_desc, "");
  for (const std::string& path : files) {
    std::ifstream in(path);
    if (!in) throw InputError("--config: cannot read '" + path + "'");
    po::variables_map file_vm;
    try {
      po::store(po::parse_config_file(in, file_desc, false), file_vm);
    } catch (const po::error& e) {
      throw InputError("--config " + path + ": " + e.what());
    }
    for (const auto& [key, value] : file_vm) {
      if (value.defaulted()) continue;
      const bool is_q = std::find(q_keys.begin(), q_keys.end(), key) != q_keys.end();
      const bool is_r = std::find(r_keys.begin(), r_keys.end(), key) != r_keys.end();
      if ((is_q && cmd_q) || (is_r && cmd_r)) continue;
      const std::string target = (is_q || is_r) ? np + key : key;
      if (given(target)) continue;
      (*vm).erase(target);
      vm->insert({target, value});
    }
  }
}

namespace {

std::vector<double> DiagOrMatrix(const po::variables_map& vm, const std::string& diag_opt,
                                 const std::string& mat_opt, int n, const std::string& what) {
  std::vector<double> out(n * n, 0.0);
  if (vm.count(diag_opt) && vm.count(mat_opt))
    throw InputError("give only one of --" + diag_opt + " and --" + mat_opt);
  if (vm.count(diag_opt)) {
    const auto d = ParseList(vm[diag_opt].as<std::string>(), "--" + diag_opt);
    RequireLength(d, n, "--" + diag_opt, what);
    for (int i = 0; i < n; ++i) out[i * n + i] = d[i];
  } else if (vm.count(mat_opt)) {
    out = ParseMatrix(vm[mat_opt].as<std::string>(), n, "--" + mat_opt);
  }
  return out;
}

}  // namespace

FilterSpec BuildFilterSpec(const po::variables_map& vm, const ModelEntry& model,
                           const std::string& np) {
  FilterSpec spec;
  const int n = int(model.states.size());
  if (!vm.count("measure")) throw InputError("--measure is required (see 'estlab list')");
  spec.measurement = vm["measure"].as<std::string>();
  const MeasurementDesc& meas = model.FindMeasurement(spec.measurement);
  const int m = int(meas.outputs.size());
  spec.params = model.ResolveParams(
      vm.count("param") ? ParseAssignments(vm["param"].as<std::vector<std::string>>(), "--param")
                        : std::vector<std::pair<std::string, double>>{});
  const std::string filter_name = vm["filter"].as<std::string>();
  spec.kind = ParseFilterKind(filter_name);
  spec.iterations = vm["iterations"].as<int>();
  if (filter_name == "iekf" && vm["iterations"].defaulted()) spec.iterations = 3;
  if (spec.iterations < 1) throw InputError("--iterations must be >= 1");

  spec.transition.integrator = ParseIntegrator(vm["integrator"].as<std::string>());
  spec.transition.substeps = vm["substeps"].as<int>();
  const std::string method = vm["method"].as<std::string>();
  if (method == "bdf")
    spec.transition.method = CvodesMethod::kBdf;
  else if (method == "adams")
    spec.transition.method = CvodesMethod::kAdams;
  else if (method != "default")
    throw InputError("--method: unknown CVODES method '" + method + "'");
  spec.transition.rtol = ParseNumber(vm["rtol"].as<std::string>(), "--rtol");
  spec.transition.atol = ParseNumber(vm["atol"].as<std::string>(), "--atol");
  spec.transition.max_steps = vm["max-steps"].as<long>();
  std::string error;
  if (!spec.transition.IsValid(&error)) throw InputError(error);

  if (vm.count("t0")) {
    spec.has_t0 = true;
    spec.t0 = ParseNumber(vm["t0"].as<std::string>(), "--t0");
  }
  spec.x0 = model.ResolveState(
      vm.count("x0") ? ParseAssignments(vm["x0"].as<std::vector<std::string>>(), "--x0")
                     : std::vector<std::pair<std::string, double>>{},
      "--x0");
  if (vm.count("p0-diag") || vm.count("p0")) {
    spec.p0 = DiagOrMatrix(vm, "p0-diag", "p0", n, "one per state");
  } else {
    spec.p0.assign(n * n, 0.0);
    for (int i = 0; i < n; ++i) spec.p0[i * n + i] = 1.0;
  }
  CheckCovariance(spec.p0, n, "P0 (--p0-diag/--p0)", false);

  const std::string qd = np + "q-diag", qm = np + "q", qw = np + "q-white-accel";
  const int q_given = int(vm.count(qd)) + int(vm.count(qm)) + int(vm.count(qw));
  if (q_given != 1) {
    throw InputError("give exactly one of --" + qd + ", --" + qm + ", --" + qw +
                     " (process noise Q)");
  }
  if (vm.count(qw)) {
    spec.q_white_accel = true;
    spec.qc = ParseNumber(vm[qw].as<std::string>(), "--" + qw);
    if (spec.qc < 0) throw InputError("--" + qw + " must be >= 0");
  } else {
    spec.q = DiagOrMatrix(vm, qd, qm, n, "one per state");
    CheckCovariance(spec.q, n, "Q (--" + (vm.count(qd) ? qd : qm) + ")", true);
  }
  const std::string rd = np + "r-diag", rm = np + "r";
  if (int(vm.count(rd)) + int(vm.count(rm)) != 1)
    throw InputError("give exactly one of --" + rd + ", --" + rm + " (measurement noise R)");
  spec.r = DiagOrMatrix(vm, rd, rm, m, "one per output of '" + meas.name + "'");
  CheckCovariance(spec.r, m, "R (--" + (vm.count(rd) ? rd : rm) + ")", false);

  if (vm.count("linearize-at")) {
    spec.linearize_at = model.ResolveState(
        ParseAssignments(vm["linearize-at"].as<std::vector<std::string>>(), "--linearize-at"),
        "--linearize-at");
  }
  spec.alpha = ParseNumber(vm["alpha"].as<std::string>(), "--alpha");
  spec.beta = ParseNumber(vm["beta"].as<std::string>(), "--beta");
  spec.kappa = ParseNumber(vm["kappa"].as<std::string>(), "--kappa");
  spec.gh_order = vm["gh-order"].as<int>();
  const std::string upd = vm["sigma-update"].as<std::string>();
  if (upd != "propagate" && upd != "redraw")
    throw InputError("--sigma-update: expected propagate or redraw, got '" + upd + "'");
  spec.sigma_redraw = upd == "redraw";
  spec.jitter = ParseNumber(vm["jitter"].as<std::string>(), "--jitter");
  if (spec.jitter < 0) throw InputError("--jitter must be >= 0");

  if (vm.count("adapt")) {
    if (spec.kind != FilterKind::kUkf && spec.kind != FilterKind::kCkf &&
        spec.kind != FilterKind::kGhkf)
      throw InputError("--adapt needs a sigma-point filter (ukf, ckf, ghkf)");
    spec.adapt.rule = vm["adapt"].as<std::string>();
    if (spec.adapt.rule != "sage-husa" && spec.adapt.rule != "innovation-matching")
      throw InputError("--adapt: unknown rule '" + spec.adapt.rule +
                       "' (expected sage-husa or innovation-matching)");
    const std::string what = vm["adapt-what"].as<std::string>();
    if (what != "q" && what != "r" && what != "qr")
      throw InputError("--adapt-what: expected q, r or qr, got '" + what + "'");
    spec.adapt.adapt_q = what.find('q') != std::string::npos;
    spec.adapt.adapt_r = what.find('r') != std::string::npos;
    spec.adapt.forgetting = ParseNumber(vm["forgetting"].as<std::string>(), "--forgetting");
    if (!(spec.adapt.forgetting > 0 && spec.adapt.forgetting < 1))
      throw InputError("--forgetting must be in (0, 1)");
    spec.adapt.window = vm["window"].as<int>();
    if (spec.adapt.window < 1) throw InputError("--window must be >= 1");
  }
  spec.particles = vm["particles"].as<int>();
  if (spec.particles < 1) throw InputError("--particles must be >= 1");
  spec.resample = vm["resample"].as<std::string>();
  if (spec.resample != "multinomial" && spec.resample != "systematic" &&
      spec.resample != "stratified" && spec.resample != "residual")
    throw InputError("--resample: unknown scheme '" + spec.resample +
                     "' (multinomial, systematic, stratified, residual)");
  spec.ess_threshold = ParseNumber(vm["ess-threshold"].as<std::string>(), "--ess-threshold");
  if (!(spec.ess_threshold >= 0 && spec.ess_threshold <= 1))
    throw InputError("--ess-threshold must be in [0, 1]");
  spec.seed = vm["seed"].as<unsigned long>();
  spec.input = ParseNumber(vm["input"].as<std::string>(), "--input");
  if (spec.input != 0 && !model.has_input)
    throw InputError("--input: model '" + model.name + "' has no input");
  spec.full_cov = vm.count("full-cov") > 0;
  return spec;
}

FilterData LoadFilterData(const std::string& path, const ModelEntry& model,
                          const MeasurementDesc& meas,
                          const std::vector<std::pair<std::string, std::string>>& renames) {
  const CsvTable table = ReadCsv(path);
  auto column = [&](const std::string& ours) {
    std::string name = ours;
    for (const auto& [a, b] : renames)
      if (a == ours) name = b;
    return table.ColumnIndex(name);
  };
  auto column_name = [&](const std::string& ours) {
    for (const auto& [a, b] : renames)
      if (a == ours) return b;
    return ours;
  };
  FilterData data;
  data.path = path;
  const int tc = column("t");
  if (tc < 0) throw InputError(path + ": no '" + column_name("t") + "' (time) column");
  std::vector<int> zc;
  for (const auto& o : meas.outputs) {
    const int c = column("z_" + o);
    if (c < 0) {
      throw InputError(path + ": no measurement column '" + column_name("z_" + o) +
                       "' for output '" + o + "' of measurement '" + meas.name +
                       "' (map another column with --column z_" + o + "=NAME)");
    }
    zc.push_back(c);
  }
  std::vector<int> sc;
  for (const auto& s : model.states) sc.push_back(column(s));
  int present = 0;
  for (int c : sc) present += c >= 0;
  data.has_truth = present == int(sc.size());
  const int uc = model.has_input ? column("u") : -1;
  data.has_input = uc >= 0;
  data.m = int(meas.outputs.size());
  const int n = int(model.states.size());
  for (size_t k = 0; k < table.rows.size(); ++k) {
    const auto& row = table.rows[k];
    const long line = table.line_numbers[k];
    const double t = row[tc];
    if (!std::isfinite(t))
      throw InputError(path + ":" + std::to_string(line) + ": column " + std::to_string(tc + 1) +
                       " ('t'): missing time");
    if (!data.t.empty() && t < data.t.back())
      throw InputError(path + ":" + std::to_string(line) + ": column " + std::to_string(tc + 1) +
                       " ('t'): time goes backwards (" + FormatNumber(t) + " after " +
                       FormatNumber(data.t.back()) + ")");
    data.t.push_back(t);
    data.lines.push_back(line);
    for (int c : zc) data.z.push_back(row[c]);
    if (data.has_truth)
      for (int i = 0; i < n; ++i) data.truth.push_back(row[sc[i]]);
    if (data.has_input) {
      if (!std::isfinite(row[uc]))
        throw InputError(path + ":" + std::to_string(line) + ": column " + std::to_string(uc + 1) +
                         " ('u'): missing input");
      data.u.push_back(row[uc]);
    }
  }
  if (data.t.empty()) throw InputError(path + ": no data rows");
  return data;
}

}  // namespace estlab::cli
