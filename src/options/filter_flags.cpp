#include "src/options/filter_flags.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <fstream>

#include "src/core/parse.h"
#include "src/io/csv_reader.h"
#include "src/options/filter_settings.h"

namespace po = boost::program_options;

namespace estlab::cli {

void AddFilterOptions(po::options_description* desc, const std::string& np) {
  for (const FilterKey& k : FilterKeyTable()) {
    const std::string name = k.noise ? np + k.name : std::string(k.name);
    switch (k.kind) {
      case FilterKey::kFlag:
        desc->add_options()(name.c_str(), k.help);
        break;
      case FilterKey::kRepeatable:
        desc->add_options()(name.c_str(), po::value<std::vector<std::string>>()->composing(),
                            k.help);
        break;
      case FilterKey::kValue:
        if (k.default_text != nullptr)
          desc->add_options()(name.c_str(), po::value<std::string>()->default_value(k.default_text),
                              k.help);
        else
          desc->add_options()(name.c_str(), po::value<std::string>(), k.help);
        break;
    }
  }
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
