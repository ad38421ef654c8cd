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

CsvTable ReadCsv(const std::string& path);
// Same, from text already in memory (`path` is used in messages).
CsvTable ParseCsv(const std::string& text, const std::string& path);

}  // namespace estlab

#endif  // ESTLAB_IO_CSV_READER_H_
