#include "src/python/tables.h"

#include <algorithm>
#include <cstring>
#include <memory>

#include "src/core/types.h"

namespace py = pybind11;

namespace estlab::python {

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

py::array_t<double> RowsArray(const std::vector<std::vector<double>>& rows, size_t columns) {
  py::array_t<double> a({rows.size(), columns});
  double* out = a.mutable_data();
  for (const std::vector<double>& row : rows) {
    std::memcpy(out, row.data(), std::min(row.size(), columns) * sizeof(double));
    out += columns;
  }
  return a;
}

}  // namespace estlab::python
