// The one key table and BuildFilterSpec (src/options/filter_settings.h): the
// same settings give the same spec whether they come from the command line
// or are set directly (as a study does), defaults come from the table, and
// every error is a KeyError naming the key the user wrote.
#include "src/options/filter_settings.h"

#include <gtest/gtest.h>

#include <boost/program_options.hpp>
#include <set>
#include <string>
#include <vector>

#include "src/options/filter_flags.h"
#include "src/registry/registry.h"

namespace estlab::testing {
namespace {

namespace po = boost::program_options;

FilterSettings Pendulum() {
  FilterSettings s;
  s.Set("measure", "sin");
  s.Set("q-diag", "1e-4,1e-3");
  s.Set("r-diag", "0.01");
  return s;
}

// The key (and message) of the KeyError that BuildFilterSpec throws.
std::pair<std::string, std::string> ErrorOf(const FilterSettings& s) {
  try {
    (void)BuildFilterSpec(s, FindModel("pendulum"));
  } catch (const KeyError& e) {
    return {e.key(), e.message()};
  }
  return {"", ""};
}

TEST(FilterSettings, CommandLineAndDirectSettingsGiveTheSameSpec) {
  po::options_description desc;
  cli::AddFilterOptions(&desc);
  const std::vector<std::string> args = {"--measure",  "sin",  "--q-diag", "1e-4,1e-3",
                                         "--r-diag",   "0.01", "--filter", "ghkf",
                                         "--gh-order", "5",    "--x0",     "theta=0.3"};
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).run(), vm);
  const FilterSpec from_cli = cli::BuildFilterSpec(vm, FindModel("pendulum"));
  FilterSettings s = Pendulum();
  s.Set("filter", "ghkf");
  s.Set("gh-order", "5");
  s.Add("x0", "theta=0.3");
  const FilterSpec direct = BuildFilterSpec(s, FindModel("pendulum"));
  EXPECT_EQ(from_cli.kind(), FilterKind::kGhkf);
  EXPECT_EQ(direct.kind(), from_cli.kind());
  const auto& sigma = std::get<SigmaPointOptions>(direct.filter);
  EXPECT_EQ(sigma.rule, SigmaRule::kGaussHermite);
  EXPECT_EQ(sigma.gh_order, 5);
  EXPECT_EQ(sigma.gh_order, std::get<SigmaPointOptions>(from_cli.filter).gh_order);
  EXPECT_EQ(direct.x0, from_cli.x0);
  EXPECT_EQ(direct.x0[0], 0.3);
  EXPECT_EQ(direct.q, from_cli.q);
  EXPECT_EQ(direct.r, from_cli.r);
  // Defaults are the table's: alpha 1e-3, redraw, rk4 with one substep.
  EXPECT_EQ(sigma.alpha, 1e-3);
  EXPECT_EQ(sigma.update, SigmaPointOptions::Update::kRedraw);
  EXPECT_EQ(direct.transition.integrator, Integrator::kRk4);
  EXPECT_EQ(direct.transition.substeps, 1);
}

TEST(FilterSettings, IekfDefaultsToThreeIterations) {
  FilterSettings s = Pendulum();
  s.Set("filter", "iekf");
  auto iterations = [&] {
    return std::get<EkfOptions>(BuildFilterSpec(s, FindModel("pendulum")).filter).iterations;
  };
  EXPECT_EQ(iterations(), 3);
  s.Set("iterations", "5");
  EXPECT_EQ(iterations(), 5);
}

TEST(FilterSettings, ErrorsNameTheKey) {
  struct Case {
    const char* key;
    const char* value;
    const char* expect_key;
    const char* expect_message;
  };
  const Case cases[] = {
      {"alpha", "-1", "alpha", "must be > 0 and finite, got -1"},
      {"alpha", "abc", "alpha", "'abc' is not a number"},
      {"iterations", "101", "iterations", "must be in [1, 100], got 101"},
      {"substeps", "0", "substeps", "must be in [1, 100000], got 0"},
      {"sigma-update", "sideways", "sigma-update", "expected propagate or redraw"},
      {"r-diag", "0.01,0.02", "r-diag", "expected 1 values"},
      {"q-diag", "-1,1", "q-diag", "Q is not positive semi-definite"},
      {"filter", "kalman", "filter", "unknown filter 'kalman'"},
  };
  for (const Case& c : cases) {
    FilterSettings s = Pendulum();
    s.Set(c.key, c.value);
    const auto [key, message] = ErrorOf(s);
    EXPECT_EQ(key, c.expect_key) << c.key << " = " << c.value << ": " << message;
    EXPECT_EQ(message.rfind(c.expect_message, 0), 0u)
        << c.key << " = " << c.value << ": " << message;
  }
  // The filter's own check, for the filter chosen: a PF with no particles.
  FilterSettings pf = Pendulum();
  pf.Set("filter", "pf");
  pf.Set("particles", "0");
  EXPECT_EQ(ErrorOf(pf).first, "particles");
  // A Gauss-Hermite rule too large for the state dimension names gh-order.
  FilterSettings gh = Pendulum();
  gh.Set("filter", "ghkf");
  gh.Set("gh-order", "20");
  EXPECT_EQ(ErrorOf(gh).first, "");  // 20^2 = 400 points: fine in 2 dimensions
  // Missing noise: named by its key.
  FilterSettings no_r;
  no_r.Set("measure", "sin");
  no_r.Set("q-diag", "1,1");
  EXPECT_EQ(ErrorOf(no_r).first, "r-diag");
}

// Every key is an option of 'estlab filter'; the tuner ("init-") leaves out
// the options of the kinds it cannot tune (pf) and of the per-step output.
TEST(FilterSettings, TheTableIsTheCommandLine) {
  po::options_description filter_desc, tune_desc;
  cli::AddFilterOptions(&filter_desc, "");
  cli::AddFilterOptions(&tune_desc, "init-");
  const std::set<std::string> not_tune = {"particles", "resample", "ess-threshold", "full-cov"};
  for (const FilterKey& k : FilterKeyTable()) {
    EXPECT_NE(filter_desc.find_nothrow(k.name, false), nullptr) << k.name;
    const std::string name = k.noise ? std::string("init-") + k.name : std::string(k.name);
    EXPECT_EQ(tune_desc.find_nothrow(name, false) != nullptr, !not_tune.count(k.name)) << name;
  }
  EXPECT_EQ(filter_desc.options().size(), FilterKeyTable().size());
  EXPECT_EQ(tune_desc.options().size(), FilterKeyTable().size() - not_tune.size());
}

}  // namespace
}  // namespace estlab::testing
