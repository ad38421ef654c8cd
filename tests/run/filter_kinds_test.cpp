// The registration of the filter kinds (src/run/filter_kinds.h): every
// registered kind round-trips through its name and its options, runs through
// the registry under its own name, and is tunable exactly when registered so.
#include "src/run/filter_kinds.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <variant>

#include "adaptive/tuner.h"
#include "src/core/types.h"
#include "src/registry/registry.h"
#include "src/run/filter_spec.h"

namespace estlab {
namespace {

TEST(FilterKinds, NamesAndOptionsRoundTrip) {
  std::set<std::string> names;
  for (const FilterKindInfo& info : FilterKinds()) {
    EXPECT_TRUE(names.insert(info.name).second) << info.name << " registered twice";
    EXPECT_EQ(ParseFilterKind(info.name), info.kind);
    EXPECT_STREQ(FilterKindName(info.kind), info.name);
    EXPECT_EQ(KindOf(DefaultFilterOptions(info.kind)), info.kind) << info.name;
    EXPECT_EQ(&InfoOf(info.kind), &info);
  }
  EXPECT_EQ(names.size(), 6u);
  EXPECT_EQ(ParseFilterKind("iekf"), FilterKind::kEkf);
  try {
    ParseFilterKind("enkf");
    ADD_FAILURE() << "enkf parsed";
  } catch (const InputError& e) {
    const std::string what = e.what();
    for (const std::string& name : names) EXPECT_NE(what.find(name), std::string::npos) << what;
  }
}

FilterSpec PendulumSpec(const ModelEntry& model, FilterKind kind) {
  FilterSpec spec;
  spec.params = model.ResolveParams({});
  spec.measurement = "sin";
  spec.filter = DefaultFilterOptions(kind);
  spec.transition.integrator = Integrator::kRk4;
  spec.x0 = {0.3, 0.0};
  spec.p0 = {0.01, 0.0, 0.0, 0.01};
  spec.q = {1e-6, 0.0, 0.0, 1e-4};
  spec.r = {0.01};
  return spec;
}

FilterData SmallData() {
  FilterData d;
  d.path = "small";
  d.m = 1;
  for (int k = 0; k < 20; ++k) {
    d.t.push_back(0.01 * k);
    d.lines.push_back(k + 2);
    d.z.push_back(0.29);
  }
  return d;
}

// MakeFilter visits the options: each kind runs as the filter of its name.
TEST(FilterKinds, EveryKindRunsUnderItsName) {
  const ModelEntry& model = FindModel("pendulum");
  const FilterData data = SmallData();
  for (const FilterKindInfo& info : FilterKinds()) {
    const FilterRunOutput out = model.run_filter(PendulumSpec(model, info.kind), data);
    EXPECT_TRUE(out.summary.ok) << info.name << ": " << out.summary.message;
    EXPECT_EQ(out.summary.filter, info.name);
    EXPECT_EQ(out.summary.updates, 20) << info.name;
  }
}

TEST(FilterKinds, TunableExactlyAsRegistered) {
  const ModelEntry& model = FindModel("pendulum");
  TunerOptions options;
  for (const FilterKindInfo& info : FilterKinds()) {
    std::string error;
    const bool tunable = IsTunable(PendulumSpec(model, info.kind), options, 2, &error);
    EXPECT_EQ(tunable, info.tunable) << info.name << ": " << error;
    if (!info.tunable) {
      EXPECT_NE(error.find(info.name), std::string::npos) << error;
    }
  }
}

// IsValidFilterOptions asks the chosen kind's IsValidFor(n): a KF operating
// point of the wrong length, a UKF with n + kappa <= 0.
TEST(FilterKinds, ValidationNeedsTheStateDimension) {
  FilterSpec spec;
  spec.filter = KfOptions{.operating_point = {0.0, 0.0, 0.0}, .operating_input = {}};
  std::string error;
  EXPECT_FALSE(IsValidFilterOptions(spec, 2, &error));
  EXPECT_EQ(error.rfind("linearize-at:", 0), 0u) << error;
  EXPECT_TRUE(IsValidFilterOptions(spec, 3, &error)) << error;
  spec.filter = SigmaPointOptions{.rule = SigmaRule::kUnscented, .kappa = -2.0};
  EXPECT_FALSE(IsValidFilterOptions(spec, 2, &error));
  EXPECT_EQ(error.rfind("kappa:", 0), 0u) << error;
  spec.adapt.rule = "sage-husa";
  spec.filter = EkfOptions{};
  EXPECT_FALSE(IsValidFilterOptions(spec, 2, &error));
  EXPECT_EQ(error.rfind("adapt:", 0), 0u) << error;
}

}  // namespace
}  // namespace estlab
