#include "src/registry/model_plugin.h"

#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
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

// The running binary (path, size, mtime): a rebuilt estlab gets new libraries.
std::string SelfIdentity() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  struct stat st {};
  if (ec || ::stat(self.c_str(), &st) != 0) return "unknown-binary";
  return self.string() + ":" + std::to_string(st.st_size) + ":" + std::to_string(st.st_mtime);
}

std::string Quote(const std::string& s) {  // for /bin/sh
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The compiler flags: the configured ones plus estlab's headers, those
// installed beside the binary (<prefix>/bin/estlab -> <prefix>/include/estlab,
// cmake/install.cmake) when they are there, else the source and build trees.
const std::string& PluginFlags() {
  static const std::string flags = [] {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    const fs::path installed =
        (self.parent_path() / ESTLAB_PLUGIN_INSTALLED_INCLUDE).lexically_normal();
    const bool is_installed =
        !ec && fs::is_regular_file(installed / "src/registry/model_entry_impl.h", ec);
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

// Compiles `source` (a translation unit) into `library` unless it exists.
// Returns the seconds it took (0 when cached).
double CompileLibrary(const ModelSource& s, const fs::path& dir, const std::string& which,
                      const std::string& unit) {
  const fs::path library = dir / (which + ".so");
  if (fs::exists(library)) return 0.0;
  fs::create_directories(dir);
  std::string tag = ".";  // appended: GCC 12 -O3 warns falsely on "." + std::string
  tag += std::to_string(::getpid());
  tag += ".tmp";
  const fs::path cpp = dir / (which + tag + ".cpp"), so = dir / (which + tag + ".so"),
                 log = dir / (which + tag + ".log");
  WriteAtomically(cpp, unit);
  std::fprintf(stderr, "estlab: compiling model %s, %s (first use; cached in %s)\n", s.name.c_str(),
               which == "entry" ? "filters and simulator" : "tuner", dir.c_str());
  const auto start = std::chrono::steady_clock::now();
  std::string libs;  // each a path (may hold spaces) or empty
  for (const char* lib : {ESTLAB_PLUGIN_LIBS, which == "tune" ? ESTLAB_PLUGIN_TUNER_LIBS : ""})
    if (*lib != '\0') {
      libs += ' ';
      libs += Quote(lib);
    }
  const std::string command = std::string(ESTLAB_PLUGIN_CXX) + " " + PluginFlags() + " " +
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
    const std::string output = fs::exists(log) ? ReadModelText(log.string()) : "";
    fs::remove(cpp, ec);
    fs::remove(so, ec);
    fs::remove(log, ec);
    throw InputError("model " + s.path + " does not compile:" + Head(output, 20));
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
  fs::path header = s.header;
  if (header.empty()) {  // a .model file: its generated header, kept for the user
    header = dir / "model.h";
    fs::create_directories(dir);
    if (!fs::exists(header)) WriteAtomically(header, s.contents);
  }
  ModelBuildReport& report = Report();
  report = {};
  std::unique_ptr<ModelEntry>& entry = loaded[dir.string()];
  if (entry == nullptr) {
    report.entry_seconds = CompileLibrary(
        s, dir, "entry", ModelEntryUnit(s, header.string(), ModelLinkage::kPlugin, false));
    report.compiled_entry = report.entry_seconds > 0.0;
    report.entry_library = (dir / "entry.so").string();
    void* handle = Open(dir / "entry.so");
    using EntryFn = const ModelEntry* (*)();
    auto fn = reinterpret_cast<EntryFn>(Symbol(handle, "estlab_model_entry_v1", dir / "entry.so"));
    entry = std::make_unique<ModelEntry>(*fn());
  }
  report.entry_library = (dir / "entry.so").string();
  if (needs.tuner && entry->tune == nullptr) {
    report.tuner_seconds =
        CompileLibrary(s, dir, "tune", ModelTunerUnit(s, header.string(), ModelLinkage::kPlugin));
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
  e.has_input = m.input.has_value();
  if (m.input) e.input_name = *m.input;
  e.stiff = m.stiff;
  e.discrete_time = m.discrete;
  return e;
}

}  // namespace estlab
