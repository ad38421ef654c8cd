#include "src/io/output_file.h"

#include <cstdlib>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "src/core/types.h"

namespace estlab {

OutputFile::OutputFile(const std::string& path)
    : path_(path), tmp_path_(path + ".tmp." + std::to_string(::getpid())) {
  if (path.empty()) throw InputError("output path is empty");
  if (std::filesystem::is_directory(path))
    throw InputError("output path '" + path + "' is a directory");
  stream_.open(tmp_path_, std::ios::out | std::ios::trunc);
  if (!stream_) throw InputError("cannot write output file '" + path + "'");
}

OutputFile::~OutputFile() {
  if (!committed_) {
    stream_.close();
    std::remove(tmp_path_.c_str());
  }
}

void OutputFile::Commit() {
  stream_.flush();
  const bool ok = static_cast<bool>(stream_);
  stream_.close();
  if (!ok) {
    std::remove(tmp_path_.c_str());
    committed_ = true;
    throw InputError("error while writing '" + path_ + "'");
  }
  if (std::rename(tmp_path_.c_str(), path_.c_str()) != 0) {
    std::remove(tmp_path_.c_str());
    committed_ = true;
    throw InputError("cannot move output into place at '" + path_ + "'");
  }
  committed_ = true;
}

std::string CellForDisplay(const std::string& cell) {
  if (cell.empty()) return "-";
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  return *end == '\0' ? FormatNumber(v) : cell;
}

std::string FormatDouble(double v) {
  if (std::isnan(v)) return "";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

void WriteCsv(std::ostream& out, const std::vector<std::string>& columns,
              const std::vector<std::vector<double>>& rows) {
  for (size_t j = 0; j < columns.size(); ++j) out << (j ? "," : "") << columns[j];
  out << "\n";
  for (const auto& row : rows) {
    for (size_t j = 0; j < row.size(); ++j) out << (j ? "," : "") << FormatDouble(row[j]);
    out << "\n";
  }
}

void WriteTextFile(const std::string& path, const std::string& text) {
  OutputFile f(path);
  f.stream() << text;
  f.Commit();
}

}  // namespace estlab
