#include "src/python/filter_run.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "src/cli/commands.h"
#include "src/core/types.h"
#include "src/options/filter_settings.h"
#include "src/python/call_guard.h"
#include "src/python/keywords.h"
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
  // The columns NAME_est side by side: rows x states.
  py::array_t<double> Estimates() const {
    std::vector<std::string> names;
    for (const std::string& c : o_.run.columns)
      if (c.size() > 4 && c.compare(c.size() - 4, 4, "_est") == 0) names.push_back(c);
    return Stack(names);
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
  return FilterRun(CallGuard::Call(nullptr, nullptr, [&] {
    ScopedMemoryFiles scope(std::move(files));
    return cli::ComputeFilter(request ? *request : cli::FilterRequestFromArgs(*args, smooth));
  }));
}

// `estlab filter` / `smooth` from arguments as the command line gives them.
FilterRun FilterFromArgs(const Args& args, const Tables& tables, bool smooth) {
  return RunRequest(nullptr, &args, tables, smooth);
}

// How a keyword of estlab.filter / smooth goes into the request: a key of
// the filter key table (its kind), one of the command's own options, or
// neither (the command line's parser then says why).
struct KeywordEntry {
  enum Kind { kValue, kRepeatable, kFlag, kOwn, kNone } kind = kNone;
  std::string key;
};

const KeywordEntry& Entry(const std::string& command, const std::string& name,
                          const py::dict& aliases) {
  static std::unordered_map<std::string, KeywordEntry> cache[2];
  auto& entries = cache[command == "smooth"];
  auto it = entries.find(name);
  if (it != entries.end()) return it->second;
  KeywordEntry e;
  if (aliases.contains(name)) {
    e.key = aliases[py::str(name)].cast<std::string>();
  } else {
    e.key = name;
    std::replace(e.key.begin(), e.key.end(), '_', '-');
  }
  if (const FilterKey* k = FindFilterKey(e.key, "")) {
    e.kind = k->kind == FilterKey::kFlag         ? KeywordEntry::kFlag
             : k->kind == FilterKey::kRepeatable ? KeywordEntry::kRepeatable
                                                 : KeywordEntry::kValue;
  } else if (e.key == "truth" || e.key == "no-truth" || e.key == "allow-degenerate" ||
             e.key == "smoother-trajectories") {
    e.kind = KeywordEntry::kOwn;
  }
  return entries.emplace(name, std::move(e)).first->second;
}

// One keyword into the request; false when it needs the command line's
// parser.
bool AddKeyword(const std::string& command, const std::string& name, py::handle value,
                const py::dict& aliases, cli::FilterRequest* r) {
  const KeywordEntry& e = Entry(command, name, aliases);
  static const char* kKinds[] = {"value", "repeatable", "flag"};
  switch (e.kind) {
    case KeywordEntry::kNone:
      return false;
    case KeywordEntry::kValue:
    case KeywordEntry::kFlag:
      for (std::string& text : Values(command, name, kKinds[e.kind], value))
        r->settings.Set(e.key, std::move(text));
      return true;
    case KeywordEntry::kRepeatable:
      for (std::string& text : Values(command, name, kKinds[e.kind], value))
        r->settings.Add(e.key, std::move(text));
      return true;
    case KeywordEntry::kOwn:
      break;
  }
  if (e.key == "no-truth") {
    r->no_truth = !Values(command, name, "flag", value).empty();
  } else if (e.key == "allow-degenerate") {
    r->allow_degenerate = !Values(command, name, "flag", value).empty();
  } else if (e.key == "truth") {
    r->truth = Values(command, name, "value", value).front();
  } else if (command == "smooth" && PyLong_CheckExact(value.ptr())) {
    int overflow = 0;
    const long long n = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
    if (overflow || n < std::numeric_limits<int>::min() || n > std::numeric_limits<int>::max())
      return false;  // the parser's message says the range
    r->smoother_trajectories_given = true;
    r->smoother_trajectories = int(n);
  } else {
    return false;
  }
  return true;
}

// estlab.filter / smooth from keyword arguments (names as in Python, with
// the command's aliases), the data's columns (the table "data") and its
// sidecar, with no option parsing (the module's fast path). None when a
// keyword needs the command line's parser (config=, an unknown key: the
// message comes from there).
py::object Filter(const std::string& command, const std::string& model,
                  const std::vector<std::string>& names, const std::vector<Column>& columns,
                  const std::string& sidecar, const py::dict& kwargs, const py::dict& aliases) {
  cli::FilterRequest r;
  r.model = model;
  r.data = "data";
  r.smooth = command == "smooth";
  for (auto [name, value] : kwargs) {
    if (value.is_none()) continue;
    if (!AddKeyword(command, name.cast<std::string>(), value, aliases, &r)) return py::none();
  }
  return py::cast(RunRequest(&r, nullptr, {{"data", {names, columns, sidecar}}}, r.smooth));
}

}  // namespace

void RegisterFilter(py::module_& m) {
  py::class_<FilterRun>(m, "FilterRun")
      .def_property_readonly("columns", &FilterRun::columns)
      .def_property_readonly("rows", &FilterRun::rows)
      .def("column", &FilterRun::Column)
      .def("stack", &FilterRun::Stack)
      .def("estimates", &FilterRun::Estimates)
      .def("table", &FilterRun::Table)
      .def("summary_json", &FilterRun::SummaryJson)
      .def_property_readonly("status", &FilterRun::status)
      .def_property_readonly("error", &FilterRun::error)
      .def_property_readonly("warning", &FilterRun::warning);
  m.def("filter", &Filter);
  m.def("filter_args", &FilterFromArgs);
}

}  // namespace estlab::python
