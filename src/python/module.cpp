// The C++ side of `import estlab` (the package: src/python/estlab/__init__.py):
// each function runs one command's core (src/cli/commands.h) on arguments as
// the command line gives them and data tables in memory, and hands back
// arrays and the command's JSON. The Python layer builds the arguments from
// keyword arguments and wraps the results (docs/python.md). Here: simulate,
// the whole commands (tune, study, ...), the options, models, exceptions;
// filter_run.h: filter and smooth; tables.h: numpy <-> tables;
// call_guard.h: the GIL, the call lock, stdout, Ctrl-C.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <boost/program_options.hpp>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "estlab_version.h"
#include "src/cli/commands.h"
#include "src/core/types.h"
#include "src/io/json.h"
#include "src/io/memory_files.h"
#include "src/python/bench_filter.h"
#include "src/python/call_guard.h"
#include "src/python/filter_run.h"
#include "src/python/keywords.h"
#include "src/python/tables.h"
#include "src/registry/registry.h"

namespace py = pybind11;
namespace po = boost::program_options;

namespace estlab::python {

namespace {

py::tuple Simulate(const Args& args, const Tables& tables) {
  std::vector<std::pair<std::string, MemoryFile>> files = MemoryFiles(tables);
  const cli::SimulateOutcome o = CallGuard::Call(nullptr, nullptr, [&] {
    ScopedMemoryFiles scope(std::move(files));
    return cli::ComputeSimulation(args);
  });
  return py::make_tuple(o.result.columns, RowsArray(o.result.rows, o.result.columns.size()),
                        o.sidecar_json, o.summary_json, o.status, o.error);
}

// A whole command (tune, study, merge, figures, list) as the command line runs it, its
// stdout and stderr kept: (exit status, stdout, stderr).
py::tuple Run(const std::string& command, const Args& args, const Tables& tables) {
  std::vector<std::pair<std::string, MemoryFile>> files = MemoryFiles(tables);
  std::string out, err;
  const int status = CallGuard::Call(&out, &err, [&] {
    ScopedMemoryFiles scope(std::move(files));
    if (command == "tune") return cli::RunTune(args);
    if (command == "study") return cli::RunStudyCommand(args);
    if (command == "list") return cli::RunList(args);
    if (command == "merge") return cli::RunMerge(args);
    if (command == "figures") return cli::RunFigures(args);
    throw InputError("no command '" + command + "'");
  });
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
// model file's description alone on first use, as the command line does.
std::string ModelJson(const std::string& name) {
  return CallGuard::Call(nullptr, nullptr, [&] {
    JsonWriter json;
    cli::ModelJson(FindModel(name, {.run = RunNeeds{.filter = -2}}), &json);
    return json.str();
  });
}

}  // namespace

// InputError (a ValueError) for the command line's exit-2 cases,
// NumericalError (a RuntimeError) for its exit 1.
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
  estlab::python::RegisterFilter(m);
  estlab::python::RegisterKeywords(m);
  m.def("simulate", &estlab::python::Simulate, py::arg("args"), py::arg("tables"));
  m.def("run", &estlab::python::Run, py::arg("command"), py::arg("args"), py::arg("tables"));
  m.def("options", &estlab::python::Options, py::arg("command"));
  m.def("model_json", &estlab::python::ModelJson, py::arg("name"));
  estlab::python::RegisterBench(m);
  m.attr("version") = ESTLAB_VERSION;
}
