// The tuner key table and BuildTunerOptions (src/options/tuner_settings.h):
// defaults are TunerOptions' own (and the estimator's iterations), settings
// from the command line equal settings set directly, a key of another
// estimator is an error naming it, and every parse error names its key.
#include "src/options/tuner_settings.h"

#include <gtest/gtest.h>

#include <boost/program_options.hpp>
#include <set>
#include <string>
#include <vector>

#include "src/options/filter_flags.h"

namespace estlab::testing {
namespace {

namespace po = boost::program_options;

std::pair<std::string, std::string> ErrorOf(const TunerSettings& s) {
  try {
    (void)BuildTunerOptions(s, "q-diag", "r-diag");
  } catch (const KeyError& e) {
    return {e.key(), e.message()};
  } catch (const InputError& e) {
    return {"", e.what()};
  }
  return {"", ""};
}

TunerSettings Of(std::initializer_list<std::pair<const char*, const char*>> kv) {
  TunerSettings s;
  for (const auto& [k, v] : kv) s.Set(k, v);
  return s;
}

TunerSettings FromCommandLine(std::vector<std::string> args) {
  po::options_description desc;
  cli::AddTunerOptions(&desc);
  std::vector<const char*> argv = {"tune"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  po::variables_map vm;
  po::store(po::parse_command_line(static_cast<int>(argv.size()), argv.data(), desc), vm);
  po::notify(vm);
  return cli::TunerSettingsFromVariablesMap(vm);
}

TEST(TunerSettings, DefaultsAreTunerOptionsDefaults) {
  const TunerOptions built = BuildTunerOptions(TunerSettings(), "q-diag", "r-diag");
  const TunerOptions plain;
  EXPECT_EQ(built.estimator, Estimator::kMl);
  EXPECT_EQ(built.solver, plain.solver);
  EXPECT_EQ(built.starts, plain.starts);
  EXPECT_EQ(built.jobs, plain.jobs);
  EXPECT_EQ(built.start_spread, plain.start_spread);
  EXPECT_EQ(built.burn_in, plain.burn_in);
  EXPECT_EQ(built.bound_width, plain.bound_width);
  EXPECT_EQ(built.max_iterations, plain.max_iterations);
  EXPECT_EQ(built.max_integrator_steps, plain.max_integrator_steps);
  EXPECT_EQ(built.em_tolerance, plain.em_tolerance);
  EXPECT_EQ(built.als_lags, plain.als_lags);
  // EM's iterations default to its own row's.
  const TunerOptions em = BuildTunerOptions(Of({{"estimator", "em"}}), "q-diag", "r-diag");
  EXPECT_EQ(em.max_iterations, InfoOf(Estimator::kEm).default_max_iterations);
  EXPECT_EQ(em.max_iterations, 1000);
}

TEST(TunerSettings, CommandLineEqualsDirectSettings) {
  const TunerSettings cmd = FromCommandLine({"--estimator", "ml", "--solver", "least-squares",
                                             "--starts", "4", "--start-spread", "1.5",
                                             "--burn-in", "7", "--log-lower", "-9,-8"});
  const TunerSettings direct = Of({{"estimator", "ml"},
                                   {"solver", "least-squares"},
                                   {"starts", "4"},
                                   {"start-spread", "1.5"},
                                   {"burn-in", "7"},
                                   {"log-lower", "-9,-8"}});
  EXPECT_EQ(cmd.values(), direct.values());
  const TunerOptions o = BuildTunerOptions(cmd, "q-diag", "r-diag");
  EXPECT_EQ(o.solver, MlSolver::kLeastSquares);
  EXPECT_EQ(o.starts, 4);
  EXPECT_EQ(o.burn_in, 7);
  EXPECT_EQ(o.log_lower, (std::vector<double>{-9, -8}));
  // Defaults of the command line are not "given": they cannot clash with
  // another estimator's keys.
  EXPECT_TRUE(FromCommandLine({}).values().empty());
}

TEST(TunerSettings, FormIsTheOldNameOfSolver) {
  EXPECT_EQ(FromCommandLine({"--form", "least-squares"}).Get("solver"), "least-squares");
  EXPECT_THROW(FromCommandLine({"--form", "lbfgs", "--solver", "lbfgs"}), InputError);
}

TEST(TunerSettings, KeyOfAnotherEstimatorIsAnErrorNamingIt) {
  EXPECT_EQ(ErrorOf(Of({{"tolerance", "1e-7"}})),
            std::make_pair(std::string("tolerance"),
                           std::string("applies to the em estimator only (the estimator is ml)")));
  EXPECT_EQ(ErrorOf(Of({{"estimator", "em"}, {"lags", "4"}})).first, "lags");
  EXPECT_EQ(ErrorOf(Of({{"estimator", "em"}, {"solver", "least-squares"}})).first, "solver");
  EXPECT_EQ(ErrorOf(Of({{"estimator", "als"}, {"starts", "3"}})).first, "starts");
  EXPECT_EQ(ErrorOf(Of({{"estimator", "em"}, {"burn-in", "5"}})).first, "burn-in");
  EXPECT_EQ(ErrorOf(Of({{"estimator", "output-error"}, {"q-param", "diag"}})).first, "q-param");
  // Keys of every estimator are accepted by each.
  for (const EstimatorInfo& e : Estimators()) {
    const auto [key, message] = ErrorOf(Of({{"estimator", e.name}, {"max-iterations", "5"}}));
    EXPECT_EQ(message, "") << e.name;
  }
}

TEST(TunerSettings, ParseErrorsNameTheirKey) {
  struct Case {
    const char *key, *text, *expect;
  };
  for (const Case& c : std::vector<Case>{{"estimator", "kalman", "got 'kalman'"},
                                         {"solver", "newton", "'newton'"},
                                         {"starts", "0", "0"},
                                         {"starts", "two", "two"},
                                         {"start-spread", "nan", "nan"},
                                         {"log-lower", "1,x", "x"},
                                         {"max-iterations", "-1", "-1"},
                                         {"q-param", "tri", "tri"},
                                         {"r-param", "white-accel", "Q only"}}) {
    const auto [key, message] = ErrorOf(Of({{c.key, c.text}}));
    EXPECT_EQ(key, c.key) << c.key << "=" << c.text << ": " << message;
    EXPECT_NE(message.find(c.expect), std::string::npos) << c.key << ": " << message;
  }
}

TEST(TunerSettings, NoiseParameterisationFollowsTheGuess) {
  EXPECT_EQ(NoiseParamOfGuess("q-white-accel"), NoiseParam::kWhiteAccel);
  EXPECT_EQ(NoiseParamOfGuess("r-scalar"), NoiseParam::kScalar);
  EXPECT_EQ(NoiseParamOfGuess("q"), NoiseParam::kFull);
  EXPECT_EQ(NoiseParamOfGuess("q-diag"), NoiseParam::kDiag);
  EXPECT_EQ(NoiseParamOfGuess(""), NoiseParam::kDiag);
  const TunerOptions o = BuildTunerOptions(Of({{"q-param", "fixed"}}), "q-white-accel", "r");
  EXPECT_EQ(o.q_param, NoiseParam::kFixed);
  EXPECT_EQ(o.r_param, NoiseParam::kFull);
}

TEST(TunerSettings, StudyKeysAreTunePrefixedAndUnique) {
  std::set<std::string> names;
  for (const TunerKey& k : TunerKeyTable()) {
    EXPECT_TRUE(names.insert(StudyTunerKey(k)).second) << k.name;
    EXPECT_NE(std::string(k.help), "") << k.name;
    if (k.applies != nullptr) {
      EXPECT_NE(std::string(k.applies_to), "") << k.name;
    }
  }
  EXPECT_TRUE(names.count("tune-solver"));
  EXPECT_TRUE(names.count("tune-lags"));
  EXPECT_TRUE(names.count("q-param"));
}

}  // namespace
}  // namespace estlab::testing
