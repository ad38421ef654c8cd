// Tiny study configurations shared by the study tests.
#ifndef ESTLAB_TESTS_STUDIES_STUDY_TEST_UTIL_H_
#define ESTLAB_TESTS_STUDIES_STUDY_TEST_UTIL_H_

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "src/registry/registry.h"

namespace estlab::testing {

// Pendulum with sin measurement, 25 steps: EKF, UKF and a 100-particle PF,
// each with the oracle noise and with a hand-tuned Q/R (and, with `tuned`,
// EKF and UKF with Q/R from the likelihood tuner, after the other settings).
inline std::string TinyStudy(int runs, int steps = 25, int particles = 100, bool tuned = false) {
  const std::string tuned_section =
      "[noise.tuned]\n"
      "q = tuned\n"
      "init-q-white-accel = 0.1\n"
      "r = tuned\n"
      "init-r-diag = 0.1\n"
      "tune-datasets = 2\n"
      "filters = ekf,ukf\n"
      "\n";
  return "[study]\n"
         "name = tiny\n"
         "seed = 7\n"
         "runs = " +
         std::to_string(runs) +
         "\n"
         "keep-runs = 0,2\n"
         "\n"
         "[scenario.pend]\n"
         "model = pendulum\n"
         "params = g=9.8\n"
         "x0 = theta=0.7853981633974483\n"
         "truth-x0 = sample\n"
         "dt = 0.05\n"
         "steps = " +
         std::to_string(steps) +
         "\n"
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
         "particles = " +
         std::to_string(particles) +
         "\n"
         "resample = systematic\n"
         "\n"
         "[noise.oracle]\n"
         "q = oracle\n"
         "r = oracle\n"
         "\n"
         "[noise.hand]\n"
         "q-diag = 1e-3,1e-2\n"
         "r-diag = 0.02\n"
         "\n" +
         (tuned ? tuned_section : std::string()) +
         "[report]\n"
         "reference = pend/ekf/oracle rmse_theta mean=0.1 var=0.01 | made up\n"
         "claim = rmse_theta: pf < ekf | PF beats EKF\n";
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The studies need the filter runner; skip where this build has none yet.
// text with its first `from` replaced by `to` (a failure when absent).
inline std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return text.replace(pos, from.size(), to);
}

inline bool FiltersAvailable() { return FindModel("pendulum").run_filter != nullptr; }

}  // namespace estlab::testing

#endif  // ESTLAB_TESTS_STUDIES_STUDY_TEST_UTIL_H_
