#include "src/python/filter_run.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "src/cli/commands.h"
#include "src/core/types.h"
#include "src/options/filter_settings.h"
#include "src/python/call_guard.h"
#include "src/python/tables.h"

namespace py = pybind11;

namespace estlab::python {

namespace {

// A finished filter or smoother run, held for Python: its columns are
// gathered into arrays when asked for, its JSON written when asked for.
class FilterRun {
 public:
  explicit FilterRun(cli::FilterOutcome o) : o_(std::move(o)) {}
  const std::vector<std::string>& columns() const { return o_.run.columns; }
  size_t rows() const { return o_.run.rows.size(); }
  py::array_t<double> Column(const std::string& name) const {
    const size_t j = IndexOf(name);
    py::array_t<double> a(o_.run.rows.size());
    double* out = a.mutable_data();
    for (const std::vector<double>& row : o_.run.rows) *out++ = row[j];
    return a;
  }
  // The columns `names` side by side: rows x names.
  py::array_t<double> Stack(const std::vector<std::string>& names) const {
    std::vector<size_t> js;
    for (const std::string& name : names) js.push_back(IndexOf(name));
    py::array_t<double> a({o_.run.rows.size(), js.size()});
    double* out = a.mutable_data();
    for (const std::vector<double>& row : o_.run.rows)
      for (size_t j : js) *out++ = row[j];
    return a;
  }
  py::array_t<double> Table() const { return RowsArray(o_.run.rows, o_.run.columns.size()); }
  std::string SummaryJson() const { return o_.SummaryJson(); }
  int status() const { return o_.status; }
  size_t IndexOf(const std::string& name) const {
    const auto& c = o_.run.columns;
    const size_t j = size_t(std::find(c.begin(), c.end(), name) - c.begin());
    if (j == c.size()) throw py::key_error(name);
    return j;
  }
  const std::string& error() const { return o_.error; }
  const std::string& warning() const { return o_.warning; }

 private:
  cli::FilterOutcome o_;
};

FilterRun RunRequest(const cli::FilterRequest* request, const Args* args, const Tables& tables,
                     bool smooth) {
  std::vector<std::pair<std::string, MemoryFile>> files = MemoryFiles(tables);
  cli::FilterOutcome o;
  {
    CallGuard guard(nullptr, nullptr);
    ScopedMemoryFiles scope(std::move(files));
    o = cli::ComputeFilter(request ? *request : cli::FilterRequestFromArgs(*args, smooth));
  }
  CallGuard::RaiseIfInterrupted();
  return FilterRun(std::move(o));
}

// `estlab filter` / `smooth` from arguments as the command line gives them.
FilterRun FilterFromArgs(const Args& args, const Tables& tables, bool smooth) {
  return RunRequest(nullptr, &args, tables, smooth);
}

// The same from the key table's settings (key, value), the data's columns
// (the table "data") and the command's own options, with no option parsing
// (the module's fast path).
FilterRun Filter(const std::string& model,
                 const std::vector<std::pair<std::string, std::string>>& keys,
                 const std::vector<std::string>& names, const std::vector<Column>& columns,
                 const std::string& sidecar, std::optional<std::string> truth, bool no_truth,
                 bool smooth, std::optional<int> smoother_trajectories, bool allow_degenerate) {
  cli::FilterRequest r;
  r.model = model;
  for (const auto& [key, value] : keys) {
    const FilterKey* k = FindFilterKey(key, "");
    if (k == nullptr) throw InputError("--" + key + ": not a filter key");
    if (k->kind == FilterKey::kRepeatable) {
      r.settings.Add(key, value);
    } else {
      r.settings.Set(key, value);
    }
  }
  r.data = "data";
  r.truth = std::move(truth);
  r.no_truth = no_truth;
  r.smooth = smooth;
  r.smoother_trajectories_given = smoother_trajectories.has_value();
  if (smoother_trajectories) r.smoother_trajectories = *smoother_trajectories;
  r.allow_degenerate = allow_degenerate;
  return RunRequest(&r, nullptr, {{"data", {names, columns, sidecar}}}, smooth);
}

// The filter key table: (key, "flag" | "repeatable" | "value").
std::vector<std::pair<std::string, std::string>> FilterKeys() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const FilterKey& k : FilterKeyTable())
    out.emplace_back(k.name, k.kind == FilterKey::kFlag         ? "flag"
                             : k.kind == FilterKey::kRepeatable ? "repeatable"
                                                                : "value");
  return out;
}

}  // namespace

void RegisterFilter(py::module_& m) {
  py::class_<FilterRun>(m, "FilterRun")
      .def_property_readonly("columns", &FilterRun::columns)
      .def_property_readonly("rows", &FilterRun::rows)
      .def("column", &FilterRun::Column)
      .def("stack", &FilterRun::Stack)
      .def("table", &FilterRun::Table)
      .def("summary_json", &FilterRun::SummaryJson)
      .def_property_readonly("status", &FilterRun::status)
      .def_property_readonly("error", &FilterRun::error)
      .def_property_readonly("warning", &FilterRun::warning);
  m.def("filter", &Filter);
  m.def("filter_args", &FilterFromArgs);
  m.def("filter_keys", &FilterKeys);
}

}  // namespace estlab::python
