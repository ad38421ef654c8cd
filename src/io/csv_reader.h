// Reads numeric CSV files with a header row (the format `estlab simulate`
// writes). Empty cells and "nan"/"NaN" read as NaN (a missing value);
// anything else that is not a complete finite number is an InputError naming
// file, line and column.
//
// Usage:
//   CsvTable table = ReadCsv("d.csv");
//   int c = table.ColumnIndex("z_theta");   // -1 when absent
#ifndef ESTLAB_IO_CSV_READER_H_
#define ESTLAB_IO_CSV_READER_H_

#include <memory>
#include <string>
#include <vector>

namespace estlab {

struct CsvTable {
  std::string path;
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;  // rows[i][j], NaN = missing
  std::vector<long> line_numbers;         // file line of each row (1-based)

  int ColumnIndex(const std::string& name) const;
};

// A table held in memory (src/io/memory_files.h) under `path` is returned
// instead of a file's.
CsvTable ReadCsv(const std::string& path);
// The same, a memory table shared rather than copied.
std::shared_ptr<const CsvTable> OpenCsv(const std::string& path);
// Same, from text already in memory (`path` is used in messages).
CsvTable ParseCsv(const std::string& text, const std::string& path);
// A table from columns of values (the Python module's data), checked as a
// file's would be, with the same messages: names non-empty and distinct,
// every column as long as the first, values finite or NaN (missing). Row i
// is numbered as the line of a CSV file whose header is line 1: i + 2.
CsvTable TableFromColumns(const std::string& path, const std::vector<std::string>& names,
                          const std::vector<std::vector<double>>& columns);

}  // namespace estlab

#endif  // ESTLAB_IO_CSV_READER_H_
