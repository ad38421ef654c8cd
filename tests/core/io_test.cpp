// CSV reading, JSON writing, chi-square bounds and the deterministic RNG.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>

#include "error_text.h"
#include "src/core/random.h"
#include "src/core/types.h"
#include "src/io/csv_reader.h"
#include "src/io/json.h"
#include "src/io/output_file.h"
#include "src/run/filter_spec.h"

namespace estlab {
namespace {

TEST(CsvReader, ReadsNumbersAndMissingCells) {
  const CsvTable t = ParseCsv("t,z_theta\n0,0.5\n0.1,\n0.2,nan\n# comment\n0.3,-1e-3\n", "d.csv");
  ASSERT_EQ(t.columns.size(), 2u);
  ASSERT_EQ(t.rows.size(), 4u);
  EXPECT_DOUBLE_EQ(t.rows[0][1], 0.5);
  EXPECT_TRUE(std::isnan(t.rows[1][1]));
  EXPECT_TRUE(std::isnan(t.rows[2][1]));
  EXPECT_DOUBLE_EQ(t.rows[3][1], -1e-3);
  EXPECT_EQ(t.line_numbers[3], 6);
  EXPECT_EQ(t.ColumnIndex("z_theta"), 1);
  EXPECT_EQ(t.ColumnIndex("nope"), -1);
}

TEST(CsvReader, ErrorsNameFileLineAndColumn) {
  try {
    ParseCsv("t,z\n0,1\n0.1,abc\n", "d.csv");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("d.csv:3: column 2 ('z')"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParseCsv("t,z\n0,1,2\n", "d.csv"), InputError);
  EXPECT_THROW(ParseCsv("t,z\n0,inf\n", "d.csv"), InputError);
  EXPECT_THROW(ParseCsv("", "d.csv"), InputError);
  EXPECT_THROW(ParseCsv("t,t\n0,1\n", "d.csv"), InputError);
  EXPECT_THROW(ReadCsv("/nonexistent/file.csv"), InputError);
}

// Console tables format numbers, never cut their text (issue 14, item 1: a
// mean of 2.176861944e-05 was printed as 2.17686194).
TEST(CsvReader, AcceptsBomAndAllLineEndings) {
  for (const std::string text : {"\xEF\xBB\xBFt,z\n0,1\n0.1,2\n", "t,z\r\n0,1\r\n0.1,2\r\n",
                                 "t,z\r0,1\r0.1,2", "\xEF\xBB\xBFt,z\r0,1\r\n0.1,2\n"}) {
    const CsvTable t = ParseCsv(text, "d.csv");
    ASSERT_EQ(t.columns, (std::vector<std::string>{"t", "z"})) << text;
    ASSERT_EQ(t.rows.size(), 2u) << text;
    EXPECT_EQ(t.rows[1][1], 2.0) << text;
    EXPECT_EQ(t.line_numbers[1], 3) << text;
  }
}

std::string CsvError(const std::string& text) {
  return testing::ErrorText([&] { ParseCsv(text, "d.csv"); });
}

TEST(CsvReader, RefusesLongLinesAndEscapesControlBytes) {
  const std::string long_line = "t,z\n0,1\n" + std::string(size_t(1) << 21, '1') + "\n";
  EXPECT_EQ(CsvError(long_line), "d.csv:3: line longer than 1048576 bytes");
  EXPECT_EQ(CsvError(std::string("t,z\n0,1\0002\n", 10)),
            "d.csv:2: column 2 ('z'): '1\\x002' is not a number");
  EXPECT_EQ(CsvError("t,z\n0,4.9e-324\n"), "");
  EXPECT_EQ(CsvError("t,z\n0,1e-400\n"),
            "d.csv:2: column 2 ('z'): '1e-400' is too small (underflows to 0)");
}

TEST(CsvReader, RefusesDirectoriesAndEndlessFiles) {
  try {
    ReadCsv("/tmp");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "data file '/tmp' is a directory");
  }
  try {
    ReadCsv("/dev/zero");
    FAIL() << "no error";
  } catch (const InputError& e) {
    // A device is never data (issue 40 item 17: a FIFO blocked forever).
    EXPECT_STREQ(e.what(),
                 "data file '/dev/zero' is not a regular file (a FIFO, socket or device); give a "
                 "file");
  }
  // An endless line in a regular file: refused at the cap.
  const std::string path =
      (std::filesystem::temp_directory_path() / ("estlab_long_" + std::to_string(::getpid())))
          .string();
  std::ofstream(path) << "t,x\n" << std::string(1100000, '1') << "\n";
  try {
    ReadCsv(path);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":2: line longer than 1048576 bytes");
  }
  std::filesystem::remove(path);
}

// Every double written reads back bit for bit (issue 39, done-when 3), and
// the text is printf's "%.17g", byte for byte: random bit patterns over the
// whole range (subnormals, huge, negative zero), a file through
// WriteCsv -> ReadCsv, and the forms only the strtod fallback takes ('+',
// hex) read as strtod reads them.
TEST(CsvReader, EveryDoubleWrittenReadsBackBitForBit) {
  std::mt19937_64 rng(39);
  std::vector<std::vector<double>> rows;
  std::vector<double> specials = {
      0.0,  -0.0, 5e-324,  -2.2250738585072009e-308, 1.7976931348623157e308, 0.1, 1.0 / 3,
      1e16, 1e-5, 123456.0};
  for (size_t i = 0; i < 20000; ++i) {
    std::vector<double> row(4);
    for (double& v : row) {
      do {
        const uint64_t bits = rng();
        std::memcpy(&v, &bits, sizeof v);
      } while (!std::isfinite(v));
    }
    if (i < specials.size()) row[0] = specials[i];
    rows.push_back(row);
  }
  rows[5][2] = std::numeric_limits<double>::quiet_NaN();  // an empty cell
  for (const auto& row : rows) {
    for (double v : row) {
      if (std::isnan(v)) continue;
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", v);
      ASSERT_EQ(FormatDouble(v), buf);
    }
  }
  const std::string path =
      (std::filesystem::temp_directory_path() / ("estlab_rt_" + std::to_string(::getpid())))
          .string();
  {
    std::ofstream out(path, std::ios::binary);
    WriteCsv(out, {"a", "b", "c", "d"}, rows);
  }
  const CsvTable back = ReadCsv(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.rows.size(), rows.size());
  for (size_t i = 0; i < rows.size(); ++i)
    for (size_t j = 0; j < 4; ++j) {
      if (std::isnan(rows[i][j])) {
        EXPECT_TRUE(std::isnan(back.rows[i][j]));
        continue;
      }
      uint64_t a, b;
      std::memcpy(&a, &rows[i][j], 8);
      std::memcpy(&b, &back.rows[i][j], 8);
      ASSERT_EQ(a, b) << "row " << i << " column " << j << ": " << FormatDouble(rows[i][j]);
    }
  // A file whose size reads 0 (a /proc file) is read to its end, not taken
  // for empty: its second line is the first refused.
  try {
    ReadCsv("/proc/self/status");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/proc/self/status:2: column 1", 0), 0u) << e.what();
  }
  const CsvTable forms = ParseCsv("a,b,c\n+1.5,0x1p-3,4.9e-324\n", "f.csv");
  EXPECT_EQ(forms.rows[0][0], 1.5);
  EXPECT_EQ(forms.rows[0][1], 0.125);
  EXPECT_EQ(forms.rows[0][2], std::strtod("4.9e-324", nullptr));
}

TEST(CellForDisplay, FormatsNumbersAndNeverCutsThem) {
  EXPECT_EQ(CellForDisplay("2.176861944e-05"), "2.17686e-05");
  EXPECT_EQ(CellForDisplay("0.12345678912345"), "0.123457");
  EXPECT_EQ(CellForDisplay("151527.12345678"), "151527");
  EXPECT_EQ(CellForDisplay("-inf"), "-inf");
  EXPECT_EQ(CellForDisplay(""), "-");
  EXPECT_EQ(CellForDisplay("ok"), "ok");
}

TEST(Json, WritesNestedValuesAndNullForNonFinite) {
  JsonWriter j;
  j.BeginObject()
      .Key("a")
      .Value(1.5)
      .Key("b")
      .BeginArray()
      .Value(1L)
      .Value(std::nan(""))
      .EndArray();
  j.Key("s").Value("q\"x").EndObject();
  EXPECT_EQ(j.str(), "{\"a\": 1.5, \"b\": [1, null], \"s\": \"q\\\"x\"}");
}

// K-step average of a d-dimensional chi-square statistic: K * mean ~ chi2(K d).
// Reference values from the chi-square quantiles chi2_{0.025}(100) = 74.2219
// and chi2_{0.975}(100) = 129.5612 (standard tables).
TEST(ChiSquare, BoundsMatchTables) {
  double b[2];
  ChiSquareBounds95(50, 2, b);
  EXPECT_NEAR(b[0], 74.2219 / 50, 1e-4);
  EXPECT_NEAR(b[1], 129.5612 / 50, 1e-4);
  ChiSquareBounds95(1, 1, b);
  EXPECT_NEAR(b[0], 0.000982069, 1e-8);
  EXPECT_NEAR(b[1], 5.023886, 1e-6);
}

TEST(Random, DeterministicAndStandardNormal) {
  Rng a(42), b(42), c(43);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(a.Next(), b.Next());
  EXPECT_NE(Rng(42).Next(), c.Next());
  Rng r(7);
  const int n = 200000;
  double sum = 0, sum2 = 0, sum4 = 0;
  for (int i = 0; i < n; ++i) {
    const double z = r.Normal();
    sum += z;
    sum2 += z * z;
    sum4 += z * z * z * z;
  }
  // Standard errors: mean 1/sqrt(n), variance sqrt(2/n), 4th moment sqrt(96/n).
  EXPECT_NEAR(sum / n, 0.0, 4.0 / std::sqrt(n));
  EXPECT_NEAR(sum2 / n, 1.0, 4.0 * std::sqrt(2.0 / n));
  EXPECT_NEAR(sum4 / n, 3.0, 4.0 * std::sqrt(96.0 / n));
  // Derived seeds differ across their parts and are order-sensitive.
  std::set<uint64_t> seeds;
  for (uint64_t s = 0; s < 3; ++s)
    for (uint64_t i = 0; i < 100; ++i) seeds.insert(DeriveSeed({1, s, i}));
  EXPECT_EQ(seeds.size(), 300u);
  EXPECT_NE(DeriveSeed({1, 2, 3}), DeriveSeed({1, 3, 2}));
}

TEST(WrapAngle, MapsIntoHalfOpenInterval) {
  const double pi = 3.14159265358979323846;
  EXPECT_DOUBLE_EQ(WrapAngle(pi), pi);
  EXPECT_DOUBLE_EQ(WrapAngle(-pi), pi);
  EXPECT_NEAR(WrapAngle(3 * pi / 2), -pi / 2, 1e-15);
  EXPECT_NEAR(WrapAngle(-7.0), -7.0 + 2 * pi, 1e-15);
}

}  // namespace
}  // namespace estlab
