// For bench/python_overhead.py: the C++ side of the comparison, timed in
// the same process as the Python calls.
#ifndef ESTLAB_PYTHON_BENCH_FILTER_H_
#define ESTLAB_PYTHON_BENCH_FILTER_H_

#include <pybind11/pybind11.h>

namespace estlab::python {

// Defines bench_filter in the module.
void RegisterBench(pybind11::module_& m);

}  // namespace estlab::python

#endif  // ESTLAB_PYTHON_BENCH_FILTER_H_
