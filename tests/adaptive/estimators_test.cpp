// The estimator table (adaptive/estimators.h): every row's name parses back
// to it, names are unique, unknown names are errors that list the table's
// names (the studies' list without output-error), and the filters a row
// accepts are the ones it says in words.
#include "adaptive/estimators.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "src/core/types.h"

namespace estlab::testing {
namespace {

std::string ErrorOf(const std::string& name, bool studies_only) {
  try {
    (void)ParseEstimator(name, "--estimator", studies_only);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Estimators, EveryRowParsesBackAndNamesAreUnique) {
  std::set<std::string> names;
  for (const EstimatorInfo& e : Estimators()) {
    EXPECT_TRUE(names.insert(e.name).second) << e.name;
    EXPECT_EQ(ParseEstimator(e.name, "--estimator"), e.id) << e.name;
    EXPECT_EQ(&InfoOf(e.id), &e) << e.name;
    EXPECT_STREQ(EstimatorName(e.id), e.name);
    EXPECT_GT(e.default_max_iterations, 0) << e.name;
    EXPECT_NE(std::string(e.summary), "") << e.name;
    EXPECT_NE(std::string(e.filters), "") << e.name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"ml", "em", "als", "output-error"}));
}

TEST(Estimators, UnknownNamesListTheTable) {
  EXPECT_EQ(ErrorOf("kalman", false),
            "--estimator: expected ml, em, als or output-error, got 'kalman'");
  // Studies offer the estimators that tune a filter's Q and R.
  EXPECT_EQ(ErrorOf("output-error", true), "--estimator: expected ml, em or als, got 'output-error'");
  EXPECT_EQ(ErrorOf("ML", false).find("got 'ML'") != std::string::npos, true);
  EXPECT_EQ(EstimatorNames(" | ", " | "), "ml | em | als | output-error");
  EXPECT_EQ(EstimatorNames(", ", " or ", true), "ml, em or als");
}

TEST(Estimators, AcceptedFiltersMatchTheirDescription) {
  FilterSpec kf, ekf, iekf, ukf, pf;
  kf.filter = DefaultFilterOptions(FilterKind::kKf);
  ekf.filter = DefaultFilterOptions(FilterKind::kEkf);
  EkfOptions iterated;
  iterated.iterations = 3;
  iekf.filter = iterated;
  ukf.filter = DefaultFilterOptions(FilterKind::kUkf);
  pf.filter = DefaultFilterOptions(FilterKind::kPf);
  const EstimatorInfo& als = InfoOf(Estimator::kAls);
  EXPECT_TRUE(als.accepts(kf));
  EXPECT_TRUE(als.accepts(ekf));
  EXPECT_FALSE(als.accepts(iekf));
  EXPECT_FALSE(als.accepts(ukf));
  EXPECT_FALSE(als.accepts(pf));
  EXPECT_NE(std::string(als.filters).find("ekf"), std::string::npos);
  const EstimatorInfo& ml = InfoOf(Estimator::kMl);
  EXPECT_TRUE(ml.accepts(ukf));
  EXPECT_TRUE(ml.accepts(iekf));
  EXPECT_FALSE(ml.accepts(pf));  // no likelihood gradient through resampling
  EXPECT_FALSE(InfoOf(Estimator::kEm).accepts(pf));
  // Output error runs no filter: it accepts every spec and has no tuner.
  const EstimatorInfo& oe = InfoOf(Estimator::kOutputError);
  EXPECT_FALSE(oe.tuner);
  EXPECT_FALSE(oe.in_studies);
  EXPECT_TRUE(oe.params);
}

TEST(Estimators, SolversParseAndNameEachOther) {
  for (MlSolver s : {MlSolver::kLbfgs, MlSolver::kLeastSquares})
    EXPECT_EQ(ParseMlSolver(MlSolverName(s), "--solver"), s);
  try {
    (void)ParseMlSolver("newton", "--solver");
    ADD_FAILURE() << "newton parsed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--solver"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'newton'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace estlab::testing
