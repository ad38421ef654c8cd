// The particle filters' degeneracy check (src/run/degeneracy.h), by hand.
#include "src/run/degeneracy.h"

#include <gtest/gtest.h>

namespace estlab {
namespace {

TEST(Degeneracy, ThresholdIsTwoParticlesOrOnePercent) {
  EXPECT_EQ(DegeneracyMonitor::Threshold(100), 2.0);
  EXPECT_EQ(DegeneracyMonitor::Threshold(200), 2.0);
  EXPECT_EQ(DegeneracyMonitor::Threshold(1000), 10.0);
}

TEST(Degeneracy, TenCollapsedUpdatesInARowAreDegenerate) {
  DegeneracyMonitor m;
  // Nine collapsed updates, a healthy one, then ten collapsed: degenerate at
  // the tenth of those (step 19), not before.
  for (int k = 0; k < 9; ++k) m.Observe(1.0, 1000, k);
  EXPECT_FALSE(m.degenerate());
  m.Observe(500.0, 1000, 9);
  for (int k = 10; k < 19; ++k) m.Observe(9.99, 1000, k);
  EXPECT_FALSE(m.degenerate());
  m.Observe(3.0, 1000, 19);
  EXPECT_TRUE(m.degenerate());
  EXPECT_EQ(m.onset_step(), 19u);
  m.Observe(1.5, 1000, 20);  // the onset stays the first one
  EXPECT_EQ(m.onset_step(), 19u);
  EXPECT_EQ(m.collapsed_updates(), 20);
  EXPECT_DOUBLE_EQ(m.min_ess(), 1.0);
  EXPECT_DOUBLE_EQ(m.mean_ess(), (9 * 1.0 + 500.0 + 9 * 9.99 + 3.0 + 1.5) / 21.0);
  EXPECT_EQ(m.particles(), 1000);
}

TEST(Degeneracy, AHealthyFilterIsNot) {
  DegeneracyMonitor m;
  EXPECT_FALSE(m.observed());
  for (int k = 0; k < 1000; ++k) m.Observe(k % 9 == 0 ? 1.0 : 300.0, 1000, k);  // brief dips
  EXPECT_TRUE(m.observed());
  EXPECT_FALSE(m.degenerate());
  EXPECT_EQ(m.collapsed_updates(), 112);
}

}  // namespace
}  // namespace estlab
