// The C++ side of `import estlab` (the package: src/python/estlab/__init__.py):
// each function runs one command's core (src/cli/commands.h) on arguments as
// the command line gives them and data tables in memory, and hands back
// arrays and the command's JSON. The Python layer builds the arguments from
// keyword arguments and wraps the results (docs/python.md).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <boost/program_options.hpp>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "estlab_version.h"
#include "src/cli/commands.h"
#include "src/core/types.h"
#include "src/io/memory_files.h"
#include "src/options/filter_flags.h"
#include "src/options/filter_settings.h"
#include "src/python/call_guard.h"
#include "src/registry/registry.h"

namespace py = pybind11;
namespace po = boost::program_options;

namespace estlab::python {

namespace {

using Args = std::vector<std::string>;
using Column = py::array_t<double, py::array::c_style | py::array::forcecast>;
// name -> (column names, columns, sidecar JSON text)
using Tables =
    std::map<std::string, std::tuple<std::vector<std::string>, std::vector<Column>, std::string>>;

// The tables as memory files (checked as files are: TableFromColumns).
std::vector<std::pair<std::string, MemoryFile>> MemoryFiles(const Tables& tables) {
  std::vector<std::pair<std::string, MemoryFile>> files;
  for (const auto& [name, table] : tables) {
    const auto& [names, columns, sidecar] = table;
    std::vector<std::vector<double>> values;
    for (const Column& c : columns) {
      if (c.ndim() != 1) throw InputError(name + ": every column must be 1-D");
      values.emplace_back(c.data(), c.data() + c.size());
    }
    files.emplace_back(
        name, MemoryFile{std::make_shared<const CsvTable>(TableFromColumns(name, names, values)),
                         sidecar});
  }
  return files;
}

// rows (each as long as columns) -> a rows x columns array.
py::array_t<double> RowsArray(const std::vector<std::vector<double>>& rows, size_t columns) {
  py::array_t<double> a({rows.size(), columns});
  double* out = a.mutable_data();
  for (const std::vector<double>& row : rows) {
    std::memcpy(out, row.data(), std::min(row.size(), columns) * sizeof(double));
    out += columns;
  }
  return a;
}

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

py::tuple Simulate(const Args& args, const Tables& tables) {
  std::vector<std::pair<std::string, MemoryFile>> files = MemoryFiles(tables);
  cli::SimulateOutcome o;
  {
    CallGuard guard(nullptr, nullptr);
    ScopedMemoryFiles scope(std::move(files));
    o = cli::ComputeSimulation(args);
  }
  CallGuard::RaiseIfInterrupted();
  return py::make_tuple(o.result.columns, RowsArray(o.result.rows, o.result.columns.size()),
                        o.sidecar_json, o.summary_json, o.status, o.error);
}

// A whole command (tune, study, merge, figures, list) as the command line runs it, its
// stdout and stderr kept: (exit status, stdout, stderr).
py::tuple Run(const std::string& command, const Args& args, const Tables& tables) {
  std::vector<std::pair<std::string, MemoryFile>> files = MemoryFiles(tables);
  int status = 0;
  std::string out, err;
  {
    CallGuard guard(&out, &err);
    ScopedMemoryFiles scope(std::move(files));
    if (command == "tune") {
      status = cli::RunTune(args);
    } else if (command == "study") {
      status = cli::RunStudyCommand(args);
    } else if (command == "list") {
      status = cli::RunList(args);
    } else if (command == "merge") {
      status = cli::RunMerge(args);
    } else if (command == "figures") {
      status = cli::RunFigures(args);
    } else {
      throw InputError("no command '" + command + "'");
    }
  }
  CallGuard::RaiseIfInterrupted();
  return py::make_tuple(status, out, err);
}

// The options of a command: (name, kind) with kind "flag" (no value),
// "repeatable" or "value".
std::vector<std::pair<std::string, std::string>> Options(const std::string& command) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& o : cli::CommandOptions(command).options()) {
    const std::string kind = o->semantic()->max_tokens() == 0 ? "flag"
                             : o->semantic()->is_composing()  ? "repeatable"
                                                              : "value";
    out.emplace_back(o->long_name(), kind);
  }
  return out;
}

// A model's description (`estlab list --model NAME --json`); compiles a
// model file on first use, as the command line does.
std::string ModelJson(const std::string& name) {
  std::string out;
  {
    CallGuard guard(nullptr, nullptr);
    JsonWriter json;
    cli::ModelJson(FindModel(name), &json);
    out = json.str();
  }
  CallGuard::RaiseIfInterrupted();
  return out;
}

// For bench/python_overhead.py: seconds per call, over `reps` calls, on the
// same data, of
//   run:     the filter run alone (model.run_filter on a spec and data built
//            once);
//   request: the C++ API the module calls (a FilterRequest of the key
//            table's settings, the table made from the columns and
//            registered, ComputeFilter: spec built, data loaded and checked,
//            the run);
//   args:    the same from command-line arguments (options parsed).
std::tuple<double, double, double> BenchFilter(
    const std::string& model_name, const std::vector<std::pair<std::string, std::string>>& keys,
    const Args& args, const Tables& tables, int reps) {
  const auto& [names, arrays, sidecar] = tables.at("data");
  std::vector<std::vector<double>> columns;
  for (const Column& c : arrays) columns.emplace_back(c.data(), c.data() + c.size());
  CallGuard guard(nullptr, nullptr);
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point a) {
    return std::chrono::duration<double>(Clock::now() - a).count();
  };
  double sink = 0;
  const ModelEntry& model = FindModel(model_name);
  cli::FilterRequest request;
  request.model = model_name;
  request.data = "data";
  for (const auto& [key, value] : keys) request.settings.Set(key, value);
  double run = 0, with_request = 0, with_args = 0;
  {
    ScopedMemoryFiles scope(
        {{"data",
          {std::make_shared<const CsvTable>(TableFromColumns("data", names, columns)), sidecar}}});
    const FilterSpec spec = BuildFilterSpec(request.settings, model);
    const FilterData data =
        cli::LoadFilterData("data", model, model.FindMeasurement(spec.measurement), {});
    auto t0 = Clock::now();
    for (int i = 0; i < reps; ++i) sink += model.run_filter(spec, data).summary.loglik;
    run = seconds(t0) / reps;
    t0 = Clock::now();
    for (int i = 0; i < reps; ++i)
      sink += cli::ComputeFilter(cli::FilterRequestFromArgs(args, false)).run.summary.loglik;
    with_args = seconds(t0) / reps;
  }
  auto t0 = Clock::now();
  for (int i = 0; i < reps; ++i) {
    ScopedMemoryFiles scope(
        {{"data",
          {std::make_shared<const CsvTable>(TableFromColumns("data", names, columns)), sidecar}}});
    cli::FilterRequest r;
    r.model = model_name;
    r.data = "data";
    for (const auto& [key, value] : keys) r.settings.Set(key, value);
    sink += cli::ComputeFilter(r).run.summary.loglik;
  }
  with_request = seconds(t0) / reps;
  if (sink == 0.123456789) std::fprintf(stderr, " ");  // keep the runs
  return {run, with_request, with_args};
}

}  // namespace

void RegisterExceptions(py::module_& m) {
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<std::runtime_error> numerical_error(m, "NumericalError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const po::error& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const py::error_already_set&) {
      throw;  // pybind11's own
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const std::bad_alloc&) {
      PyErr_SetString(PyExc_MemoryError,
                      "out of memory: a size given (data rows, particles, smoother trajectories, "
                      "starts, lags, grid points, study runs or steps) needs more memory than "
                      "this machine has; make it smaller");
    } catch (const std::exception& e) {  // the command line's exit 1
      PyErr_SetString(numerical_error.ptr(), e.what());
    }
  });
}

}  // namespace estlab::python

PYBIND11_MODULE(_estlab, m) {
  m.doc() = "estlab's C++ core (use the estlab package, not this module)";
  estlab::python::RegisterExceptions(m);
  py::class_<estlab::python::FilterRun>(m, "FilterRun")
      .def_property_readonly("columns", &estlab::python::FilterRun::columns)
      .def_property_readonly("rows", &estlab::python::FilterRun::rows)
      .def("column", &estlab::python::FilterRun::Column)
      .def("stack", &estlab::python::FilterRun::Stack)
      .def("table", &estlab::python::FilterRun::Table)
      .def("summary_json", &estlab::python::FilterRun::SummaryJson)
      .def_property_readonly("status", &estlab::python::FilterRun::status)
      .def_property_readonly("error", &estlab::python::FilterRun::error)
      .def_property_readonly("warning", &estlab::python::FilterRun::warning);
  m.def("filter", &estlab::python::Filter);
  m.def("filter_args", &estlab::python::FilterFromArgs);
  m.def("filter_keys", &estlab::python::FilterKeys);
  m.def("simulate", &estlab::python::Simulate, py::arg("args"), py::arg("tables"));
  m.def("run", &estlab::python::Run, py::arg("command"), py::arg("args"), py::arg("tables"));
  m.def("options", &estlab::python::Options, py::arg("command"));
  m.def("model_json", &estlab::python::ModelJson, py::arg("name"));
  m.def("bench_filter", &estlab::python::BenchFilter);
  m.attr("version") = ESTLAB_VERSION;
}
