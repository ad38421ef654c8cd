// ParseNumber at the edges of the double range: subnormals are numbers,
// underflow and overflow are refused with their own words.
#include <gtest/gtest.h>

#include <string>

#include "error_text.h"
#include "src/core/parse.h"
#include "src/core/types.h"

namespace estlab {
namespace {

std::string ErrorOf(const std::string& text) {
  return testing::ErrorText([&] { ParseNumber(text, "--x"); });
}

TEST(ParseNumber, AcceptsSubnormals) {
  EXPECT_EQ(ParseNumber("4.9e-324", "--x"), 4.9e-324);
  EXPECT_EQ(ParseNumber("2.2e-310", "--x"), 2.2e-310);
  EXPECT_EQ(ParseNumber("-2.2e-310", "--x"), -2.2e-310);
  EXPECT_GT(ParseNumber("4.9e-324", "--x"), 0.0);
}

TEST(ParseNumber, RefusesUnderflowAndNonFinite) {
  EXPECT_EQ(ErrorOf("1e-400"), "--x: '1e-400' is too small (underflows to 0)");
  EXPECT_EQ(ErrorOf("-1e-400"), "--x: '-1e-400' is too small (underflows to 0)");
  EXPECT_EQ(ErrorOf("1e400"), "--x: '1e400' is not a finite number");
  EXPECT_EQ(ErrorOf("-1e400"), "--x: '-1e400' is not a finite number");
  EXPECT_EQ(ErrorOf("inf"), "--x: 'inf' is not a finite number");
  EXPECT_EQ(ErrorOf("nan"), "--x: 'nan' is not a finite number");
  EXPECT_EQ(ParseNumber("0", "--x"), 0.0);
  EXPECT_EQ(ParseNumber("0e-400", "--x"), 0.0);
}

TEST(ParseNumber, EscapesControlBytesInMessages) {
  EXPECT_EQ(ErrorOf(std::string("1\0002", 3)), "--x: '1\\x002' is not a number");
  EXPECT_EQ(ErrorOf("1\x01"
                    "2"),
            "--x: '1\\x012' is not a number");
}

}  // namespace
}  // namespace estlab
