// ParseGroupItems: the one reader of "GROUP=VALUE,..." (--sensor-rate,
// --sensor-every, --r-param per group).
#include "src/options/group_items.h"

#include <gtest/gtest.h>

#include "src/core/types.h"

namespace estlab {
namespace {

TEST(GroupItems, ReadsTheItemsInOrderTrimmed) {
  const auto items = ParseGroupItems(" gps = 1 , imu=100", "--sensor-rate", "HZ");
  ASSERT_EQ(items.size(), 2u);
  EXPECT_EQ(items[0], (std::pair<std::string, std::string>{"gps", "1"}));
  EXPECT_EQ(items[1], (std::pair<std::string, std::string>{"imu", "100"}));
}

TEST(GroupItems, RefusesAnItemWithoutAGroupAndAGroupTwice) {
  for (const char* bad : {"gps", "=1", " = 1", "gps=1,,imu"}) {
    try {
      ParseGroupItems(bad, "--r-param", "KIND");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--r-param: expected GROUP=KIND, got '"),
                std::string::npos)
          << e.what();
    }
  }
  try {
    ParseGroupItems("gps=1,imu=2,gps=3", "--sensor-every", "K");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "--sensor-every: sensor group 'gps' is given twice");
  }
}

}  // namespace
}  // namespace estlab
