#include "src/python/bench_filter.h"

#include <pybind11/stl.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/cli/commands.h"
#include "src/options/filter_flags.h"
#include "src/options/filter_settings.h"
#include "src/python/call_guard.h"
#include "src/python/tables.h"
#include "src/registry/registry.h"

namespace estlab::python {

namespace {

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

void RegisterBench(pybind11::module_& m) { m.def("bench_filter", &BenchFilter); }

}  // namespace estlab::python
