// `estlab tune` end to end: simulate, tune, validate, write tuned.ini, and the
// exit statuses for bad input (2) and divergence at every start (1).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <boost/program_options.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

struct CmdResult {
  int exit_code = -1;
  std::string out, err;
};

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class TuneCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("estlab_tune_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  CmdResult Estlab(const std::string& args) {
    const std::string out = (dir_ / "stdout.txt").string(), err = (dir_ / "stderr.txt").string();
    const std::string cmd = "cd '" + dir_.string() + "' && '" ESTLAB_BINARY "' " + args + " >'" +
                            out + "' 2>'" + err + "'";
    const int status = std::system(cmd.c_str());
    CmdResult r;
    if (status != -1 && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = Slurp(out);
    r.err = Slurp(err);
    return r;
  }
  bool Exists(const std::string& name) const { return fs::exists(dir_ / name); }
  std::string File(const std::string& name) const { return (dir_ / name).string(); }

  void Simulate(const std::string& out, int seed) {
    const CmdResult r = Estlab(
        "simulate --model pendulum --x0 theta=0.785398 --t-end 10 --dt 0.01 --integrator rk4 "
        "--process-noise-var 1e-6,1e-4 --measure sin --meas-noise-var 0.01 --seed " +
        std::to_string(seed) + " --out " + out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }

  static constexpr const char* kFilter =
      "--model pendulum --measure sin --filter ekf --integrator rk4 --x0 theta=0.785398 "
      "--p0-diag 1e-4,1e-4 ";

  fs::path dir_;
};

TEST_F(TuneCli, TunesValidatesAndWritesAnIniThatFilterReads) {
  Simulate("train.csv", 1);
  Simulate("valid.csv", 2);
  const CmdResult r = Estlab(std::string("tune ") + kFilter +
                             "--data train.csv --init-q-diag 1e-4,1e-2 --init-r-diag 1 "
                             "--validate valid.csv --out tuned.ini --json");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  for (const char* key :
       {"\"tuned\": {\"q\": {\"param\": \"diag\", \"diag\": [", "\"r\": {\"param\": \"diag\"",
        "\"q_matrix\": [[", "\"r_matrix\": [[", "\"std_errors_log\"", "\"nll_initial\"",
        "\"nll_tuned\"", "\"iterations\"", "\"termination\"", "\"wall_s\"", "\"validation\"",
        "\"initial\": {", "\"tuned\": {\"status\"", "\"oracle\": {", "\"nll_per_step\"",
        "\"mean_nis\"", "\"rmse\"", "\"mean_nees\"", "\"status\": \"converged\""}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << "missing " << key << " in\n" << r.out;
  }
  ASSERT_TRUE(Exists("tuned.ini"));
  const std::string ini = Slurp(File("tuned.ini"));
  EXPECT_NE(ini.find("q-diag = "), std::string::npos) << ini;
  EXPECT_NE(ini.find("r-diag = "), std::string::npos) << ini;

  // The file parses as a Boost config file with the options of `estlab filter`.
  namespace po = boost::program_options;
  po::options_description desc;
  desc.add_options()("q-diag", po::value<std::string>())("q", po::value<std::string>())(
      "q-white-accel", po::value<std::string>())("r-diag", po::value<std::string>())(
      "r", po::value<std::string>())("integrator", po::value<std::string>())(
      "substeps", po::value<std::string>());
  po::variables_map vm;
  std::ifstream in(File("tuned.ini"));
  po::store(po::parse_config_file(in, desc), vm);
  ASSERT_TRUE(vm.count("q-diag") && vm.count("r-diag"));
  // The process model the per-step Q belongs to (no input: no hold line).
  ASSERT_TRUE(vm.count("integrator") && vm.count("substeps")) << ini;
  EXPECT_EQ(vm["integrator"].as<std::string>(), "rk4");
  EXPECT_EQ(vm["substeps"].as<std::string>(), "1");
  EXPECT_EQ(ini.find("input-hold"), std::string::npos) << ini;
  const double r_tuned = std::stod(vm["r-diag"].as<std::string>());
  EXPECT_NEAR(r_tuned, 0.01, 0.002);  // simulated R = 0.01 over 1000 updates

  // And `estlab filter` runs with it.
  const CmdResult f = Estlab(std::string("filter ") + kFilter + "--data valid.csv --q-diag " +
                             vm["q-diag"].as<std::string>() + " --r-diag " +
                             vm["r-diag"].as<std::string>() + " --out est.csv");
  EXPECT_EQ(f.exit_code, 0) << f.err;

  // --config tuned.ini reads the same options: the same est.csv, byte for byte.
  const CmdResult c = Estlab(std::string("filter ") + kFilter +
                             "--data valid.csv --config tuned.ini --out est_config.csv");
  EXPECT_EQ(c.exit_code, 0) << c.err;
  EXPECT_EQ(Slurp(File("est.csv")), Slurp(File("est_config.csv")));
  // The command line wins: --r-diag replaces the file's R (and only R).
  const CmdResult o = Estlab(std::string("filter ") + kFilter +
                             "--data valid.csv --config tuned.ini --r-diag 1 --out est_r1.csv");
  EXPECT_EQ(o.exit_code, 0) << o.err;
  const CmdResult e =
      Estlab(std::string("filter ") + kFilter + "--data valid.csv --q-diag " +
             vm["q-diag"].as<std::string>() + " --r-diag 1 --out est_r1_explicit.csv");
  EXPECT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(Slurp(File("est.csv")), Slurp(File("est_r1.csv")));
  EXPECT_EQ(Slurp(File("est_r1.csv")), Slurp(File("est_r1_explicit.csv")));
  // And `estlab tune --config tuned.ini` starts from the tuned values: the
  // NLL at the start already equals the tuned one.
  const CmdResult t =
      Estlab(std::string("tune ") + kFilter + "--data train.csv --config tuned.ini --json");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  auto number_after = [](const std::string& text, const std::string& key) {
    const size_t at = text.find("\"" + key + "\": ");
    return at == std::string::npos ? std::nan("") : std::stod(text.substr(at + key.size() + 4));
  };
  const double nll_tuned = number_after(r.out, "nll_tuned");
  EXPECT_NEAR(number_after(t.out, "nll_initial"), nll_tuned, 1e-6 * std::abs(nll_tuned)) << t.out;
}

TEST_F(TuneCli, BadConfigFilesExitTwo) {
  Simulate("valid.csv", 6);
  {
    std::ofstream bad(File("bad_key.ini"));
    bad << "q-diag = 1e-4,1e-2\nr-diag = 0.01\nnot-an-option = 3\n";
  }
  {
    std::ofstream bad(File("bad_value.ini"));
    bad << "q-diag = 1e-4,abc\nr-diag = 0.01\n";
  }
  for (const char* config : {"missing.ini", "bad_key.ini", "bad_value.ini"}) {
    const CmdResult r = Estlab(std::string("filter ") + kFilter + "--data valid.csv --config " +
                               config + " --out est.csv");
    EXPECT_EQ(r.exit_code, 2) << config << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error:"), std::string::npos) << r.err;
    EXPECT_FALSE(Exists("est.csv")) << config;
  }
  const CmdResult r = Estlab(std::string("filter ") + kFilter +
                             "--data valid.csv --config bad_key.ini --out est.csv");
  EXPECT_NE(r.err.find("not-an-option"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bad_key.ini"), std::string::npos) << r.err;
}

TEST_F(TuneCli, WhiteAccelScalarLeastSquaresAndHumanOutput) {
  Simulate("train.csv", 3);
  const CmdResult r = Estlab(std::string("tune ") + kFilter +
                             "--data train.csv --data train.csv --init-q-white-accel 0.1 "
                             "--init-r-scalar 0.1 --solver least-squares --starts 2 --burn-in 10 "
                             "--out tuned.ini");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("estimator     ml (least-squares)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("log qc"), std::string::npos) << r.out;
  const std::string ini = Slurp(File("tuned.ini"));
  EXPECT_NE(ini.find("q-white-accel = "), std::string::npos) << ini;
  EXPECT_NE(ini.find("r-diag = "), std::string::npos) << ini;
}

// Issue 14 item 5: the text's "start N" and the JSON's message and best_start
// number the starts alike, from 1 (start 1 = the initial guess).
TEST_F(TuneCli, TextAndJsonNumberTheBestStartAlike) {
  Simulate("train.csv", 3);
  const std::string args = std::string("tune ") + kFilter +
                           "--data train.csv --init-q-diag 1e-4,1e-2 --init-r-diag 1 --starts 3 ";
  const CmdResult text = Estlab(args);
  ASSERT_EQ(text.exit_code, 0) << text.err << text.out;
  const size_t at = text.out.find(" iterations, start ");
  ASSERT_NE(at, std::string::npos) << text.out;
  const int best = std::atoi(text.out.c_str() + at + 19);
  EXPECT_GE(best, 1);
  EXPECT_LE(best, 3);
  const CmdResult json = Estlab(args + "--json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const std::string n = std::to_string(best);
  EXPECT_NE(json.out.find("best of 3 start(s): start " + n), std::string::npos) << json.out;
  EXPECT_NE(json.out.find("\"best_start\": " + n + ","), std::string::npos) << json.out;
}

TEST_F(TuneCli, BadInputExitsTwo) {
  Simulate("train.csv", 4);
  const std::string base = std::string("tune ") + kFilter + "--data train.csv ";
  for (const std::string& bad :
       {base + "--init-q-diag 1e-4,1e-2 --init-r-diag 1 --burn-in 5000",
        base + "--init-q-diag 1e-4,1e-2 --init-r-diag 1 --log-lower 1 --log-upper 0",
        base + "--init-q-diag 1e-4,1e-2 --init-r-diag 1 --q-param nope",
        base + "--init-q-diag 1e-4,1e-2 --init-r-diag 1 --r-param white-accel",
        base + "--init-q-diag 1e-4,1e-2 --init-r '1,0;0,1' --r-param full",
        base + "--init-q-diag 1e-4,1e-2 --init-r-diag 1 --init-r-scalar 1",
        base + "--init-q-diag 1e-4,1e-2 --init-r-diag 1 --filter pf",
        std::string("tune ") + kFilter + "--init-q-diag 1e-4,1e-2 --init-r-diag 1"}) {
    const CmdResult r = Estlab(bad + " --out tuned.ini");
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error:"), std::string::npos) << r.err;
    EXPECT_FALSE(Exists("tuned.ini")) << bad;
  }
}

// Issue 13: --estimator em and als end to end: the JSON's "em" history,
// the ini that `estlab filter --config` reads, ALS's identifiability notes,
// and the options they do not take (exit 2, no output).
TEST_F(TuneCli, EmAndAlsEstimators) {
  Simulate("train.csv", 6);
  const std::string base =
      std::string("tune ") + kFilter + "--data train.csv --init-q-diag 1e-4,1e-2 --init-r-diag 1 ";
  const CmdResult em = Estlab(base + "--estimator em --tolerance 1e-6 --out tuned_em.ini --json");
  ASSERT_EQ(em.exit_code, 0) << em.err << em.out;
  EXPECT_NE(em.out.find("\"form\": \"em\""), std::string::npos) << em.out;
  EXPECT_NE(em.out.find("\"nll_history\": ["), std::string::npos) << em.out;
  EXPECT_NE(em.out.find("\"nll_ml_from_em\": "), std::string::npos) << em.out;
  EXPECT_NE(em.out.find("\"estimator\": \"em\""), std::string::npos) << em.out;
  // The same estimator chosen in a --config file (tuner keys without "--"):
  // the same numbers.
  {
    std::ofstream cfg(File("em.ini"));
    cfg << "estimator = em\ntolerance = 1e-6\n";
  }
  const CmdResult em_cfg = Estlab(base + "--config em.ini --out tuned_em_cfg.ini --json");
  ASSERT_EQ(em_cfg.exit_code, 0) << em_cfg.err << em_cfg.out;
  EXPECT_EQ(Slurp(File("tuned_em.ini")), Slurp(File("tuned_em_cfg.ini")));
  const CmdResult f = Estlab(std::string("filter ") + kFilter +
                             "--data train.csv --config tuned_em.ini --out est.csv");
  EXPECT_EQ(f.exit_code, 0) << f.err;
  const CmdResult text = Estlab(base + "--estimator em --tolerance 1e-6");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("ml from EM's solution"), std::string::npos) << text.out;
  // EM with the initial angle estimated (--x0 0.6, truth 0.785398): the
  // same report, JSON and tuned.ini x0 and p0 lines as ml's.
  const CmdResult x0 = Estlab(
      "tune --model pendulum --measure sin --filter ekf --integrator rk4 --x0 theta=0.6 "
      "--p0-diag 1e-2,1e-4 --data train.csv --init-q-diag 1e-4,1e-2 --init-r-diag 1 "
      "--estimator em --tolerance 1e-7 --estimate-x0 theta --out tuned_em_x0.ini --json");
  ASSERT_EQ(x0.exit_code, 0) << x0.err << x0.out;
  const size_t at = x0.out.find("\"x0\": {\"theta\": ");
  ASSERT_NE(at, std::string::npos) << x0.out;
  const double theta0 = std::stod(x0.out.substr(at + 16));
  EXPECT_NEAR(theta0, 0.785398, 0.05) << x0.out;
  const std::string ini = Slurp(File("tuned_em_x0.ini"));
  EXPECT_NE(ini.find("\nx0 = "), std::string::npos) << ini;
  EXPECT_NE(ini.find("\np0"), std::string::npos) << ini;
  const CmdResult als = Estlab(base + "--estimator als --lags 8 --burn-in 50");
  ASSERT_EQ(als.exit_code, 0) << als.err << als.out;
  EXPECT_NE(als.out.find("ALS with 8 lag(s) identifies"), std::string::npos) << als.out;
  for (const std::string& bad :
       {base + "--estimator em --burn-in 5", base + "--estimator em --starts 2",
        base + "--estimator em --solver least-squares", base + "--tolerance 1e-6",
        base + "--lags 4", base + "--estimator als --lags 0", base + "--estimator als --filter ukf",
        base + "--estimator nope"}) {
    const CmdResult r = Estlab(bad + " --out bad.ini");
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.err;
    EXPECT_NE(r.err.find("estlab: error:"), std::string::npos) << r.err;
    EXPECT_FALSE(Exists("bad.ini")) << bad;
  }
}

TEST_F(TuneCli, EveryStartDivergingExitsOneWithoutIni) {
  Simulate("train.csv", 5);
  // trace(P0) = 2e13 exceeds the divergence guard (1e12) at the first row.
  const CmdResult r = Estlab(
      "tune --model pendulum --measure sin --filter ekf --integrator rk4 --x0 theta=0.785398 "
      "--p0-diag 1e13,1e13 --data train.csv --init-q-diag 1e-4,1e-2 --init-r-diag 1 "
      "--starts 3 --out tuned.ini --json");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.out.find("\"status\": \"all-starts-diverged\""), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("diverged"), std::string::npos) << r.err;
  EXPECT_FALSE(Exists("tuned.ini"));
}

// Issue 33: a fit that is not verified converged (here: stopped by the
// iteration limit) exits 1 with its status and sentence, writes no --out
// file; --keep-best writes the best admissible point, saying so in the file.
TEST_F(TuneCli, NotConvergedExitsOneAndWritesOnlyWithKeepBest) {
  Simulate("train.csv", 5);
  const std::string tune = std::string("tune ") + kFilter +
                           "--data train.csv --init-q-diag 1e-4,1e-2 --init-r-diag 1 "
                           "--max-iterations 1 --out tuned.ini ";
  const CmdResult r = Estlab(tune + "--json");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.out.find("\"status\": \"no-convergence\""), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("estlab: error: tune: status no-convergence"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no --out file written"), std::string::npos) << r.err;
  EXPECT_FALSE(Exists("tuned.ini"));
  const CmdResult kept = Estlab(tune + "--keep-best");
  EXPECT_EQ(kept.exit_code, 1) << kept.err;
  ASSERT_TRUE(Exists("tuned.ini"));
  EXPECT_NE(Slurp(File("tuned.ini")).find("# NOT A VERIFIED FIT (--keep-best)"), std::string::npos);
  EXPECT_NE(kept.out.find("NOT CONVERGED"), std::string::npos) << kept.out;
}

// Issue 15 item 14: from absurd initial values (qc = 1e12, R = 1e-12) one
// Ceres iteration with --integrator cvodes took 163 s, CVODES allowed
// 500000 steps in every interval. The work per trial point is now bounded
// (--max-integrator-steps, on average per interval, 100x in one): a point
// beyond it is infeasible. Checked here by its behaviour, not by a clock:
// a bound far below what sane values need makes every start fail with the
// sentence naming the bound, and the absurd start ends (the test's own
// timeout would catch a hang) with a status instead of computing for minutes.
TEST_F(TuneCli, CvodesWorkPerTrialPointIsBounded) {
  Simulate("train.csv", 5);
  const std::string tune =
      "tune --model pendulum --measure sin --filter ekf --integrator cvodes --x0 theta=0.785398 "
      "--p0-diag 1e-4,1e-4 --data train.csv --max-iterations 5 --json ";
  const CmdResult tight = Estlab(tune +
                                 "--init-q-diag 1e-4,1e-2 --init-r-diag 1 "
                                 "--max-integrator-steps 1");
  EXPECT_EQ(tight.exit_code, 1) << tight.err;
  EXPECT_NE(tight.out.find("\"status\": \"all-starts-"), std::string::npos) << tight.out;
  EXPECT_NE((tight.out + tight.err)
                .find("intervals, more than 10^4 + 1 (max integrator steps) "
                      "per interval"),
            std::string::npos)
      << tight.out << tight.err;
  // Five iterations may end short of the optimum: then the status says so
  // (no-convergence, exit 1), but no start fails.
  const CmdResult sane = Estlab(tune + "--init-q-diag 1e-4,1e-2 --init-r-diag 1");
  EXPECT_EQ(sane.out.find("\"status\": \"all-starts-"), std::string::npos) << sane.out;
  EXPECT_EQ(sane.exit_code, sane.out.find("\"status\": \"converged\"") != std::string::npos ? 0 : 1)
      << sane.err;
  const CmdResult absurd = Estlab(tune + "--init-q-white-accel 1e12 --init-r-diag 1e-12");
  EXPECT_TRUE(absurd.exit_code == 0 || absurd.exit_code == 1) << absurd.err;
  EXPECT_NE(absurd.out.find("\"status\": "), std::string::npos) << absurd.out;
  const CmdResult bad = Estlab(tune +
                               "--init-q-diag 1e-4,1e-2 --init-r-diag 1 "
                               "--max-integrator-steps 0");
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--max-integrator-steps: must be >= 1, got 0"), std::string::npos)
      << bad.err;
}

}  // namespace

namespace {

// --estimate-param end to end: the estimates in the JSON and tuned.ini, which
// `estlab filter --config` reads (parameters included); bad names exit 2.
TEST_F(TuneCli, EstimatesParametersAndWritesThemForFilter) {
  const CmdResult s = Estlab(
      "simulate --model pendulum --param L=0.5,b=0.3 --x0 theta=1.2 --t-end 10 --dt 0.01 "
      "--integrator rk4 --process-noise-var 0,1e-3 --measure angle --meas-noise-var 1e-3 "
      "--seed 3 --out train.csv");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const std::string filter =
      "--model pendulum --measure angle --filter ekf --integrator rk4 --x0 theta=1.2 "
      "--p0-diag 1e-2,1e-2 ";
  const CmdResult r = Estlab("tune " + filter +
                             "--data train.csv --param L=0.8,b=0.1 --estimate-param L,b "
                             "--param-bounds b=0:5 --init-q-white-accel 1e-2 --init-r-diag 1e-2 "
                             "--out tuned.ini --json");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  for (const char* key :
       {"\"params\": {\"L\": ", "\"std_errors\": {\"L\": ", "\"params_initial\": {\"L\": 0.8",
        "\"identifiability\": []", "\"correlation\": [1, "}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << "missing " << key << " in\n" << r.out;
  }
  const std::string ini = Slurp(File("tuned.ini"));
  ASSERT_NE(ini.find("param = L="), std::string::npos) << ini;
  ASSERT_NE(ini.find("param = b="), std::string::npos) << ini;
  const double L = std::stod(ini.substr(ini.find("param = L=") + 10));
  EXPECT_NEAR(L, 0.5, 0.03);
  const CmdResult f =
      Estlab("filter " + filter + "--data train.csv --config tuned.ini --out est.csv --json");
  ASSERT_EQ(f.exit_code, 0) << f.err;
  // The filter with the estimated L, b and noise: NIS near 1.
  const size_t at = f.out.find("\"mean_nis\": ");
  ASSERT_NE(at, std::string::npos) << f.out;
  EXPECT_NEAR(std::stod(f.out.substr(at + 12)), 1.0, 0.15) << f.out;
  // `estlab simulate --config tuned.ini` takes the parameters (and skips Q/R).
  const CmdResult sim = Estlab(
      "simulate --model pendulum --config tuned.ini --x0 theta=1 --t-end 1 --out sim.csv --json");
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const std::string sidecar = Slurp(File("sim.csv.json"));  // the simulation's parameters
  const size_t l_at = sidecar.find("\"L\": ");
  ASSERT_NE(l_at, std::string::npos) << sidecar;
  EXPECT_DOUBLE_EQ(std::stod(sidecar.substr(l_at + 5)), L) << sidecar;
  {
    std::ofstream bad(File("bad_sim.ini"));
    bad << "param = L=0.5\nfilter = ekf\n";
  }
  const CmdResult bad_sim =
      Estlab("simulate --model pendulum --config bad_sim.ini --t-end 1 --out sim2.csv");
  EXPECT_EQ(bad_sim.exit_code, 2);
  EXPECT_NE(bad_sim.err.find("bad_sim.ini:2: "), std::string::npos) << bad_sim.err;
  EXPECT_FALSE(Exists("sim2.csv"));

  for (const std::string& bad :
       {std::string("--estimate-param len"), std::string("--estimate-param L --param-bounds b=0:1"),
        std::string("--estimate-param L --param-prior L=normal:1:-1")}) {
    const CmdResult e =
        Estlab("tune " + filter + "--data train.csv --init-q-white-accel 1e-2 --init-r-diag 1e-2 " +
               bad + " --out bad.ini");
    EXPECT_EQ(e.exit_code, 2) << bad << "\n" << e.err;
    EXPECT_NE(e.err.find("estlab: error:"), std::string::npos) << e.err;
    EXPECT_FALSE(Exists("bad.ini")) << bad;
  }
}

}  // namespace

namespace {

// Output-error, repeatable --validate with free-simulation RMSE, --profile
// and x0 = first-sample, on simulated data with state columns.
TEST_F(TuneCli, OutputErrorValidationProfileAndFirstSample) {
  for (int seed : {3, 4}) {
    const CmdResult s = Estlab(
        "simulate --model pendulum --param L=0.5,b=0.3 --x0 theta=1.2 --t-end 10 --dt 0.01 "
        "--integrator rk4 --process-noise-var 0,1e-4 --measure angle --meas-noise-var 1e-4 "
        "--seed " +
        std::to_string(seed) + " --out run" + std::to_string(seed) + ".csv");
    ASSERT_EQ(s.exit_code, 0) << s.err;
  }
  const std::string base =
      "tune --model pendulum --measure angle --filter ekf --integrator rk4 --x0 first-sample "
      "--p0-diag 1e-2,1 --data run3.csv --param L=0.8,b=0.1 --estimate-param L,b "
      "--init-q-white-accel 1e-2 --init-r-diag 1e-2 --validate run4.csv --validate run3.csv ";
  const CmdResult oe = Estlab(base + "--estimator output-error --horizon 0.5 --json --out oe.ini");
  ASSERT_EQ(oe.exit_code, 0) << oe.err << oe.out;
  for (const char* key : {"\"estimator\": \"output-error\"", "\"tuned\": {\"params\": {\"L\": ",
                          "\"free_rmse\": {\"theta\": ", "\"pred_rmse\": {\"theta\": ",
                          "\"data\": \"run4.csv\"", "\"data\": \"run3.csv\""}) {
    EXPECT_NE(oe.out.find(key), std::string::npos) << "missing " << key << " in\n" << oe.out;
  }
  EXPECT_NE(Slurp(File("oe.ini")).find("param = L="), std::string::npos);
  const CmdResult ml = Estlab(base + "--profile b=0.1:0.5:5 --profile-out prof_b");
  ASSERT_EQ(ml.exit_code, 0) << ml.err << ml.out;
  EXPECT_NE(ml.out.find("profile likelihood of b"), std::string::npos) << ml.out;
  EXPECT_NE(ml.out.find("free-sim RMSE over 0.5 s"), std::string::npos) << ml.out;
  const std::string csv = Slurp(File("prof_b.csv"));
  EXPECT_EQ(csv.rfind("b,nll,delta_nll,status\n", 0), 0u) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 6);
  EXPECT_TRUE(Exists("prof_b.gp"));
  // The profile's minimum is at the grid point nearest the estimate (0.3).
  std::istringstream rows(csv.substr(csv.find('\n') + 1));
  double best_b = 0.0, best_delta = 1e300;
  for (std::string row; std::getline(rows, row);) {
    const double b = std::stod(row),
                 delta = std::stod(row.substr(row.find(',', row.find(',') + 1) + 1));
    if (delta < best_delta) best_delta = delta, best_b = b;
  }
  EXPECT_NEAR(best_b, 0.3, 1e-12) << csv;

  for (const std::string& bad :
       {base + "--estimator nope", base + "--horizon 0", base + "--profile g",
        base + "--estimator output-error --profile L", base + "--profile L=2:1",
        base + "--profile-out p"}) {
    const CmdResult e = Estlab(bad + " --out bad.ini");
    EXPECT_EQ(e.exit_code, 2) << bad << "\n" << e.err;
    EXPECT_NE(e.err.find("estlab: error:"), std::string::npos) << e.err;
    EXPECT_FALSE(Exists("bad.ini")) << bad;
  }
  // Issue 40 items 3, 16 and 19: a profile grid outside the parameter's
  // constraint (it used to report NLLs at L = -1 as converged), an absurd
  // grid, and empty option values (once ignored) are refused before the fit.
  const std::pair<std::string, std::string> refused[] = {
      {"--profile L=-1:0.9:5",
       "--profile L=-1:0.9: the grid leaves the parameter's range (parameter 'L' of model "
       "'pendulum' must be > 0, got -1)"},
      {"--profile b=-5:0.5:4", "parameter 'b' of model 'pendulum' must be >= 0, got -5"},
      {"--profile b=0.1:0.5:100000", "--profile b: N = 100000 points exceeds 1000"},
      {"--estimate-x0 ''", "--estimate-x0 is empty"},
  };
  for (const auto& [args, message] : refused) {
    const CmdResult e = Estlab(base + args + " --out bad.ini");
    EXPECT_EQ(e.exit_code, 2) << args << "\n" << e.err;
    EXPECT_NE(e.err.find(message), std::string::npos) << args << "\n" << e.err;
    EXPECT_FALSE(Exists("bad.ini")) << args;
    EXPECT_FALSE(Exists("profile_L.csv")) << args;
  }
  const CmdResult empty = Estlab(
      "tune --model pendulum --measure angle --data run3.csv --estimate-param '' --out bad.ini");
  EXPECT_EQ(empty.exit_code, 2) << empty.err;
  EXPECT_NE(empty.err.find("--estimate-param is empty"), std::string::npos) << empty.err;
}

}  // namespace

namespace {

// Issue 12, done-when 4: the real single-pendulum recording (one training
// piece of examples/data/multiarm/single), the built-in pendulum with the
// recorded angle (from upright) shifted by pi. The joint fit of L, b with Q
// and R on all four pieces gives L = 0.15316 (omega0^2 = g / L = 64.05 1/s^2)
// and b = 0.0555 1/s (docs/real-data.md); one piece must land near it, with
// finite standard errors and no identifiability note, and output-error on the
// same piece near its own 4-piece value.
TEST_F(TuneCli, RealSinglePendulumPieceFitsLengthAndDamping) {
  const std::string data = std::string(ESTLAB_SOURCE_DIR) + "/examples/data/multiarm/single/";
  const std::string base =
      "tune --model pendulum --measure angle --filter ekf --integrator rk4 --data " + data +
      "train_1.csv --column z_theta=theta-pi --column theta=theta-pi --x0 first-sample "
      "--p0-diag 0.01,100 --burn-in 50 --param L=0.15,b=0.05 --estimate-param L,b "
      "--init-q-white-accel 1 --init-r-diag 1e-6 --json ";
  auto number_after = [](const std::string& text, const std::string& key) {
    const size_t at = text.find(key);
    return at == std::string::npos ? std::nan("") : std::stod(text.substr(at + key.size()));
  };
  const CmdResult ml = Estlab(base);
  ASSERT_EQ(ml.exit_code, 0) << ml.err << ml.out;
  const double L = number_after(ml.out, "\"params\": {\"L\": ");
  const double se_L = number_after(ml.out, "\"std_errors\": {\"L\": ");
  const double b = number_after(ml.out, "\"b\": ");
  std::printf("  one piece, ml: L %.6f (SE %.2g), omega0^2 %.3f, b %.4f\n", L, se_L, 9.81 / L, b);
  EXPECT_NEAR(L, 0.15316, 0.002) << ml.out;
  EXPECT_GT(b, 0.03) << ml.out;
  EXPECT_LT(b, 0.08) << ml.out;
  EXPECT_TRUE(std::isfinite(se_L) && se_L > 0 && se_L < 1e-3) << ml.out;
  EXPECT_NE(ml.out.find("\"identifiability\": []"), std::string::npos) << ml.out;
  const CmdResult oe = Estlab(base + "--estimator output-error --horizon 0.5");
  ASSERT_EQ(oe.exit_code, 0) << oe.err << oe.out;
  EXPECT_NEAR(number_after(oe.out, "\"params\": {\"L\": "), 0.15286, 0.002) << oe.out;
}

}  // namespace
