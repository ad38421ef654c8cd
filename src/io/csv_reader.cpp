#include "src/io/csv_reader.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/io/memory_files.h"

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

// Longer lines are refused: no real data row comes near it, and it stops
// `--data /dev/zero` (no line ends at all) from filling the memory.
constexpr size_t kMaxLineBytes = size_t(1) << 20;

// The next line of `in` into *line, without its end: "\n", "\r\n" or a lone
// "\r" (old Mac files). False at the end of the input.
bool NextLine(std::streambuf* in, const std::string& path, long line_no, std::string* line) {
  line->clear();
  int c = in->sbumpc();
  if (c == std::char_traits<char>::eof()) return false;
  for (; c != std::char_traits<char>::eof() && c != '\n'; c = in->sbumpc()) {
    if (c == '\r') {
      if (in->sgetc() == '\n') in->sbumpc();
      break;
    }
    if (line->size() == kMaxLineBytes)
      throw InputError(path + ":" + std::to_string(line_no) + ": line longer than " +
                       std::to_string(kMaxLineBytes) + " bytes");
    line->push_back(char(c));
  }
  return true;
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

namespace {

// The table in `in`; `path` names it in messages.
CsvTable ParseCsvStream(std::istream& in, const std::string& path) {
  CsvTable table;
  table.path = path;
  std::string line;
  long line_no = 0;
  bool have_header = false;
  while (NextLine(in.rdbuf(), path, line_no + 1, &line)) {
    if (++line_no == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 BOM
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
      row[j] = ParseNumber(c, Where(path, line_no, j, table.columns[j]));
    }
    table.rows.push_back(std::move(row));
    table.line_numbers.push_back(line_no);
  }
  if (!have_header) throw InputError(path + ": empty file (no header row)");
  return table;
}

}  // namespace

CsvTable ParseCsv(const std::string& text, const std::string& path) {
  std::istringstream in(text);
  return ParseCsvStream(in, path);
}

std::shared_ptr<const CsvTable> OpenCsv(const std::string& path) {
  if (std::shared_ptr<const CsvTable> memory = FindMemoryTable(path)) return memory;
  return std::make_shared<const CsvTable>(ReadCsv(path));
}

CsvTable ReadCsv(const std::string& path) {
  if (std::shared_ptr<const CsvTable> memory = FindMemoryTable(path)) return *memory;
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status))
    throw InputError("data file '" + path + "' is a directory");
  // A FIFO would block until a writer comes (forever, in a study), a
  // device might never end: data are regular files.
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw InputError("data file '" + path +
                     "' is not a regular file (a FIFO, socket or device); give a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("cannot read data file '" + path + "'");
  return ParseCsvStream(in, path);
}

CsvTable TableFromColumns(const std::string& path, const std::vector<std::string>& names,
                          const std::vector<std::vector<double>>& columns) {
  CsvTable table;
  table.path = path;
  constexpr long kHeaderLine = 1;
  for (size_t j = 0; j < names.size(); ++j) {
    if (Trim(names[j]).empty())
      throw InputError(Where(path, kHeaderLine, j, "") + ": empty column name in the header");
    if (names[j].find_first_of(",\n\r") != std::string::npos || Trim(names[j]) != names[j])
      throw InputError(Where(path, kHeaderLine, j, names[j]) +
                       ": a column name without commas, line ends or outer spaces");
    for (size_t i = 0; i < j; ++i)
      if (names[i] == names[j])
        throw InputError(Where(path, kHeaderLine, j, names[j]) + ": duplicate column name");
  }
  if (names.size() != columns.size())
    throw InputError(path + ": " + std::to_string(names.size()) + " column names for " +
                     std::to_string(columns.size()) + " columns");
  const size_t rows = columns.empty() ? 0 : columns[0].size();
  for (size_t j = 0; j < columns.size(); ++j)
    if (columns[j].size() != rows)
      throw InputError(path + ": column '" + names[j] + "' has " +
                       std::to_string(columns[j].size()) + " values, column '" + names[0] + "' " +
                       std::to_string(rows));
  table.columns = names;
  table.rows.assign(rows, std::vector<double>(columns.size()));
  for (size_t i = 0; i < rows; ++i) {
    const long line = long(i) + kHeaderLine + 1;
    for (size_t j = 0; j < columns.size(); ++j) {
      const double v = columns[j][i];
      if (std::isinf(v))  // NaN is a missing value, as an empty cell
        ParseNumber(v > 0 ? "inf" : "-inf", Where(path, line, j, names[j]));
      table.rows[i][j] = v;
    }
    table.line_numbers.push_back(line);
  }
  return table;
}

}  // namespace estlab
