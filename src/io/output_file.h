// Files that appear whole or not at all: text goes to a short temporary name
// ".estlab-<pid>-<n>.tmp" in the target's folder and is renamed onto it by
// Commit(); a SIGINT/SIGTERM removes it, and a later process writing in the
// folder removes those of dead processes (temp_files.h). A file never committed is removed, so a
// failed command leaves no partial output under the requested name. A symlink is resolved first
// (the link stays, its target is replaced); anything that exists and is not a regular file
// (/dev/null, a FIFO, a device) is written directly, never replaced by a regular file.
//
// Usage:
//   OutputFile out("traj.csv");          // throws InputError if unwritable
//   out.stream() << "t,theta\n";
//   out.Commit();
// Two outputs that belong together (a CSV and its sidecar) appear both or
// neither: Finish() both (where a full disk shows), then Commit() both.
#ifndef ESTLAB_IO_OUTPUT_FILE_H_
#define ESTLAB_IO_OUTPUT_FILE_H_

#include <fstream>
#include <string>
#include <vector>

namespace estlab {

class OutputFile {
 public:
  explicit OutputFile(const std::string& path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::ostream& stream() { return stream_; }
  // Flushes, closes and checks for write errors (the temporary file is
  // removed and InputError thrown on one); the output is not in place yet.
  void Finish();
  // Finish() unless done, then renames into place. Throws InputError.
  void Commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string target_;    // path_ with symlinks resolved
  std::string tmp_path_;  // empty when writing directly to target_
  std::ofstream stream_;
  bool finished_ = false;
  bool committed_ = false;
};

// Throws InputError naming both when `output` (the value of option `option`,
// e.g. "--out") is the same file as one of `inputs`: same device and inode,
// so "d.csv", "./d.csv" and a link to it all match. Paths that do not exist
// never match. Call before reading inputs, so nothing is written.
void RefuseOutputOverInput(const std::string& option, const std::string& output,
                           const std::vector<std::string>& inputs);

// v as printf's "%.17g" writes it (17 significant digits: reads back as
// the same double), NaN as "" (an empty cell); std::to_chars, which writes
// the same bytes as printf, several times faster.
std::string FormatDouble(double v);
// The same appended to *out.
void AppendDouble(double v, std::string* out);

// A CSV cell for a console table: its number with 6 significant digits
// (FormatNumber: "2.176861944e-05" -> "2.17686e-05", inf and nan as such),
// "-" for an empty cell, text that is not a number unchanged. Never a cut
// string.
std::string CellForDisplay(const std::string& cell);

// Writes a CSV with a header row; values with FormatDouble, NaN as empty cell.
void WriteCsv(std::ostream& out, const std::vector<std::string>& columns,
              const std::vector<std::vector<double>>& rows);

// Writes a whole text file atomically.
void WriteTextFile(const std::string& path, const std::string& text);

}  // namespace estlab

#endif  // ESTLAB_IO_OUTPUT_FILE_H_
