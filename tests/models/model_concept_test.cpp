// The model contract (models/model.h) holds for every built-in model and
// measurement, and fails for a model missing a member.
#include "models/model.h"

#include <gtest/gtest.h>

#include <string>

#include "models/cart_pole.h"
#include "models/dipc.h"
#include "models/double_pendulum.h"
#include "models/pendulum.h"
#include "models/van_der_pol.h"

namespace estlab::testing {
namespace {

static_assert(DynamicModel<models::Pendulum> && kAllMeasurementsOf<models::Pendulum>);
static_assert(DynamicModel<models::DoublePendulum> && kAllMeasurementsOf<models::DoublePendulum>);
static_assert(DynamicModel<models::CartPole> && kAllMeasurementsOf<models::CartPole>);
static_assert(DynamicModel<models::Dipc> && kAllMeasurementsOf<models::Dipc>);
static_assert(DynamicModel<models::VanDerPol> && kAllMeasurementsOf<models::VanDerPol>);

// The pendulum without its state units: not a model.
struct NoUnits : models::Pendulum {
  static constexpr std::array<const char*, 1> kStateUnits = {"rad"};  // wrong length
};
static_assert(!DynamicModel<NoUnits>);
// A measurement of the wrong output count.
struct BadMeas : models::Pendulum::Angle {
  static constexpr std::array<bool, 2> kAngleOutputs = {true, false};
};
static_assert(!MeasurementOf<BadMeas, models::Pendulum>);
static_assert(MeasurementOf<models::Pendulum::Sin, models::Pendulum>);

// The contract checks are the static_asserts above: this file does not
// compile when one fails. At run time: the units the figures read.
TEST(ModelConcept, StateUnitsAreTheModelsOwn) {
  EXPECT_EQ(models::Pendulum::kStateUnits[0], std::string("rad"));
  EXPECT_EQ(models::CartPole::kStateUnits[0], std::string("m"));
  EXPECT_EQ(models::VanDerPol::kStateUnits[0], std::string(""));
}

}  // namespace
}  // namespace estlab::testing
