#include "src/io/output_file.h"

#include <cstdlib>

#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "src/core/types.h"
#include "src/io/temp_files.h"

namespace estlab {

namespace {

namespace fs = std::filesystem;

// The file a write to `path` lands in: symlinks followed (also a dangling one,
// whose target is created), other paths unchanged.
std::string ResolveSymlinks(const std::string& path) {
  std::error_code ec;
  if (!fs::is_symlink(fs::symlink_status(path, ec))) return path;
  const fs::path resolved = fs::weakly_canonical(path, ec);
  if (!ec && !fs::is_symlink(fs::symlink_status(resolved, ec))) return resolved.string();
  throw InputError("cannot resolve the symbolic link '" + path + "'");
}

}  // namespace

OutputFile::OutputFile(const std::string& path) : path_(path) {
  if (path.empty()) throw InputError("output path is empty");
  target_ = ResolveSymlinks(path);
  std::error_code ec;
  const fs::file_status st = fs::status(target_, ec);
  if (fs::is_directory(st)) throw InputError("output path '" + path + "' is a directory");
  const bool direct = fs::exists(st) && !fs::is_regular_file(st);
  if (!direct) {
    tmp_path_ = TempPathBeside(target_);
    RemoveStaleTempFiles(fs::path(target_).parent_path().string());
    RegisterTempFile(tmp_path_);
  }
  stream_.open(direct ? target_ : tmp_path_, std::ios::out | std::ios::trunc);
  if (!stream_) {
    if (!tmp_path_.empty()) UnregisterTempFile(tmp_path_);
    throw InputError("cannot write output file '" + path + "'");
  }
}

OutputFile::~OutputFile() {
  if (!committed_) {
    stream_.close();
    if (!tmp_path_.empty()) std::remove(tmp_path_.c_str());
  }
  if (!tmp_path_.empty()) UnregisterTempFile(tmp_path_);
}

void OutputFile::Finish() {
  if (finished_) return;
  finished_ = true;
  stream_.flush();
  const bool ok = static_cast<bool>(stream_);
  stream_.close();
  if (!ok) {
    committed_ = true;  // nothing left for the destructor
    if (!tmp_path_.empty()) std::remove(tmp_path_.c_str());
    throw InputError("error while writing '" + path_ + "'");
  }
}

void OutputFile::Commit() {
  Finish();
  committed_ = true;
  if (tmp_path_.empty()) return;
  const int renamed = std::rename(tmp_path_.c_str(), target_.c_str());
  UnregisterTempFile(tmp_path_);
  if (renamed != 0) {
    std::remove(tmp_path_.c_str());
    throw InputError("cannot move output into place at '" + path_ + "'");
  }
}

void RefuseOutputOverInput(const std::string& option, const std::string& output,
                           const std::vector<std::string>& inputs) {
  std::error_code ec;
  if (!fs::is_regular_file(output, ec)) return;  // /dev/null may be read and written
  for (const std::string& input : inputs) {
    if (fs::equivalent(output, input, ec) && !ec)
      throw InputError(option + " '" + output + "' is the input file '" + input +
                       "'; refusing to overwrite it (choose another output name)");
  }
}

std::string CellForDisplay(const std::string& cell) {
  if (cell.empty()) return "-";
  char* end = nullptr;
  const double v = std::strtod(cell.c_str(), &end);
  return *end == '\0' ? FormatNumber(v) : cell;
}

void AppendDouble(double v, std::string* out) {
  if (std::isnan(v)) return;
  char buf[32];  // "-1.2345678901234567e-308": 24
  out->append(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17).ptr);
}

std::string FormatDouble(double v) {
  std::string out;
  AppendDouble(v, &out);
  return out;
}

void WriteCsv(std::ostream& out, const std::vector<std::string>& columns,
              const std::vector<std::vector<double>>& rows) {
  std::string text;
  for (size_t j = 0; j < columns.size(); ++j) (text += j ? "," : "") += columns[j];
  text += '\n';
  constexpr size_t kFlushBytes = size_t(1) << 16;
  for (const auto& row : rows) {
    for (size_t j = 0; j < row.size(); ++j) {
      if (j) text += ',';
      AppendDouble(row[j], &text);
    }
    text += '\n';
    if (text.size() >= kFlushBytes) {
      out.write(text.data(), std::streamsize(text.size()));
      text.clear();
    }
  }
  out.write(text.data(), std::streamsize(text.size()));
}

void WriteTextFile(const std::string& path, const std::string& text) {
  OutputFile f(path);
  f.stream() << text;
  f.Commit();
}

}  // namespace estlab
