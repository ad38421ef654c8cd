#include "src/io/csv_reader.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include "src/core/parse.h"
#include "src/core/types.h"

namespace estlab {

namespace {

std::vector<std::string> SplitLine(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  for (char c : line) {
    if (c == ',') {
      cells.push_back(Trim(cell));
      cell.clear();
    } else {
      cell += c;
    }
  }
  cells.push_back(Trim(cell));
  return cells;
}

std::string Where(const std::string& path, long line, size_t col, const std::string& name) {
  return path + ":" + std::to_string(line) + ": column " + std::to_string(col + 1) +
         (name.empty() ? "" : " ('" + name + "')");
}

}  // namespace

int CsvTable::ColumnIndex(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return int(i);
  return -1;
}

CsvTable ParseCsv(const std::string& text, const std::string& path) {
  CsvTable table;
  table.path = path;
  std::istringstream in(text);
  std::string line;
  long line_no = 0;
  bool have_header = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (Trim(line).empty() || Trim(line)[0] == '#') continue;
    std::vector<std::string> cells = SplitLine(line);
    if (!have_header) {
      for (size_t j = 0; j < cells.size(); ++j) {
        if (cells[j].empty()) {
          throw InputError(Where(path, line_no, j, "") + ": empty column name in the header");
        }
        for (size_t i = 0; i < j; ++i) {
          if (cells[i] == cells[j]) {
            throw InputError(Where(path, line_no, j, cells[j]) + ": duplicate column name");
          }
        }
      }
      table.columns = cells;
      have_header = true;
      continue;
    }
    if (cells.size() != table.columns.size()) {
      throw InputError(path + ":" + std::to_string(line_no) + ": expected " +
                       std::to_string(table.columns.size()) + " columns, found " +
                       std::to_string(cells.size()));
    }
    std::vector<double> row(cells.size());
    for (size_t j = 0; j < cells.size(); ++j) {
      const std::string& c = cells[j];
      if (c.empty() || c == "nan" || c == "NaN" || c == "NA") {
        row[j] = std::numeric_limits<double>::quiet_NaN();
        continue;
      }
      errno = 0;
      char* end = nullptr;
      const double v = std::strtod(c.c_str(), &end);
      if (end != c.c_str() + c.size() || errno == ERANGE || std::isinf(v)) {
        throw InputError(Where(path, line_no, j, table.columns[j]) + ": '" + c +
                         "' is not a finite number");
      }
      row[j] = v;
    }
    table.rows.push_back(std::move(row));
    table.line_numbers.push_back(line_no);
  }
  if (!have_header) throw InputError(path + ": empty file (no header row)");
  return table;
}

CsvTable ReadCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read data file '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseCsv(text.str(), path);
}

}  // namespace estlab
