#include "src/options/filter_flags.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <optional>

#include "src/core/parse.h"
#include "src/io/csv_reader.h"
#include "src/options/filter_settings.h"
#include "src/run/filter_kinds.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {

// The kind a key belongs to when its help starts with "<kind>: " (e.g.
// "pf: number of particles"), else nullopt.
std::optional<FilterKind> KindOfKey(const FilterKey& key) {
  const std::string help = key.help;
  const size_t colon = help.find(": ");
  if (colon == std::string::npos || help.find(' ') < colon) return std::nullopt;
  try {
    return ParseFilterKind(help.substr(0, colon));
  } catch (const InputError&) {
    return std::nullopt;
  }
}

// For the tuner: the table's "kf | ekf | ... | pf" with the kinds it cannot
// tune left out.
std::string TunableKindsHelp(const std::string& help) {
  std::string out;
  size_t start = 0;
  while (start <= help.size()) {
    const size_t bar = std::min(help.find(" | ", start), help.size());
    const std::string name = help.substr(start, bar - start);
    if (InfoOf(ParseFilterKind(name)).tunable) out += (out.empty() ? "" : " | ") + name;
    start = bar + 3;
  }
  return out;
}

// Whether the tuner (noise prefix "init-") shows the key: not the options
// of kinds it cannot tune, nor those of the per-step output.
bool TunerUses(const FilterKey& key) {
  const std::optional<FilterKind> kind = KindOfKey(key);
  return !(kind && !InfoOf(*kind).tunable) && std::string(key.name) != "full-cov";
}

}  // namespace

void AddFilterOptions(po::options_description* desc, const std::string& np) {
  const bool tuner = np == "init-";
  for (const FilterKey& k : FilterKeyTable()) {
    if (tuner && !TunerUses(k)) continue;
    const std::string name = k.noise ? np + k.name : std::string(k.name);
    const std::string help =
        tuner && name == "filter" ? TunableKindsHelp(k.help) : std::string(k.help);
    switch (k.kind) {
      case FilterKey::kFlag:
        desc->add_options()(name.c_str(), help.c_str());
        break;
      case FilterKey::kRepeatable:
        desc->add_options()(name.c_str(), po::value<std::vector<std::string>>()->composing(),
                            help.c_str());
        break;
      case FilterKey::kValue:
        if (k.default_text != nullptr)
          desc->add_options()(name.c_str(), po::value<std::string>()->default_value(k.default_text),
                              help.c_str());
        else
          desc->add_options()(name.c_str(), po::value<std::string>(), help.c_str());
        break;
    }
  }
}

void AddTunerOptions(po::options_description* desc) {
  for (const TunerKey& k : TunerKeyTable()) {
    if (k.default_text != nullptr)
      desc->add_options()(k.name, po::value<std::string>()->default_value(k.default_text), k.help);
    else
      desc->add_options()(k.name, po::value<std::string>(), k.help);
  }
  desc->add_options()("form", po::value<std::string>(), "the old name of --solver");
}

TunerSettings TunerSettingsFromVariablesMap(const po::variables_map& vm) {
  TunerSettings s;
  for (const TunerKey& k : TunerKeyTable())
    if (vm.count(k.name) && !vm[k.name].defaulted()) s.Set(k.name, vm[k.name].as<std::string>());
  if (vm.count("form")) {
    if (s.Given("solver")) throw InputError("--form is the old name of --solver: give one");
    s.Set("solver", vm["form"].as<std::string>());
  }
  return s;
}

FilterSettings SettingsFromVariablesMap(const po::variables_map& vm, const std::string& np) {
  FilterSettings s(np);
  for (const FilterKey& k : FilterKeyTable()) {
    const std::string name = k.noise ? np + k.name : std::string(k.name);
    if (!vm.count(name) || vm[name].defaulted()) continue;
    switch (k.kind) {
      case FilterKey::kFlag:
        s.Set(name, "true");
        break;
      case FilterKey::kRepeatable:
        for (const std::string& v : vm[name].as<std::vector<std::string>>()) s.Add(name, v);
        break;
      case FilterKey::kValue:
        s.Set(name, vm[name].as<std::string>());
        break;
    }
  }
  return s;
}

FilterSpec BuildFilterSpec(const po::variables_map& vm, const ModelEntry& model,
                           const std::string& np) {
  return estlab::BuildFilterSpec(SettingsFromVariablesMap(vm, np), model);
}

std::vector<ColumnMap> ParseColumnRenames(const po::variables_map& vm) {
  if (!vm.count("column")) return {};
  return ParseColumnMaps(vm["column"].as<std::vector<std::string>>());
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

void CheckPriorTime(const FilterSpec& spec, const FilterData& data) {
  if (!spec.has_t0 || data.t.empty() || spec.t0 <= data.t[0]) return;
  throw InputError("--t0 " + FormatNumber(spec.t0) + " is later than the first data row (" +
                   data.path + ":" + std::to_string(data.lines[0]) +
                   ", t = " + FormatNumber(data.t[0]) +
                   "); give --t0 <= " + FormatNumber(data.t[0]) + " or leave it out");
}

std::vector<std::string> InputFiles(const po::variables_map& vm,
                                    const std::vector<std::string>& keys) {
  std::vector<std::string> files;
  for (const std::string& key : keys) {
    if (!vm.count(key)) continue;
    const boost::any& value = vm[key].value();
    if (const auto* one = boost::any_cast<std::string>(&value)) files.push_back(*one);
    if (const auto* many = boost::any_cast<std::vector<std::string>>(&value))
      files.insert(files.end(), many->begin(), many->end());
  }
  const size_t given = files.size();  // each one's sidecar is read too
  for (size_t i = 0; i < given; ++i) files.push_back(files[i] + ".json");
  return files;
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
  if (np == "init-") AddTunerOptions(&file_desc);
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

// Where one of our columns comes from: a column of the file and its affine map.
struct Source {
  int column = -1;   // -1: absent
  std::string name;  // the file's column name
  double scale = 1.0, offset = 0.0;
  double Read(const std::vector<double>& row) const { return scale * row[column] + offset; }
};

Source FindSource(const CsvTable& table, const std::vector<ColumnMap>& maps,
                  const std::string& ours) {
  Source s;
  s.name = ours;
  for (const ColumnMap& m : maps) {
    if (m.ours != ours) continue;
    s.name = m.theirs;
    s.scale = m.scale;
    s.offset = m.offset;
  }
  s.column = table.ColumnIndex(s.name);
  return s;
}

// "PATH:LINE: column C ('NAME'): "
std::string Where(const std::string& path, long line, const Source& s) {
  return path + ":" + std::to_string(line) + ": column " + std::to_string(s.column + 1) + " ('" +
         s.name + "'): ";
}

}  // namespace

namespace {

// The input columns of `table`, one per model input, matched by name
// (--column maps others; a model's single input may also be a column "u").
// Empty when the table has none of them; an error naming the missing ones
// when it has some but not all, or none and the run holds no constant input.
std::vector<Source> FindInputColumns(const CsvTable& table, const std::string& path,
                                     const ModelEntry& model, const std::vector<ColumnMap>& columns,
                                     bool constant_input) {
  std::vector<Source> found;
  std::vector<std::string> missing;
  for (const std::string& name : model.inputs) {
    Source uc = FindSource(table, columns, name);
    const bool u_is_a_state =
        std::find(model.states.begin(), model.states.end(), "u") != model.states.end();
    if (uc.column < 0 && model.inputs.size() == 1 && name != "u" && !u_is_a_state)
      uc = FindSource(table, columns, "u");
    if (uc.column < 0) missing.push_back(name);
    found.push_back(uc);
  }
  if (missing.empty()) return found;
  if (missing.size() == model.inputs.size() && constant_input) return {};
  std::string names;
  for (const std::string& name : missing) names += (names.empty() ? "'" : ", '") + name + "'";
  throw InputError(path + ": no input column " + names + " for " +
                   (model.inputs.size() == 1 ? "the input" : "the inputs") + " of model '" +
                   model.name + "' (map another column with --column " + missing[0] + "=NAME" +
                   (missing.size() == model.inputs.size()
                        ? ", or hold the input constant with --input)"
                        : "; every input needs its column)"));
}

// The time and input columns of every row of `table` into *data (t, lines,
// nu, u). A model with inputs needs their columns unless constant_input says
// the run holds one value; a missing or non-finite input and time going
// backwards are errors naming FILE:LINE and the column.
void ReadTimesAndInputs(const CsvTable& table, const std::string& path, const ModelEntry& model,
                        const std::vector<ColumnMap>& columns, bool constant_input,
                        FilterData* data) {
  const Source tc = FindSource(table, columns, "t");
  if (tc.column < 0) throw InputError(path + ": no '" + tc.name + "' (time) column");
  const std::vector<Source> inputs = FindInputColumns(table, path, model, columns, constant_input);
  data->nu = int(inputs.size());
  for (size_t k = 0; k < table.rows.size(); ++k) {
    const auto& row = table.rows[k];
    const long line = table.line_numbers[k];
    const double t = tc.Read(row);
    if (!std::isfinite(t)) throw InputError(Where(path, line, tc) + "missing time");
    if (!data->t.empty() && t < data->t.back())
      throw InputError(Where(path, line, tc) + "time goes backwards (" + FormatNumber(t) +
                       " after " + FormatNumber(data->t.back()) + ")");
    data->t.push_back(t);
    data->lines.push_back(line);
    for (const Source& uc : inputs) {
      const double u = uc.Read(row);
      if (std::isnan(row[uc.column])) throw InputError(Where(path, line, uc) + "missing input");
      if (!std::isfinite(u))
        throw InputError(Where(path, line, uc) + "input is not finite (" + FormatNumber(u) + ")");
      data->u.push_back(u);
    }
  }
  if (data->t.empty()) throw InputError(path + ": no data rows");
}

}  // namespace

FilterData LoadFilterData(const std::string& path, const ModelEntry& model,
                          const MeasurementDesc& meas, const std::vector<ColumnMap>& columns,
                          bool read_truth, bool constant_input) {
  const std::shared_ptr<const CsvTable> shared = OpenCsv(path);
  const CsvTable& table = *shared;
  auto source = [&](const std::string& ours) { return FindSource(table, columns, ours); };
  FilterData data;
  data.path = path;
  std::vector<Source> zc;
  for (const auto& o : meas.outputs) {
    zc.push_back(source("z_" + o));
    if (zc.back().column < 0) {
      throw InputError(path + ": no measurement column '" + zc.back().name + "' for output '" + o +
                       "' of measurement '" + meas.name + "' (map another column with --column z_" +
                       o + "=NAME)");
    }
  }
  std::vector<Source> sc;
  for (const auto& s : model.states) sc.push_back(source(s));
  int present = 0;
  for (const Source& s : sc) present += s.column >= 0;
  data.has_truth = read_truth && present == int(sc.size());
  ReadTimesAndInputs(table, path, model, columns, constant_input, &data);
  data.m = int(meas.outputs.size());
  const int n = int(model.states.size());
  for (const auto& row : table.rows) {
    for (const Source& z : zc) data.z.push_back(z.Read(row));
    if (data.has_truth)
      for (int i = 0; i < n; ++i) data.truth.push_back(sc[i].Read(row));
  }
  return data;
}

bool ConstantInputGiven(const po::variables_map& vm) {
  return vm.count("input") && !vm["input"].defaulted();
}

FilterData LoadInputRecord(const std::string& path, const ModelEntry& model,
                           const std::vector<ColumnMap>& columns) {
  const std::shared_ptr<const CsvTable> shared = OpenCsv(path);
  const CsvTable& table = *shared;
  FilterData data;
  data.path = path;
  ReadTimesAndInputs(table, path, model, columns, false, &data);
  return data;
}

}  // namespace estlab::cli
