// Input files held in memory: the Python module (src/python) hands a command
// its data as tables under names ("data", "data[1]", "validate[0]") instead
// of paths, so that the command reads, checks and reports them exactly as it
// would the files: ReadCsv and ReadSidecar look here first.
//
// A name is registered only while its ScopedMemoryFiles lives; the command
// line never registers any, so a path always means a file there.
//
// Usage:
//   ScopedMemoryFiles files(
//       {{"data", {std::make_shared<CsvTable>(TableFromColumns("data", names, cols)), ""}}});
//   RunTune({"--data", "data", ...});   // reads the table, names it "data:LINE"
#ifndef ESTLAB_IO_MEMORY_FILES_H_
#define ESTLAB_IO_MEMORY_FILES_H_

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "src/io/csv_reader.h"

namespace estlab {

struct MemoryFile {
  std::shared_ptr<const CsvTable> table;
  std::string sidecar;  // the text of NAME.json (estlab simulate's sidecar); "" = none
};

// Registers the files for its lifetime (replacing none: a name already
// registered is an InputError). Not copyable.
class ScopedMemoryFiles {
 public:
  explicit ScopedMemoryFiles(std::vector<std::pair<std::string, MemoryFile>> files);
  ~ScopedMemoryFiles();
  ScopedMemoryFiles(const ScopedMemoryFiles&) = delete;
  ScopedMemoryFiles& operator=(const ScopedMemoryFiles&) = delete;

 private:
  std::vector<std::string> names_;
};

// The registered table named `path` (shared, not copied), or null.
std::shared_ptr<const CsvTable> FindMemoryTable(const std::string& path);

// The sidecar PATH.json's text: the registered file's, else the file's on
// disk, else nullopt.
std::optional<std::string> ReadSidecar(const std::string& path);

}  // namespace estlab

#endif  // ESTLAB_IO_MEMORY_FILES_H_
