#include "src/io/csv_reader.h"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string_view>

#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/io/memory_files.h"

namespace estlab {

namespace {

// Longer lines are refused: no real data row comes near it, and it stops
// `--data /dev/zero` (no line ends at all) from filling the memory.
constexpr size_t kMaxLineBytes = size_t(1) << 20;

std::string_view TrimView(std::string_view s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

// The line of `text` that starts at *pos, without its end ("\n", "\r\n" or
// a lone "\r": old Mac files); *pos moves past it. False at the end.
bool NextLine(std::string_view text, const std::string& path, long line_no, size_t* pos,
              std::string_view* line) {
  if (*pos >= text.size()) return false;
  size_t end = *pos;
  while (end < text.size() && text[end] != '\n' && text[end] != '\r') ++end;
  if (end - *pos > kMaxLineBytes)
    throw InputError(path + ":" + std::to_string(line_no) + ": line longer than " +
                     std::to_string(kMaxLineBytes) + " bytes");
  *line = text.substr(*pos, end - *pos);
  *pos = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
  return true;
}

// The cells of `line`, trimmed, into *cells (views into line).
void SplitCells(std::string_view line, std::vector<std::string_view>* cells) {
  cells->clear();
  size_t start = 0;
  for (size_t comma; (comma = line.find(',', start)) != std::string_view::npos; start = comma + 1)
    cells->push_back(TrimView(line.substr(start, comma - start)));
  cells->push_back(TrimView(line.substr(start)));
}

std::string Where(const std::string& path, long line, size_t col, const std::string& name) {
  return path + ":" + std::to_string(line) + ": column " + std::to_string(col + 1) +
         (name.empty() ? "" : " ('" + name + "')");
}

// A data cell's value: NaN for an empty, "nan", "NaN" or "NA" cell, else the
// number. std::from_chars reads what it can whole (correctly rounded, as
// strtod does); anything else (a '+' sign, hex, junk, inf, a number out of
// range) goes to ParseNumber, which takes what strtod takes and names the
// cell when it refuses (Where is built only then).
double CellValue(std::string_view c, const CsvTable& table, long line_no, size_t j) {
  if (c.empty() || c == "nan" || c == "NaN" || c == "NA")
    return std::numeric_limits<double>::quiet_NaN();
  double v;
  const auto [end, ec] = std::from_chars(c.data(), c.data() + c.size(), v);
  if (ec == std::errc() && end == c.data() + c.size() && std::isfinite(v)) return v;
  return ParseNumber(std::string(c), Where(table.path, line_no, j, table.columns[j]));
}

void ReadHeader(const std::vector<std::string_view>& cells, long line_no, CsvTable* table) {
  for (size_t j = 0; j < cells.size(); ++j) {
    if (cells[j].empty())
      throw InputError(Where(table->path, line_no, j, "") + ": empty column name in the header");
    for (size_t i = 0; i < j; ++i)
      if (cells[i] == cells[j])
        throw InputError(Where(table->path, line_no, j, std::string(cells[j])) +
                         ": duplicate column name");
  }
  table->columns.assign(cells.begin(), cells.end());
}

// The table in `text`; `path` names it in messages.
CsvTable ParseCsvText(std::string_view text, const std::string& path) {
  CsvTable table;
  table.path = path;
  std::string_view line;
  std::vector<std::string_view> cells;
  long line_no = 0;
  size_t pos = 0;
  bool have_header = false;
  while (NextLine(text, path, line_no + 1, &pos, &line)) {
    if (++line_no == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // BOM
    const std::string_view trimmed = TrimView(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    SplitCells(line, &cells);
    if (!have_header) {
      ReadHeader(cells, line_no, &table);
      have_header = true;
      continue;
    }
    if (cells.size() != table.columns.size()) {
      throw InputError(path + ":" + std::to_string(line_no) + ": expected " +
                       std::to_string(table.columns.size()) + " columns, found " +
                       std::to_string(cells.size()));
    }
    std::vector<double>& row = table.rows.emplace_back(cells.size());
    for (size_t j = 0; j < cells.size(); ++j) row[j] = CellValue(cells[j], table, line_no, j);
    table.line_numbers.push_back(line_no);
  }
  if (!have_header) throw InputError(path + ": empty file (no header row)");
  return table;
}

}  // namespace

int CsvTable::ColumnIndex(const std::string& name) const {
  for (size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return int(i);
  return -1;
}

CsvTable ParseCsv(const std::string& text, const std::string& path) {
  return ParseCsvText(text, path);
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
  // The whole file at once: by its size, or to its end where the size says
  // 0 (a /proc file, some FUSE mounts).
  std::string text;
  const std::streamoff size = in.seekg(0, std::ios::end).tellg();
  in.seekg(0);
  if (size > 0) {
    text.resize(size_t(size));
    in.read(text.data(), size);
    text.resize(size_t(in.gcount()));
  } else {
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  if (in.bad()) throw InputError("cannot read data file '" + path + "'");
  return ParseCsvText(text, path);
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
