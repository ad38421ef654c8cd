// The run figures' numbers (studies/report/run_figures.h): the autocorrelation
// against its definition and an AR(1) process, and the figure files.
#include "studies/report/run_figures.h"

#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace estlab {
namespace {

TEST(RunFigures, AutocorrelationByHand) {
  // e = 1, 2, 3, 4: mean 2.5, deviations -1.5 -0.5 0.5 1.5, c0 = 5/4,
  // c1 = (0.75 - 0.25 + 0.75)/4 = 1.25/4, c2 = (-0.75 - 0.75)/4.
  const std::vector<double> rho = Autocorrelation({1, 2, NAN, 3, 4}, 2);
  ASSERT_EQ(rho.size(), 2u);
  EXPECT_DOUBLE_EQ(rho[0], 0.25);
  EXPECT_DOUBLE_EQ(rho[1], -0.3);
  EXPECT_TRUE(Autocorrelation({1, 1, 1, 1, 1}, 2).empty());  // c0 = 0
  EXPECT_TRUE(Autocorrelation({1, 2, 3}, 2).empty());        // too short
}

// AR(1), x_k = phi x_{k-1} + w_k: rho_l = phi^l. White noise (phi = 0)
// stays inside +-1.96/sqrt(K) at about 95 % of the lags.
TEST(RunFigures, AutocorrelationOfAnAr1Process) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> w;
  for (double phi : {0.0, 0.6}) {
    std::vector<double> x(20000);
    double prev = 0.0;
    for (double& v : x) v = prev = phi * prev + w(rng);
    const std::vector<double> rho = Autocorrelation(x, 40);
    ASSERT_EQ(rho.size(), 40u);
    const double band = 1.96 / std::sqrt(double(x.size()));
    int inside = 0;  // counted for white noise only (phi = 0.6 widens them)
    for (int l = 1; l <= 40; ++l) {
      EXPECT_NEAR(rho[l - 1], std::pow(phi, l), 3 * band) << "phi " << phi << " lag " << l;
      inside += std::abs(rho[l - 1] - std::pow(phi, l)) < band;
    }
    if (phi == 0.0) {
      EXPECT_GE(inside, 34);  // 95 % of 40 is 38; binomial slack
    }
  }
}

TEST(RunFigures, WritesScriptsAndDataWithoutRendering) {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("estlab_run_fig_" + std::to_string(::getpid())))
          .string();
  RunFigureInput in;
  in.title = "x_y";  // an underscore: shown as written
  in.columns = {"t", "a_est", "a_var", "nu_a", "S_a", "nis"};
  for (int k = 0; k < 100; ++k) {
    const double nu = std::sin(0.7 * k);
    in.rows.push_back({0.125 * k, 1.0, 0.25, nu, 0.5, nu * nu / 0.5});
  }
  in.outputs = {"a"};
  in.meas_t = {0.0, 0.125};
  in.meas_z = {1.5, 0.5};
  in.objective_history = {3.0, 2.0, 1.5};
  FiguresOptions options;
  options.render = false;
  const FiguresSummary f = DrawRunFigures(in, dir, options);
  EXPECT_EQ(f.scripts.size(), 5u);  // estimates, innovations, nis, autocorrelation, convergence
  std::ifstream est(dir + "/estimates.dat");
  std::stringstream text;
  text << est.rdbuf();
  // est, est -+ 2 sd (sd 0.5), no truth; then the measurement block.
  EXPECT_NE(text.str().find("\n0.125 1 0 2 NaN\n"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("# t z_a\n0 1.5\n0.125 0.5\n"), std::string::npos) << text.str();
  std::ifstream gp(dir + "/estimates.gp");
  std::stringstream script;
  script << gp.rdbuf();
  EXPECT_NE(script.str().find("'x_y: estimate and +-2 sd' noenhanced"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace estlab
