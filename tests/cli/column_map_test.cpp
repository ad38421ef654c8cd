// --column maps (src/options/column_map.h): the parser's good and bad forms,
// and the values LoadFilterData reads through them, against hand values.
#include "src/options/column_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "cli_test_util.h"
#include "src/core/types.h"
#include "src/options/filter_flags.h"
#include "src/registry/registry.h"

namespace estlab {
namespace {

std::string ParseError(const std::string& text) {
  try {
    ParseColumnMap(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ColumnMap, PlainRenameKeepsTheValue) {
  const ColumnMap c = ParseColumnMap("z_theta=angle_rad");
  EXPECT_EQ(c.ours, "z_theta");
  EXPECT_EQ(c.theirs, "angle_rad");
  EXPECT_EQ(c.Apply(0.25), 0.25);
  // A name with a '-' that is not followed by a constant stays a name.
  EXPECT_EQ(ParseColumnMap("x=x-pos").theirs, "x-pos");
}

TEST(ColumnMap, AffineForms) {
  const double pi = std::numbers::pi;
  const ColumnMap shift = ParseColumnMap("theta=angle-pi");
  EXPECT_EQ(shift.theirs, "angle");
  EXPECT_DOUBLE_EQ(shift.Apply(4.0), 4.0 - pi);
  const ColumnMap deg = ParseColumnMap("theta=0.0174533*angle_deg");
  EXPECT_EQ(deg.theirs, "angle_deg");
  EXPECT_DOUBLE_EQ(deg.Apply(90.0), 1.570797);  // 90 * 0.0174533
  const ColumnMap both = ParseColumnMap(" z_theta = 2 * x + 1 ");
  EXPECT_EQ(both.ours, "z_theta");
  EXPECT_EQ(both.theirs, "x");
  EXPECT_DOUBLE_EQ(both.Apply(3.0), 7.0);
  const ColumnMap exp = ParseColumnMap("t=1e-3*t_ms+1e-3");  // an exponent is no shift
  EXPECT_EQ(exp.theirs, "t_ms");
  EXPECT_DOUBLE_EQ(exp.Apply(2000.0), 2.001);
  EXPECT_DOUBLE_EQ(ParseColumnMap("theta=-1*a+pi").Apply(1.0), pi - 1.0);
  EXPECT_DOUBLE_EQ(ParseColumnMap("theta=pi*a").Apply(2.0), 2 * pi);
}

TEST(ColumnMap, BadFormsNameTheText) {
  for (const char* bad :
       {"theta", "=angle", "theta=", "theta=2*", "theta=x*angle", "theta=2*3", "theta=angle-",
        "theta=-angle", "the ta=angle", "theta=2**angle", "theta=inf*angle", "theta=a=b"}) {
    EXPECT_EQ(ParseError(bad),
              std::string("--column: expected ours=[a*]theirs[+-b], got '") + bad + "'")
        << bad;
  }
  EXPECT_EQ(ParseColumnMap("theta=angle+x").theirs, "angle+x");
}

TEST(ColumnMap, OursMappedTwiceIsAnError) {
  try {
    ParseColumnMaps({"z_theta=a", "z_theta=b"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--column: 'z_theta' is mapped twice ('z_theta=b')");
  }
}

// LoadFilterData through affine maps: time in ms, the angle from upright in
// degrees, truth columns mapped too; hand values per row.
TEST(ColumnMap, LoadFilterDataAppliesTheMaps) {
  testing::TempDir dir;
  const std::string path = dir.File("lab.csv");
  std::ofstream(path) << "t_ms,angle_deg,rate\n0,180,1\n10,90,\n20,270,-2\n";
  const ModelEntry& model = FindModel("pendulum");
  const std::vector<ColumnMap> maps =
      ParseColumnMaps({"t=1e-3*t_ms", "z_theta=0.0174533*angle_deg-pi",
                       "theta=0.0174533*angle_deg-pi", "omega=rate"});
  const FilterData d = cli::LoadFilterData(path, model, model.FindMeasurement("angle"), maps);
  ASSERT_EQ(d.t.size(), 3u);
  EXPECT_DOUBLE_EQ(d.t[1], 0.01);
  EXPECT_DOUBLE_EQ(d.t[2], 0.02);
  const double pi = std::numbers::pi;
  ASSERT_EQ(d.z.size(), 3u);
  EXPECT_DOUBLE_EQ(d.z[0], 180 * 0.0174533 - pi);
  EXPECT_DOUBLE_EQ(d.z[1], 90 * 0.0174533 - pi);
  EXPECT_DOUBLE_EQ(d.z[2], 270 * 0.0174533 - pi);
  ASSERT_TRUE(d.has_truth);
  EXPECT_DOUBLE_EQ(d.truth[0], 180 * 0.0174533 - pi);  // theta, omega per row
  EXPECT_EQ(d.truth[1], 1.0);
  EXPECT_TRUE(std::isnan(d.truth[3]));  // the empty rate cell stays missing
  EXPECT_EQ(d.truth[5], -2.0);
  // read_truth = false: the state-named columns are not truth.
  EXPECT_FALSE(
      cli::LoadFilterData(path, model, model.FindMeasurement("angle"), maps, false).has_truth);
}

}  // namespace
}  // namespace estlab
