// Data between numpy and the commands: columns in (as tables in memory,
// src/io/memory_files.h), rows out (as one rows x columns array).
#ifndef ESTLAB_PYTHON_TABLES_H_
#define ESTLAB_PYTHON_TABLES_H_

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "src/io/memory_files.h"

namespace estlab::python {

// The command's arguments, as on the command line.
using Args = std::vector<std::string>;
// One column: float64, contiguous (converted when not).
using Column = pybind11::array_t<double, pybind11::array::c_style | pybind11::array::forcecast>;
// name -> (column names, columns, sidecar JSON text)
using Tables =
    std::map<std::string, std::tuple<std::vector<std::string>, std::vector<Column>, std::string>>;

// The tables as memory files (checked as files are: TableFromColumns). Call
// with the GIL held.
std::vector<std::pair<std::string, MemoryFile>> MemoryFiles(const Tables& tables);

// rows (each as long as columns) -> a rows x columns array.
pybind11::array_t<double> RowsArray(const std::vector<std::vector<double>>& rows, size_t columns);

}  // namespace estlab::python

#endif  // ESTLAB_PYTHON_TABLES_H_
