// The study's task order (studies/run/study_schedule.h): costs by hand from the
// formulas of the header, and the longest-first order.
#include "studies/run/study_schedule.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "studies/study_test_util.h"

namespace estlab::testing {
namespace {

TEST(StudySchedule, LongestFirstIsStableAndCostliestFirst) {
  EXPECT_EQ(LongestFirst({}), std::vector<size_t>{});
  EXPECT_EQ(LongestFirst({1.0, 5.0, 1.0, 7.0, 5.0}), (std::vector<size_t>{3, 1, 4, 0, 2}));
  EXPECT_EQ(LongestFirst({2.0, 2.0, 2.0}), (std::vector<size_t>{0, 1, 2}));
}

TEST(StudySchedule, CostsFollowTheHeadersFormulas) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  // Pendulum (n = 2), sin (m = 1), 25 steps, rk4 with 1 substep: a Gaussian
  // filter step costs (2 + 1)^3 x 2 = 54, the 100-particle PF's 10 times that.
  const StudyConfig c = ParseStudyConfig(TinyStudy(4, 25, 100, true), "s.ini");
  const ScenarioConfig& sc = c.scenarios[0];
  double per_row = 0.0;
  for (const Combo& cb : sc.combos) {
    const std::string& kind = c.filters[size_t(cb.filter)].name;
    EXPECT_DOUBLE_EQ(ComboStepCost(sc, cb), kind == "pf" ? 540.0 : 54.0) << kind;
    per_row += ComboStepCost(sc, cb);
    if (cb.tune) {  // 2 datasets x 25 steps x 54 x 100 iterations
      EXPECT_DOUBLE_EQ(TuningCost(sc, cb), 2 * 25 * 54.0 * 100.0) << kind;
    }
  }
  EXPECT_DOUBLE_EQ(RunCost(sc, 0), 25.0 * per_row);
  EXPECT_DOUBLE_EQ(RunCost(sc, 3), RunCost(sc, 0));  // simulated runs: the same rows
}

TEST(StudySchedule, RecordedRunsOfDifferentLengthsGoLongestFirst) {
  if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
  ScenarioConfig sc;
  sc.model = &FindModel("pendulum");
  sc.recorded = true;
  for (size_t rows : {10, 30, 20}) {
    FilterData d;
    d.t.assign(rows, 0.0);
    sc.data_runs.push_back(d);
  }
  Combo cb;
  cb.spec.measurement = "sin";
  cb.spec.filter = EkfOptions{};
  cb.spec.transition.substeps = 3;  // (2 + 1)^3 x (3 + 1) = 108 a step
  sc.combos = {cb};
  std::vector<double> costs;
  for (int run = 0; run < 3; ++run) costs.push_back(RunCost(sc, run));
  EXPECT_EQ(costs, (std::vector<double>{10 * 108.0, 30 * 108.0, 20 * 108.0}));
  EXPECT_EQ(LongestFirst(costs), (std::vector<size_t>{1, 2, 0}));
  sc.combos[0].tune_per_run = true;  // a run that tunes costs 100 filter runs
  EXPECT_DOUBLE_EQ(RunCost(sc, 0), 100 * 10 * 108.0);
}

}  // namespace
}  // namespace estlab::testing
