// Helpers for tests that run the estlab executable: a fresh temporary working
// directory per test, running a command line with stdout/stderr captured, and
// reading files back.
//
// Usage:
//   estlab::testing::TempDir dir;
//   auto r = estlab::testing::RunEstlab("simulate --model pendulum --out o.csv", dir.path());
//   EXPECT_EQ(r.exit_code, 0) << r.err;
//   EXPECT_TRUE(dir.Exists("o.csv"));
#ifndef ESTLAB_TESTS_CLI_CLI_TEST_UTIL_H_
#define ESTLAB_TESTS_CLI_CLI_TEST_UTIL_H_

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef ESTLAB_BINARY
#error "ESTLAB_BINARY must be defined (path of the estlab executable)"
#endif

namespace estlab::testing {

// A new empty directory under the system temp directory, removed (with its
// contents) on destruction.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "estlab_cli_XXXXXX").string();
    std::vector<char> buf(tmpl.begin(), tmpl.end());
    buf.push_back('\0');
    if (::mkdtemp(buf.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = buf.data();
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  bool Exists(const std::string& name) const { return std::filesystem::exists(File(name)); }

  // Names of the regular files in the directory, sorted.
  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path_))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  std::string path_;
};

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

// The `build/estlab` commands of the first ```sh block after `heading` in the
// markdown file `path` (relative to the source tree), as written: lines
// joined at a trailing backslash, comments skipped, `$D` replaced by the
// block's `D=FOLDER` (relative to the source tree), "build/estlab " cut off.
// Empty when the heading is missing.
inline std::vector<std::string> MarkdownCommands(const std::string& path,
                                                 const std::string& heading) {
  const std::string text = ReadFile(std::string(ESTLAB_SOURCE_DIR) + "/" + path);
  const size_t section = text.find(heading);
  if (section == std::string::npos) return {};
  const size_t begin = text.find("```sh\n", section) + 6;
  const std::string block = text.substr(begin, text.find("```", begin) - begin);
  std::string d, joined;
  std::vector<std::string> commands;
  for (const std::string& line : SplitLines(block)) {
    if (line.rfind("D=", 0) == 0) d = std::string(ESTLAB_SOURCE_DIR) + "/" + line.substr(2);
    if (line.empty() || line[0] == '#' || line.rfind("D=", 0) == 0) continue;
    joined += line;
    if (joined.back() == '\\') {
      joined.pop_back();
      continue;
    }
    for (size_t at; (at = joined.find("$D")) != std::string::npos;) joined.replace(at, 2, d);
    if (joined.rfind("build/estlab ", 0) == 0) commands.push_back(joined.substr(13));
    joined.clear();
  }
  return commands;
}

// A noisy pendulum run (measurement `sin`) into d.csv, and filter options
// that fit it (append --data and --out).
inline constexpr const char* kPendulumSimulate =
    "simulate --model pendulum --param g=9.8 --x0 theta=0.785398 --t-end 5 --dt 0.0125 "
    "--integrator euler --measure sin --meas-noise-var 0.1 --seed 3 --out d.csv";
#define ESTLAB_TEST_PENDULUM_FILTER                                         \
  "filter --model pendulum --param g=9.8 --measure sin --integrator euler " \
  "--x0 theta=0.785398 --p0-diag 0.1,0.1 --q-white-accel 1 "
// Van der Pol (mu = 1000) data on which an explicit-Euler EKF at dt 0.01
// diverges: the divergence tests of `estlab filter` and `estlab smooth`.
inline constexpr const char* kDivergingVanDerPolSimulate =
    "simulate --model van-der-pol --x0 x=2 --t-end 2 --dt 0.01 --measure x "
    "--meas-noise-var 0.01 --out v.csv";
inline constexpr const char* kDivergingVanDerPolFilter =
    "--model van-der-pol --measure x --filter ekf --data v.csv --integrator euler --x0 x=2 "
    "--q-diag 1e-4,1e-4 --r-diag 0.01 ";
inline constexpr const char* kPendulumFilter = ESTLAB_TEST_PENDULUM_FILTER "--r-diag 0.1 ";
// The same up to the noise R (add --r-diag), on d.csv.
inline constexpr const char* kFilterWithoutR = ESTLAB_TEST_PENDULUM_FILTER "--data d.csv ";

struct RunResult {
  int exit_code = -1;  // -1 when the process did not exit normally
  std::string out;     // stdout
  std::string err;     // stderr
};

// Runs `ESTLAB_BINARY <args>` through /bin/sh with `cwd` as the working
// directory; args are passed to the shell verbatim (quote them yourself).
// stdout and stderr are captured through files outside `cwd`, so `cwd` only
// ever contains what estlab writes.
inline RunResult RunEstlab(const std::string& args, const std::string& cwd) {
  static int counter = 0;
  const std::string capture =
      (std::filesystem::temp_directory_path() /
       ("estlab_cli_capture_" + std::to_string(::getpid()) + "_" + std::to_string(counter++)))
          .string();
  const std::string cmd = "cd '" + cwd + "' && '" + std::string(ESTLAB_BINARY) + "' " + args +
                          " >'" + capture + ".out' 2>'" + capture + ".err'";
  const int status = std::system(cmd.c_str());
  RunResult r;
  if (status != -1 && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  r.out = ReadFile(capture + ".out");
  r.err = ReadFile(capture + ".err");
  std::filesystem::remove(capture + ".out");
  std::filesystem::remove(capture + ".err");
  return r;
}

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_CLI_CLI_TEST_UTIL_H_
