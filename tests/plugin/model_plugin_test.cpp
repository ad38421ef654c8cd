// Models from files, end to end through the estlab binary: the built-in
// pendulum and double pendulum re-written as .model files give the built-ins'
// numbers; a first run compiles only its parts, with the whole entry's
// bytes; a C++ header compiles, loads and filters; the cache compiles once,
// rebuilds an edited model, survives two concurrent first uses and keeps
// nothing of a failed compile. Label "plugin": these compile models (minutes
// on two cores), so the sanitizer run (-L unit) leaves them out.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "cli/cli_test_util.h"

namespace estlab::testing {
namespace {

namespace fs = std::filesystem;

// One cache for the whole program, in the build tree: the models compile
// once per build of estlab.
std::string Cache() {
  return (fs::path(ESTLAB_BINARY).parent_path() / "test-model-cache").string();
}
std::string Example(const std::string& name) {
  return std::string(ESTLAB_SOURCE_DIR) + "/examples/models/" + name;
}
RunResult Est(const std::string& args, const std::string& cwd, const std::string& cache = Cache()) {
  return RunEstlab("--model-cache '" + cache + "' " + args, cwd);
}

std::vector<std::vector<double>> Numbers(const std::string& csv, std::string* header) {
  std::vector<std::vector<double>> rows;
  const auto lines = SplitLines(csv);
  for (size_t i = 0; i < lines.size(); ++i) {
    if (i == 0) {
      *header = lines[0];
      continue;
    }
    std::vector<double> row;
    std::stringstream cells(lines[i]);
    std::string cell;
    while (std::getline(cells, cell, ',')) row.push_back(std::strtod(cell.c_str(), nullptr));
    rows.push_back(row);
  }
  return rows;
}

// Same header, same shape, every number within rel * max(1, |a|).
void ExpectSameCsv(const std::string& a_path, const std::string& b_path, double rel) {
  std::string ha, hb;
  const auto a = Numbers(ReadFile(a_path), &ha), b = Numbers(ReadFile(b_path), &hb);
  ASSERT_EQ(ha, hb);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].size(), b[i].size()) << "row " << i;
    for (size_t j = 0; j < a[i].size(); ++j) {
      if (std::isnan(a[i][j]) && std::isnan(b[i][j])) continue;
      worst = std::max(worst, std::abs(a[i][j] - b[i][j]) / std::max(1.0, std::abs(a[i][j])));
    }
  }
  EXPECT_LE(worst, rel) << a_path << " vs " << b_path;
  std::printf("  %s: worst relative difference %.3g over %zu rows\n",
              fs::path(b_path).filename().c_str(), worst, a.size());
}

// (No std::regex here: GCC 12's <regex> trips -Wmaybe-uninitialized in the
// sanitizer build.)
std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The number right after `prefix` in `json` (NaN when absent).
double NumberAfter(const std::string& json, const std::string& prefix) {
  const size_t at = json.find(prefix);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + at + prefix.size(), nullptr);
}

std::vector<double> JsonArray(const std::string& json, const std::string& key) {
  std::vector<double> out;
  const std::string open = "\"" + key + "\": [";
  const size_t at = json.find(open);
  if (at == std::string::npos) return out;
  const size_t end = json.find(']', at);
  std::stringstream items(json.substr(at + open.size(), end - at - open.size()));
  std::string item;
  while (std::getline(items, item, ',')) out.push_back(std::strtod(item.c_str(), nullptr));
  return out;
}

const char* kPendulumSim =
    " --param g=9.8 --x0 theta=0.785398 --t-end 5 --dt 0.0125 --measure sin "
    "--meas-noise-var 0.1 --process-noise-var 1e-6,1e-4 --seed 3";
const char* kPendulumFilter =
    " --param g=9.8 --measure sin --data d.csv --integrator rk4 --x0 theta=0.785398 "
    "--p0-diag 0.1,0.1 --q-white-accel 1 --r-diag 0.1 --seed 5";

TEST(ModelFile, PendulumFileGivesTheBuiltInsNumbers) {
  TempDir dir;
  const std::string file = Example("pendulum.model");
  ASSERT_EQ(
      Est(std::string("simulate --model pendulum") + kPendulumSim + " --out d.csv", dir.path())
          .exit_code,
      0);
  const RunResult first =
      Est("simulate --model '" + file + "'" + kPendulumSim + " --out f.csv", dir.path());
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ExpectSameCsv(dir.File("d.csv"), dir.File("f.csv"), 1e-12);  // CVODES
  for (const char* filter : {"ekf", "ukf", "pf"}) {
    const std::string tail = std::string(kPendulumFilter) + " --filter " + filter;
    ASSERT_EQ(Est("filter --model pendulum" + tail + " --out b.csv", dir.path()).exit_code, 0);
    const RunResult r = Est("filter --model '" + file + "'" + tail + " --out m.csv", dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    ExpectSameCsv(dir.File("b.csv"), dir.File("m.csv"), 1e-12);
    const RunResult again =
        Est("filter --model '" + file + "'" + tail + " --out n.csv", dir.path());
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(again.err.find("compiling"), std::string::npos) << "compiled again: " << again.err;
  }
  const std::string tune =
      " --measure sin --data d.csv --filter ekf --integrator rk4 --x0 theta=0.785398 "
      "--p0-diag 0.1,0.1 --init-q-white-accel 0.3 --init-r-diag 0.3 --param g=9.8 --json";
  const RunResult b = Est("tune --model pendulum" + tune, dir.path());
  const RunResult m = Est("tune --model '" + file + "'" + tune, dir.path());
  ASSERT_EQ(b.exit_code, 0) << b.err;
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const auto tb = JsonArray(b.out, "theta"), tm = JsonArray(m.out, "theta");
  ASSERT_EQ(tb.size(), 2u) << b.out;
  ASSERT_EQ(tm.size(), tb.size()) << m.out;
  for (size_t i = 0; i < tb.size(); ++i)
    EXPECT_NEAR(tm[i], tb[i], 1e-8 * std::max(1.0, std::abs(tb[i])));
}

// Issue 38: a model file's first filter, smoother or simulation compiles
// only what that command runs (src/run/run_parts.h), with the same code as
// the whole entry: the same bytes out. A run that needs another part
// compiles that part; once the whole entry is in the cache, it serves every
// command.
TEST(ModelFile, FirstRunCompilesOnlyItsPartsWithTheWholeEntrysBytes) {
  TempDir dir, parts;
  const std::string file = "'" + Example("pendulum.model") + "'";
  auto library_names = [&] {
    std::vector<std::string> names;
    for (const auto& e : fs::recursive_directory_iterator(parts.path()))
      if (e.path().extension() == ".so") names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  };
  const RunResult sim =
      Est("simulate --model " + file + kPendulumSim + " --out d.csv", dir.path(), parts.path());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  EXPECT_NE(sim.err.find("run-all-none-sim"), std::string::npos) << sim.err;
  const std::string run = std::string(kPendulumFilter) + " --filter ukf";
  const RunResult a =
      Est("filter --model " + file + run + " --out a.csv", dir.path(), parts.path());
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_NE(a.err.find("compiling model"), std::string::npos) << a.err;
  const RunResult s =
      Est("smooth --model " + file + run + " --out s.csv", dir.path(), parts.path());
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const RunResult ad = Est("filter --model " + file + run + " --adapt sage-husa --out ad.csv",
                           dir.path(), parts.path());
  ASSERT_EQ(ad.exit_code, 0) << ad.err;
  EXPECT_EQ(library_names(),
            (std::vector<std::string>{"run-all-none-sim.so", "run-sin-sigma-adapt.so",
                                      "run-sin-sigma-smooth.so", "run-sin-sigma.so"}));
  // The whole entry (the shared cache: `model build` compiles it once per
  // build of estlab): the same bytes for each run, and no compile for a
  // filter it holds.
  const std::string whole = Cache();
  ASSERT_EQ(Est("model build " + file, dir.path(), whole).exit_code, 0);
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"simulate --model " + file + kPendulumSim, "d.csv"},
      {"filter --model " + file + run, "a.csv"},
      {"smooth --model " + file + run, "s.csv"},
      {"filter --model " + file + run + " --adapt sage-husa", "ad.csv"},
      {"filter --model " + file + kPendulumFilter + " --filter ekf", ""}};
  for (const auto& [command, same_as] : runs) {
    const RunResult w = Est(command + " --out w.csv", dir.path(), whole);
    ASSERT_EQ(w.exit_code, 0) << command << ": " << w.err;
    EXPECT_EQ(w.err.find("compiling"), std::string::npos) << command << ": " << w.err;
    if (!same_as.empty()) {
      EXPECT_EQ(ReadFile(dir.File("w.csv")), ReadFile(dir.File(same_as))) << command;
    }
  }
}

TEST(ModelFile, DoublePendulumFileGivesTheBuiltInsNumbers) {
  TempDir dir;
  const std::string sim =
      " --x0 theta1=0.785398,theta2=0.523599 --t-end 4 --dt 0.01 --measure angles "
      "--meas-noise-var 0.0025,0.0016 --seed 4";
  ASSERT_EQ(Est("simulate --model double-pendulum" + sim + " --out d.csv", dir.path()).exit_code,
            0);
  const std::string file = Example("double_pendulum.model");
  const RunResult r = Est("simulate --model '" + file + "'" + sim + " --out f.csv", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectSameCsv(dir.File("d.csv"), dir.File("f.csv"), 1e-12);
  const std::string filter =
      " --measure angles --data d.csv --integrator rk4 --x0 theta1=0.785398,theta2=0.523599 "
      "--p0-diag 0.01,0.01,0.01,0.01 --q-diag 1e-6,1e-6,1e-4,1e-4 --r-diag 0.0025,0.0016 --seed 2";
  for (const char* kind : {"ekf", "ukf", "pf"}) {
    const std::string tail = filter + " --filter " + kind;
    ASSERT_EQ(Est("filter --model double-pendulum" + tail + " --out b.csv", dir.path()).exit_code,
              0);
    const RunResult f = Est("filter --model '" + file + "'" + tail + " --out m.csv", dir.path());
    ASSERT_EQ(f.exit_code, 0) << f.err;
    ExpectSameCsv(dir.File("b.csv"), dir.File("m.csv"), 1e-12);
  }
}

TEST(ModelFile, CppHeaderCompilesLoadsAndFilters) {
  TempDir dir;
  const std::string header = std::string(ESTLAB_SOURCE_DIR) + "/tests/plugin/data/spring.h";
  const RunResult sim = Est("simulate --model '" + header +
                                "' --x0 x=1 --t-end 5 --dt 0.01 --measure position "
                                "--meas-noise-var 0.01 --seed 1 --out d.csv --json",
                            dir.path());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const RunResult f = Est("filter --model '" + header +
                              "' --measure position --data d.csv --filter ukf --x0 x=1 "
                              "--q-diag 1e-8,1e-8 --r-diag 0.01 --json --out e.csv",
                          dir.path());
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_NE(f.out.find("\"status\": \"ok\""), std::string::npos) << f.out;
  // The filter's position RMSE against the simulated truth is far below the
  // measurement noise (standard deviation 0.1).
  const double rmse = NumberAfter(f.out, "\"rmse\": {\"x\": ");
  EXPECT_LT(rmse, 0.05) << f.out;
  const RunResult show = Est("model show '" + header + "'", dir.path());
  ASSERT_EQ(show.exit_code, 0) << show.err;
  EXPECT_NE(show.out.find("spring"), std::string::npos);
}

// A discrete-time model file ([step]) simulates with its own map (the
// default integrator; others refused), and on this linear model the KF, EKF
// and UKF give the same log-likelihood, which is the tuner's NLL at the same
// noise.
TEST(ModelFile, DiscreteTimeModelSimulatesFiltersAndTunes) {
  TempDir dir;
  const std::string file = "'" + Example("linear_cv.model") + "'";
  const RunResult sim = Est("simulate --model " + file +
                                " --x0 pos=1,vel=0.5 --t-end 2 --dt 0.1 --measure position "
                                "--meas-noise-var 0.01 --seed 2 --out d.csv --json",
                            dir.path());
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  EXPECT_NE(sim.out.find("\"integrator\": \"discrete\""), std::string::npos) << sim.out;
  std::string header;
  const auto rows = Numbers(ReadFile(dir.File("d.csv")), &header);
  ASSERT_EQ(header, "t,pos,vel,z_pos");
  ASSERT_EQ(rows.size(), 21u);
  for (const auto& row : rows) {  // pos = 1 + 0.5 t, vel = 0.5: the map, step by step
    EXPECT_NEAR(row[1], 1.0 + 0.5 * row[0], 1e-12);
    EXPECT_EQ(row[2], 0.5);
  }
  const RunResult rk4 =
      Est("simulate --model " + file + " --integrator rk4 --out x.csv", dir.path());
  EXPECT_EQ(rk4.exit_code, 2);
  EXPECT_NE(rk4.err.find("is discrete-time"), std::string::npos) << rk4.err;
  EXPECT_FALSE(dir.Exists("x.csv"));

  const std::string common =
      " --measure position --data d.csv --x0 pos=1 --p0-diag 0.1,0.1 --q-diag 1e-6,1e-4 "
      "--r-diag 0.01";
  std::vector<double> logliks;
  // (alpha = 1: the default 1e-3 puts weights of 2.5e5 on the points, whose
  // rounding then shows at 1e-9; sigma_point_test.cpp.)
  for (const std::string kind : {"kf", "ekf", "ukf --alpha 1 --sigma-update redraw"}) {
    const RunResult f = Est("filter --model " + file + common + " --filter " + kind +
                                " --json --out " + kind.substr(0, 3) + ".csv",
                            dir.path());
    ASSERT_EQ(f.exit_code, 0) << kind << ": " << f.err;
    logliks.push_back(NumberAfter(f.out, "\"loglik\": "));
  }
  ExpectSameCsv(dir.File("kf.csv"), dir.File("ekf.csv"), 1e-10);
  ExpectSameCsv(dir.File("kf.csv"), dir.File("ukf.csv"), 1e-10);
  const RunResult tune = Est("tune --model " + file +
                                 " --measure position --data d.csv --x0 pos=1 --p0-diag 0.1,0.1 "
                                 "--init-q-diag 1e-6,1e-4 --init-r-diag 0.01 --filter kf --json",
                             dir.path());
  ASSERT_EQ(tune.exit_code, 0) << tune.err;
  const double nll = NumberAfter(tune.out, "\"nll_initial\": ");
  for (double loglik : logliks) EXPECT_NEAR(nll, -loglik, 1e-9 * std::abs(loglik)) << tune.out;
}

// A copy of the pendulum with a changed default: a new key.
std::string EditedPendulum(const std::string& dir, const std::string& g) {
  std::string text = ReadFile(Example("pendulum.model"));
  text = Replace(text, "name = pendulum-file", "name = pendulum-edit");
  text = Replace(text, "g = 9.81", "g = " + g);
  const std::string path = dir + "/edited.model";
  std::ofstream(path) << text;
  return path;
}

TEST(ModelFile, CacheCompilesOnceRebuildsEditsAndSurvivesConcurrentFirstUse) {
  TempDir dir, cache;
  const std::string path = EditedPendulum(dir.path(), "9.7");
  const std::string build = "model build '" + path + "' --json";
  RunResult a, b;
  std::thread ta([&] { a = Est(build, dir.path(), cache.path()); });
  std::thread tb([&] { b = Est(build, dir.path(), cache.path()); });
  ta.join();
  tb.join();
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const RunResult again = Est(build, dir.path(), cache.path());
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("\"compiled_entry\": false"), std::string::npos) << again.out;
  EXPECT_EQ(again.err.find("compiling"), std::string::npos);
  // Nothing temporary is left next to the library.
  for (const auto& e : fs::recursive_directory_iterator(cache.path()))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  EditedPendulum(dir.path(), "9.6");  // an edit: another key, compiled anew
  const RunResult edited = Est(build, dir.path(), cache.path());
  ASSERT_EQ(edited.exit_code, 0) << edited.err;
  EXPECT_NE(edited.out.find("\"compiled_entry\": true"), std::string::npos) << edited.out;
}

// Issue 40 items 8 and 10: a cache folder whose path holds a newline, an
// #error line and a quote compiles the model, not the path (its name once
// went into an #include); the same file named from its folder or from
// above has one key (the path was in the generated header).
TEST(ModelFile, CacheFolderPathIsNeverCompiledAndTheKeyIgnoresHowTheFileIsNamed) {
  TempDir dir, cache;
  const std::string odd = cache.path() + "/m\n#error INJECTED\n\"q\"";
  fs::create_directories(dir.File("R"));
  EditedPendulum(dir.File("R"), "9.65");
  const RunResult inner = Est("model build edited.model --json", dir.File("R"), odd);
  ASSERT_EQ(inner.exit_code, 0) << inner.err;
  EXPECT_EQ(inner.err.find("#error INJECTED\n  "), std::string::npos) << inner.err;
  EXPECT_EQ(inner.err.find("does not compile"), std::string::npos) << inner.err;
  EXPECT_NE(inner.out.find("\"compiled_entry\": true"), std::string::npos) << inner.out;
  const RunResult outer = Est("model build R/edited.model --json", dir.path(), odd);
  ASSERT_EQ(outer.exit_code, 0) << outer.err;
  EXPECT_NE(outer.out.find("\"compiled_entry\": false"), std::string::npos) << outer.out;
  // Issue 40 item 9: the cached header edited by hand is not what the key
  // says: it is put back and the library compiled again from it.
  std::string header;
  for (const auto& e : fs::recursive_directory_iterator(odd))
    if (e.path().filename() == "model.h") header = e.path().string();
  ASSERT_FALSE(header.empty());
  const std::string original = ReadFile(header);
  std::ofstream(header, std::ios::app) << "#error HAND-EDITED\n";
  // Item 15: what a killed compile left (a process that has ended) goes.
  const pid_t child = ::fork();
  if (child == 0) _exit(0);
  ::waitpid(child, nullptr, 0);
  const std::string folder = fs::path(header).parent_path().string(),
                    stale = folder + "/entry." + std::to_string(child) + ".tmp";
  for (const char* ext : {".cpp", ".log"}) {  // written two hours ago
    std::ofstream(stale + ext) << "left\n";
    fs::last_write_time(stale + ext, fs::file_time_type::clock::now() - std::chrono::hours(2));
  }
  // A fresh one may be another machine's compile in progress (a shared
  // cache): it stays.
  const std::string fresh = folder + "/tune." + std::to_string(child) + ".tmp.log";
  std::ofstream(fresh) << "running elsewhere\n";
  const RunResult edited = Est("model build R/edited.model --json", dir.path(), odd);
  ASSERT_EQ(edited.exit_code, 0) << edited.err;
  EXPECT_NE(edited.out.find("\"compiled_entry\": true"), std::string::npos) << edited.out;
  EXPECT_EQ(ReadFile(header), original);
  EXPECT_FALSE(fs::exists(stale + ".cpp"));
  EXPECT_FALSE(fs::exists(stale + ".log"));
  EXPECT_TRUE(fs::exists(fresh));
}

TEST(ModelFile, HeaderWithATypeErrorExits2AndLeavesNothing) {
  TempDir dir, cache;
  std::string text = ReadFile(std::string(ESTLAB_SOURCE_DIR) + "/tests/plugin/data/spring.h");
  text = Replace(text, "dx(0) = x(1);", "dx(0) = \"oops\";");
  std::ofstream(dir.File("broken.h")) << text;
  const RunResult r =
      Est("filter --model broken.h --measure position --data d.csv --q-diag 1,1 "
          "--r-diag 1 --out e.csv",
          dir.path(), cache.path());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("broken.h:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not compile"), std::string::npos) << r.err;
  EXPECT_FALSE(dir.Exists("e.csv"));
  for (const auto& e : fs::recursive_directory_iterator(cache.path()))
    EXPECT_FALSE(e.is_regular_file()) << "left behind: " << e.path();
}

TEST(ModelFile, MalformedModelFileExits2WithFileLineColumn) {
  TempDir dir;
  std::ofstream(dir.File("bad.model")) << "[model]\nname = bad\n[states]\nx =\n[rhs]\nx = y\n"
                                          "[measurement pos]\nx = x\n";
  for (const char* command : {"model check bad.model", "simulate --model bad.model --out o.csv"}) {
    const RunResult r = Est(command, dir.path());
    EXPECT_EQ(r.exit_code, 2) << command;
    EXPECT_NE(r.err.find("bad.model:6:5:"), std::string::npos) << command << ": " << r.err;
    EXPECT_FALSE(dir.Exists("o.csv"));
  }
}

}  // namespace
}  // namespace estlab::testing
