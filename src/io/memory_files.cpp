#include "src/io/memory_files.h"

#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "src/core/types.h"

namespace estlab {

namespace {

std::mutex& Mutex() {
  static std::mutex m;
  return m;
}

std::map<std::string, MemoryFile>& Files() {
  static std::map<std::string, MemoryFile> files;
  return files;
}

}  // namespace

ScopedMemoryFiles::ScopedMemoryFiles(std::vector<std::pair<std::string, MemoryFile>> files) {
  std::lock_guard<std::mutex> lock(Mutex());
  for (auto& [name, file] : files)
    if (Files().count(name)) throw InputError("'" + name + "' is already in use by another call");
  for (auto& [name, file] : files) {
    Files().emplace(name, std::move(file));
    names_.push_back(name);
  }
}

ScopedMemoryFiles::~ScopedMemoryFiles() {
  std::lock_guard<std::mutex> lock(Mutex());
  for (const std::string& name : names_) Files().erase(name);
}

std::shared_ptr<const CsvTable> FindMemoryTable(const std::string& path) {
  std::lock_guard<std::mutex> lock(Mutex());
  const auto it = Files().find(path);
  return it == Files().end() ? nullptr : it->second.table;
}

std::optional<std::string> ReadSidecar(const std::string& path) {
  {
    std::lock_guard<std::mutex> lock(Mutex());
    const auto it = Files().find(path);
    if (it != Files().end()) {
      if (it->second.sidecar.empty()) return std::nullopt;
      return it->second.sidecar;
    }
  }
  std::ifstream in(path + ".json");
  if (!in) return std::nullopt;
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace estlab
