#include "src/registry/model_plugin.h"

#include <dlfcn.h>
#include <link.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "estlab_plugin_config.h"
#include "estlab_version.h"
#include "src/core/hash.h"
#include "src/core/types.h"
#include "src/modelfile/model_file.h"
#include "src/registry/model_source.h"

namespace estlab {
namespace {

namespace fs = std::filesystem;

std::string& CacheOverride() {
  static std::string dir;
  return dir;
}

ModelBuildReport& Report() {
  static ModelBuildReport report;
  return report;
}

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The file that holds estlab's code: the estlab binary, or the Python
// module (a shared library) that carries it. Empty when unknown.
fs::path EstlabImage() {
  Dl_info info{};
  struct link_map* map = nullptr;
  if (::dladdr1(reinterpret_cast<void*>(&EstlabImage), &info, reinterpret_cast<void**>(&map),
                RTLD_DL_LINKMAP) != 0 &&
      map != nullptr && map->l_name != nullptr && map->l_name[0] != '\0') {
    std::error_code ec;
    const fs::path lib = fs::canonical(map->l_name, ec);
    return ec ? fs::path() : lib;
  }
  std::error_code ec;  // the main program
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : self;
}

// That file (path, size, mtime): a rebuilt estlab gets new libraries.
std::string SelfIdentity() {
  const fs::path self = EstlabImage();
  struct stat st {};
  if (self.empty() || ::stat(self.c_str(), &st) != 0) return "unknown-binary";
  return self.string() + ":" + std::to_string(st.st_size) + ":" + std::to_string(st.st_mtime);
}

// A shell's status (std::system) that says Ctrl-C stopped the command: the
// compiler ended by SIGINT, or the shell exited 128 + SIGINT for it.
bool StoppedByCtrlC(int status) {
  return (WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) ||
         (WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGINT);
}

std::string Quote(const std::string& s) {  // for /bin/sh
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The compiler flags: the configured ones plus estlab's headers, those
// installed beside the binary (<prefix>/bin/estlab -> <prefix>/include/estlab,
// cmake/install.cmake) or the Python module
// (<prefix>/lib/python3/dist-packages/estlab/_estlab*.so) when they are there,
// else the source and build trees.
const std::string& PluginFlags() {
  static const std::string flags = [] {
    std::error_code ec;
    const fs::path self = EstlabImage();
    const bool module = self.extension() == ".so";
    const fs::path installed =
        (self.parent_path() /
         (module ? ESTLAB_PLUGIN_PYTHON_INSTALLED_INCLUDE : ESTLAB_PLUGIN_INSTALLED_INCLUDE))
            .lexically_normal();
    const bool is_installed =
        !self.empty() && fs::is_regular_file(installed / "src/registry/model_entry_impl.h", ec);
    return std::string(ESTLAB_PLUGIN_FLAGS) + " " +
           (is_installed ? "-I" + Quote(installed.string())
                         : std::string(ESTLAB_PLUGIN_SOURCE_INCLUDES));
  }();
  return flags;
}

std::string KeyOf(const ModelSource& s) {
  uint64_t h = Fnv1a64("estlab-model-library-v1\n");
  for (const std::string& part :
       {s.contents, s.type, std::string(ESTLAB_VERSION), std::string(ESTLAB_GIT_COMMIT),
        SelfIdentity(), std::string(ESTLAB_PLUGIN_CXX), PluginFlags(),
        std::string(ESTLAB_PLUGIN_TUNER_LIBS), std::string(ESTLAB_PLUGIN_LIBS)})
    h = Fnv1a64(part + "\n", h);
  return HashHex(h);
}

// Writes `text` to `path` whole or not at all (temporary name, rename).
void WriteAtomically(const fs::path& path, const std::string& text) {
  const fs::path tmp = path.string() + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out.flush()) throw InputError("cannot write '" + tmp.string() + "'");
  }
  fs::rename(tmp, path);
}

// The first lines of a compiler log, for the error message.
std::string Head(const std::string& text, int lines) {
  std::istringstream in(text);
  std::string line, out;
  for (int i = 0; i < lines && std::getline(in, line); ++i) out += "\n  " + line;
  return out;
}

// Prints elapsed seconds while `done` is false, on a terminal only.
class Progress {
 public:
  explicit Progress(std::string what) : what_(std::move(what)) {
    if (::isatty(2)) thread_ = std::thread([this] { Tick(); });
  }
  ~Progress() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }

 private:
  void Tick() {
    const auto start = std::chrono::steady_clock::now();
    while (!done_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      const double s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr, "\r  %s ... %.0f s", what_.c_str(), s);
    }
    std::fprintf(stderr, "\r\033[K");
  }
  std::string what_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

// Replaces every `from` in `text` with `to`.
std::string ReplaceAll(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = 0; (at = text.find(from, at)) != std::string::npos; at += to.size())
    text.replace(at, from.size(), to);
  return text;
}

// The compiled libraries in `dir` (entry.so, tune.so, run-*.so), not the
// NAME.PID.tmp.so of a compile in progress.
std::vector<fs::path> Libraries(const fs::path& dir) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().extension() == ".so" &&
        e.path().filename().string().find(".tmp") == std::string::npos)
      found.push_back(e.path());
  return found;
}

// The header the libraries of `dir` are compiled from: DIR/model.h, a copy
// of the text the key was made of (a .model file's generated header, a C++
// header's own text). When it is missing it is written; when it is not that
// text (edited by hand, or a header edited while it compiled) it is
// rewritten and the libraries beside it, which may hold the other text,
// are removed: a cache entry always holds what its key says.
void EnsureSnapshot(const fs::path& dir, const std::string& text) {
  fs::create_directories(dir);
  const fs::path header = dir / "model.h";
  std::error_code ec;
  if (fs::exists(header, ec) && ReadModelText(header.string()) == text) return;
  for (const fs::path& library : Libraries(dir)) fs::remove(library, ec);
  WriteAtomically(header, text);
}

// Whether `dir` holds a compiled library.
bool HoldsLibrary(const fs::path& dir) { return !Libraries(dir).empty(); }

// What a library holds, for the compile message.
std::string WhatItHolds(const std::string& which) {
  if (which == "entry") return "filters and simulator";
  if (which == "tune") return "tuner";
  return "what this command runs, " + which;
}

// Whether `path` was last written more than an hour ago: older than any
// compile (minutes), so a file of a compile that another machine sharing
// the cache runs now (its pid means nothing here) is never taken for a
// leftover.
bool OlderThanAnHour(const fs::path& path) {
  std::error_code ec;
  const auto written = fs::last_write_time(path, ec);
  return !ec && fs::file_time_type::clock::now() - written > std::chrono::hours(1);
}

// Removes what killed compiles left in `dir`: NAME.PID.tmp.{cpp,so,log}
// (and model.h.tmp.PID) of processes that no longer run here, written more
// than an hour ago.
void RemoveLeftovers(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const size_t tmp = name.find(".tmp");
    if (tmp == std::string::npos || !OlderThanAnHour(e.path())) continue;
    // The pid: the digits before ".tmp" (entry.123.tmp.cpp) or after it
    // (model.h.tmp.123).
    auto is_pid = [](const std::string& t) {
      return !t.empty() && t.size() < 12 && t.find_first_not_of("0123456789") == std::string::npos;
    };
    const size_t dot = tmp > 0 ? name.rfind('.', tmp - 1) : std::string::npos;
    std::string digits = dot == std::string::npos ? "" : name.substr(dot + 1, tmp - dot - 1);
    if (!is_pid(digits)) digits = name.size() > tmp + 5 ? name.substr(tmp + 5) : "";
    if (!is_pid(digits)) continue;
    const long pid = std::strtol(digits.c_str(), nullptr, 10);
    if (pid > 0 && ::kill(pid_t(pid), 0) != 0 && errno == ESRCH) fs::remove(e.path(), ec);
  }
}

// Whether `dir` holds the unit of a compile in progress (NAME.PID.tmp.cpp,
// written within the hour); this process's own are removed before it asks.
bool OtherCompileRunning(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() > 8 && name.compare(name.size() - 8, 8, ".tmp.cpp") == 0 &&
        !OlderThanAnHour(e.path()))
      return true;
  }
  return false;
}

// A file's text, or "" (and never an exception) when it cannot be read.
std::string ReadIfReadable(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  return text.str();
}

// Compiles `source` (a translation unit) into `library` unless it exists.
// Returns the seconds it took (0 when cached). The unit includes the
// snapshot DIR/model.h, which must still be `snapshot` when the compile
// ends (else it is refused: the library could hold another text).
double CompileLibrary(const ModelSource& s, const fs::path& dir, const std::string& which,
                      const std::string& unit, const std::string& snapshot) {
  const fs::path library = dir / (which + ".so");
  if (fs::exists(library)) return 0.0;
  fs::create_directories(dir);
  RemoveLeftovers(dir);
  std::string tag = ".";  // appended: GCC 12 -O3 warns falsely on "." + std::string
  tag += std::to_string(::getpid());
  tag += ".tmp";
  const fs::path cpp = dir / (which + tag + ".cpp"), so = dir / (which + tag + ".so"),
                 log = dir / (which + tag + ".log");
  WriteAtomically(cpp, unit);
  std::fprintf(stderr, "estlab: compiling model %s, %s (first use; cached in %s)\n", s.name.c_str(),
               WhatItHolds(which).c_str(), dir.c_str());
  const auto start = std::chrono::steady_clock::now();
  std::string libs;  // each a path (may hold spaces) or empty
  for (const char* lib : {ESTLAB_PLUGIN_LIBS, which == "tune" ? ESTLAB_PLUGIN_TUNER_LIBS : ""})
    if (*lib != '\0') {
      libs += ' ';
      libs += Quote(lib);
    }
  // A C++ header's own relative includes: from its folder.
  const std::string own =
      s.header.empty() ? "" : " -iquote " + Quote(fs::path(s.header).parent_path().string());
  const std::string command = std::string(ESTLAB_PLUGIN_CXX) + " " + PluginFlags() + own + " " +
                              Quote(cpp.string()) + " -o " + Quote(so.string()) + libs + " > " +
                              Quote(log.string()) + " 2>&1";
  int status;
  {
    Progress progress("compiling " + s.name);
    status = std::system(command.c_str());
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::error_code ec;
  if (status != 0) {
    // The compiler names the snapshot; the user knows their own file.
    const std::string output =
        fs::exists(log) ? ReplaceAll(ReadModelText(log.string()), (dir / "model.h").string(),
                                     s.header.empty() ? (dir / "model.h").string() : s.header)
                        : "";
    fs::remove(cpp, ec);
    fs::remove(so, ec);
    fs::remove(log, ec);
    // Nothing of a failed compile stays: the snapshot (written again on the
    // next use) and the folder once empty; not while another compile of
    // this key (its NAME.PID.tmp.cpp) still reads the snapshot.
    if (!HoldsLibrary(dir) && !OtherCompileRunning(dir)) {
      fs::remove(dir / "model.h", ec);
      fs::remove(dir, ec);  // only when empty
    }
    if (StoppedByCtrlC(status)) {
      // std::system ignored the Ctrl-C here; the compiler took it. Act on
      // it now (the command line's handler ends the process; the Python
      // module's raises KeyboardInterrupt), never as a compile error.
      ::raise(SIGINT);
      throw InputError("model " + s.path + ": compiling it was interrupted (Ctrl-C)");
    }
    throw InputError("model " + s.path + " does not compile:" + Head(output, 20));
  }
  if (ReadIfReadable(dir / "model.h") != snapshot) {  // gone or changed
    fs::remove(cpp, ec);
    fs::remove(so, ec);
    fs::remove(log, ec);
    throw InputError("model " + s.path + ": its cached header " + (dir / "model.h").string() +
                     " changed while it compiled; nothing was kept (run again)");
  }
  fs::rename(so, library);  // atomic: a concurrent compile of the same key just replaces it
  fs::remove(cpp, ec);
  fs::remove(log, ec);
  std::fprintf(stderr, "estlab: compiled model %s in %.1f s\n", s.name.c_str(), seconds);
  return seconds;
}

void* Open(const fs::path& library) {
  void* handle = ::dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = ::dlerror();
    throw InputError("cannot load model library " + library.string() + ": " +
                     (why != nullptr ? why : "unknown error") +
                     " (delete it to rebuild; see docs/models.md)");
  }
  return handle;  // never closed: the entry's function pointers point into it
}

void* Symbol(void* handle, const char* name, const fs::path& library) {
  void* symbol = ::dlsym(handle, name);
  if (symbol == nullptr) throw InputError("model library " + library.string() + " has no " + name);
  return symbol;
}

// The entry a compiled library (entry.so or run-*.so) describes.
std::unique_ptr<ModelEntry> LoadEntry(const fs::path& library) {
  using EntryFn = const ModelEntry* (*)();
  auto fn = reinterpret_cast<EntryFn>(Symbol(Open(library), "estlab_model_entry_v1", library));
  return std::make_unique<ModelEntry>(*fn());
}

}  // namespace

bool IsModelPath(const std::string& name) {
  return EndsWith(name, ".model") || EndsWith(name, ".h") || name.find('/') != std::string::npos;
}

std::string ResolveModelPath(const std::string& name) {
  std::error_code ec;
  if (IsModelPath(name) && fs::is_regular_file(name, ec)) return name;
  const char* path = std::getenv("ESTLAB_MODEL_PATH");
  if (path == nullptr || name.find('/') != std::string::npos) return "";
  std::istringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    for (const char* ext : {"", ".model", ".h"}) {
      const fs::path candidate = fs::path(dir) / (name + ext);
      if ((IsModelPath(candidate.string())) && fs::is_regular_file(candidate, ec))
        return candidate.string();
    }
  }
  return "";
}

void SetModelCacheDir(const std::string& dir) { CacheOverride() = dir; }

namespace {

// The cache folder as given (option, environment, XDG, HOME), maybe relative.
std::string GivenCacheDir() {
  if (!CacheOverride().empty()) return CacheOverride();
  if (const char* d = std::getenv("ESTLAB_MODEL_CACHE"); d != nullptr && *d) return d;
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d != nullptr && *d)
    return (fs::path(d) / "estlab").string();
  if (const char* h = std::getenv("HOME"); h != nullptr && *h)
    return (fs::path(h) / ".cache" / "estlab").string();
  throw InputError("no model cache folder: set ESTLAB_MODEL_CACHE or give --model-cache");
}

}  // namespace

// Absolute: the compiler runs in the cache folder, where a relative path
// (--model-cache cache) would name cache/cache/... (it used to fail with
// "fatal error: cache/<name>-<key>/model.h: No such file or directory").
std::string ModelCacheDir() { return fs::absolute(GivenCacheDir()).lexically_normal().string(); }

const ModelEntry& LoadModelFile(const std::string& path, ModelNeeds needs) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<ModelEntry>> loaded;
  const std::lock_guard<std::mutex> lock(mutex);
  ModelSource s = ReadModelSource(path);
  const fs::path dir = fs::path(ModelCacheDir()) / (s.name + "-" + KeyOf(s));
  // The units include the snapshot DIR/model.h of the text the key was made
  // of (EnsureSnapshot) by its name alone: they are compiled beside it, and
  // the cache folder's path (which may hold a newline or a quote) never
  // enters an #include.
  EnsureSnapshot(dir, s.contents);
  const fs::path header = "model.h";
  ModelBuildReport& report = Report();
  report = {};
  // The whole entry, or one command's parts (src/run/run_parts.h) while the
  // whole entry is neither loaded nor in the cache: a third of its compile.
  const bool parts =
      needs.run.has_value() && loaded.count(dir.string()) == 0 && !fs::exists(dir / "entry.so");
  const std::string which = parts ? PartsLibraryName(*needs.run) : "entry";
  const fs::path library = dir / (which + ".so");
  std::unique_ptr<ModelEntry>& entry = loaded[parts ? library.string() : dir.string()];
  if (entry == nullptr) {
    const std::string unit = parts
                                 ? ModelPartsUnit(s, header.string(), *needs.run)
                                 : ModelEntryUnit(s, header.string(), ModelLinkage::kPlugin, false);
    report.entry_seconds = CompileLibrary(s, dir, which, unit, s.contents);
    report.compiled_entry = report.entry_seconds > 0.0;
    entry = LoadEntry(library);
  }
  report.entry_library = library.string();
  if (needs.tuner && entry->tune == nullptr) {
    report.tuner_seconds = CompileLibrary(
        s, dir, "tune", ModelTunerUnit(s, header.string(), ModelLinkage::kPlugin), s.contents);
    report.compiled_tuner = report.tuner_seconds > 0.0;
    void* handle = Open(dir / "tune.so");
    using TunerFn = decltype(ModelEntry::tune) (*)();
    auto fn = reinterpret_cast<TunerFn>(Symbol(handle, "estlab_model_tuner_v1", dir / "tune.so"));
    entry->tune = fn();
  }
  if (needs.tuner) report.tuner_library = (dir / "tune.so").string();
  return *entry;
}

const ModelBuildReport& LastModelBuild() { return Report(); }

ModelEntry DescribeModelFile(const std::string& path) {
  if (!EndsWith(path, ".model"))
    throw InputError("'" + path + "' is not a .model file (a C++ header is described once built)");
  const modelfile::ModelFile m = modelfile::ParseModelFile(ReadModelText(path), path);
  ModelEntry e;
  e.name = m.name;
  e.description = m.description;
  for (const modelfile::StateDecl& s : m.states) {
    e.states.push_back(s.name);
    e.angle_states.push_back(s.angle);
    e.state_units.push_back(s.unit);
  }
  for (const modelfile::ParamDecl& p : m.params)
    e.params.push_back({p.name, p.default_value,
                        p.name + (p.unit.empty() ? "" : " [" + p.unit + "]"), p.constraint});
  for (const modelfile::MeasurementDecl& meas : m.measurements) {
    MeasurementDesc d;
    d.name = meas.name;
    for (const modelfile::OutputDecl& o : meas.outputs) {
      d.outputs.push_back(o.name);
      d.angle_outputs.push_back(o.angle);
    }
    e.measurements.push_back(d);
  }
  for (const modelfile::InvariantDecl& inv : m.invariants) e.invariants.push_back(inv.name);
  for (const modelfile::InputDecl& input : m.inputs) {
    e.inputs.push_back(input.name);
    e.input_units.push_back(input.unit);
  }
  e.stiff = m.stiff;
  e.discrete_time = m.discrete;
  return e;
}

}  // namespace estlab
