// Memory of a study stays flat as the number of runs grows (issue
// "Performance": results are streamed to disk, not kept): `estlab study` on
// a small pendulum study with 10^3 and 10^4 runs, peak resident memory of the
// child process from wait4(); 10^4 runs must stay under 50 MB and within a
// few MB of 10^3 runs. Labelled "perf", not "unit": under the sanitizers
// (make test-asan runs -L unit) resident memory means something else.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// Pendulum, y = sin(theta), 10 steps per run; EKF, UKF and a 50-particle PF
// with the oracle noise, and the EKF with Q/R identified in each run; the
// time series of run 0 kept.
std::string PendulumStudy(int runs) {
  return "[study]\n"
         "name = memory\n"
         "seed = 11\n"
         "runs = " +
         std::to_string(runs) +
         "\n"
         "jobs = 1\n"
         "keep-runs = 0\n"
         "\n"
         "[scenario.pend]\n"
         "model = pendulum\n"
         "params = g=9.8\n"
         "x0 = theta=0.7853981633974483\n"
         "truth-x0 = sample\n"
         "dt = 0.05\n"
         "steps = 10\n"
         "truth-integrator = rk4\n"
         "process-noise = white-accel 0.5\n"
         "measurement = sin\n"
         "meas-noise-var = 0.01\n"
         "prior-p0-diag = 0.05,0.05\n"
         "\n"
         "[filter.ekf]\n"
         "kind = ekf\n"
         "integrator = rk4\n"
         "\n"
         "[filter.ukf]\n"
         "kind = ukf\n"
         "integrator = rk4\n"
         "alpha = 0.5\n"
         "\n"
         "[filter.pf]\n"
         "kind = pf\n"
         "integrator = rk4\n"
         "particles = 50\n"
         "resample = systematic\n"
         "\n"
         "[noise.oracle]\n"
         "q = oracle\n"
         "r = oracle\n"
         "\n"
         "[noise.ml]\n"  // Q/R identified in every run (issue 17)
         "q = tuned\n"
         "r = tuned\n"
         "tune-per-run = true\n"
         "filters = ekf\n";
}

struct ChildRun {
  int exit_status = -1;
  long max_rss_kb = 0;
  double wall_s = 0.0;
};

// Runs `estlab study CONFIG --out DIR --jobs 1` and reads the child's peak
// resident set size (ru_maxrss, kB on Linux) from wait4().
ChildRun RunStudyProcess(const std::string& config, const std::string& out,
                         const std::string& log) {
  ChildRun result;
  const auto start = std::chrono::steady_clock::now();
  std::fflush(stdout);  // the child must not inherit (and flush) buffered output
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (std::freopen(log.c_str(), "w", stdout) == nullptr) _exit(126);
    if (std::freopen(log.c_str(), "a", stderr) == nullptr) _exit(126);
    std::vector<std::string> args = {ESTLAB_BINARY, "study", config, "--out", out, "--jobs", "1"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (pid < 0) return result;
  int status = 0;
  struct rusage usage {};
  if (wait4(pid, &status, 0, &usage) != pid) return result;
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.max_rss_kb = usage.ru_maxrss;
  return result;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

long CountLines(const std::string& path) {
  std::ifstream in(path);
  long n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

TEST(StudyMemory, FlatFrom1000To10000RunsAndUnder50MB) {
  const fs::path dir =
      fs::temp_directory_path() / ("estlab_study_memory_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::vector<ChildRun> runs;
  for (int n : {1000, 10000}) {
    const std::string config = (dir / ("memory" + std::to_string(n) + ".ini")).string();
    const std::string out = (dir / ("out" + std::to_string(n))).string();
    const std::string log = (dir / ("log" + std::to_string(n) + ".txt")).string();
    std::ofstream(config) << PendulumStudy(n);
    const ChildRun r = RunStudyProcess(config, out, log);
    ASSERT_EQ(r.exit_status, 0) << "estlab study failed:\n" << ReadText(log);
    // Every run of every combination was written: one header and 4 x n rows.
    EXPECT_EQ(CountLines(out + "/runs.csv"), 1 + 4L * n);
    std::printf("  %5d runs: peak RSS %.1f MB, %.2f s\n", n, r.max_rss_kb / 1024.0, r.wall_s);
    runs.push_back(r);
  }
  const double small_mb = runs[0].max_rss_kb / 1024.0, large_mb = runs[1].max_rss_kb / 1024.0;
  EXPECT_LT(large_mb, 50.0) << "10^4 runs: peak RSS " << large_mb << " MB";
  // Flat: 9000 more runs may not add more than 8 MB (under 1 kB per run).
  EXPECT_LT(large_mb - small_mb, 8.0) << "peak RSS grew from " << small_mb << " MB (10^3 runs) to "
                                      << large_mb << " MB (10^4 runs)";
  fs::remove_all(dir);
}

}  // namespace
