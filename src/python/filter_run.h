// `estlab.filter` and `estlab.smooth` in C++: the request (the fast path
// from the key table's settings, or command-line arguments), the run, and
// its result held for Python (FilterRun: columns gathered into arrays when
// asked for, the JSON written when asked for).
#ifndef ESTLAB_PYTHON_FILTER_RUN_H_
#define ESTLAB_PYTHON_FILTER_RUN_H_

#include <pybind11/pybind11.h>

namespace estlab::python {

// Defines FilterRun, filter and filter_args in the module.
void RegisterFilter(pybind11::module_& m);

}  // namespace estlab::python

#endif  // ESTLAB_PYTHON_FILTER_RUN_H_
