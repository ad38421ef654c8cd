#include "src/io/temp_files.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <mutex>

namespace estlab {

namespace {

// Fixed storage the signal handler can read without allocating: a slot is
// in use when its path is not empty.
constexpr int kSlots = 256;
constexpr size_t kPathBytes = 4096;
char g_paths[kSlots][kPathBytes];
std::mutex g_mutex;

extern "C" void RemoveTempFilesAndExit(int sig) {
  for (int i = 0; i < kSlots; ++i)
    if (g_paths[i][0] != '\0') ::unlink(g_paths[i]);  // async-signal-safe
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// ".estlab-<pid>-<n>.tmp" -> pid, else 0.
long TempFilePid(const std::string& name) {
  const std::string prefix = ".estlab-", suffix = ".tmp";
  if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return 0;
  const std::string middle =
      name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  const size_t dash = middle.find('-');
  if (dash == 0 || dash == std::string::npos || dash + 1 == middle.size()) return 0;
  for (size_t i = 0; i < middle.size(); ++i)
    if (i != dash && (middle[i] < '0' || middle[i] > '9')) return 0;
  return std::stol(middle.substr(0, dash));
}

}  // namespace

std::string TempPathBeside(const std::string& target) {
  static std::atomic<long> counter{0};  // OutputFiles are made by worker threads too
  const std::string name =
      ".estlab-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tmp";
  return (std::filesystem::path(target).parent_path() / name).string();
}

void RegisterTempFile(const std::string& path) {
  if (path.size() >= kPathBytes) return;  // not cleaned on a signal; still removed normally
  std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kSlots; ++i) {
    if (g_paths[i][0] != '\0') continue;
    // The path first, its first byte last: the handler never sees a half
    // written slot as in use.
    std::memcpy(g_paths[i] + 1, path.c_str() + 1, path.size());
    g_paths[i][0] = path[0];
    return;
  }
}

void UnregisterTempFile(const std::string& path) {
  std::lock_guard<std::mutex> lock(g_mutex);
  for (int i = 0; i < kSlots; ++i)
    if (g_paths[i][0] != '\0' && path == g_paths[i]) g_paths[i][0] = '\0';
}

void InstallTempFileCleanup() {
  struct sigaction sa {};
  sa.sa_handler = RemoveTempFilesAndExit;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

int RemoveStaleTempFiles(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  int removed = 0;
  for (fs::directory_iterator it(folder.empty() ? "." : folder, ec), end; !ec && it != end;
       it.increment(ec)) {
    const long pid = TempFilePid(it->path().filename().string());
    if (pid <= 0 || pid == long(::getpid()) || it->is_symlink(ec)) continue;
    if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to see)
    if (fs::remove_all(it->path(), ec) > 0) ++removed;           // a file, or a folder (merge)
  }
  return removed;
}

}  // namespace estlab
