// The seeded input signals of src/sim/input_signal.h against their
// definitions: a multisine's mean, mean square and spectrum over a common
// period, the maximum-length property of every PRBS order (all 2^n - 1
// nonzero windows once, 2^(n-1) ones), the steps by hand, and errors that
// name the key.
#include "src/sim/input_signal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "src/core/types.h"

namespace estlab {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Each (text, message): parsing text throws an InputError containing message.
void ExpectErrors(const std::vector<std::pair<std::string, std::string>>& cases,
                  const std::string& base_dir) {
  for (const auto& [text, message] : cases) {
    try {
      ParseInputSignal(text, "input", base_dir);
      ADD_FAILURE() << text << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << text << ": " << e.what();
    }
  }
}

TEST(InputSignal, MultisineHasItsMeanItsRmsAndOnlyItsBand) {
  // Five sines at 0.01 .. 0.05 Hz: 100 s is a common period; 2000 samples
  // resolve it exactly (discrete orthogonality of the cosines).
  const InputSignal s =
      ParseInputSignal("multisine(rms=0.5, mean=2.5, band=0.01:0.05, sines=5, seed=3)", "input");
  const int n = 2000;
  const double dt = 100.0 / n;
  std::vector<double> u(n);
  double mean = 0.0, square = 0.0;
  for (int k = 0; k < n; ++k) u[k] = s.At(k * dt), mean += u[k] / n;
  for (int k = 0; k < n; ++k) square += (u[k] - 2.5) * (u[k] - 2.5) / n;
  EXPECT_NEAR(mean, 2.5, 1e-12);
  EXPECT_NEAR(square, 0.25, 1e-12);
  // The Fourier amplitude at f: 2 |sum_k (u_k - mean) e^{-i 2 pi f t_k}| / n.
  auto amplitude = [&](double f) {
    double re = 0.0, im = 0.0;
    for (int k = 0; k < n; ++k) {
      re += (u[k] - 2.5) * std::cos(2 * kPi * f * k * dt);
      im -= (u[k] - 2.5) * std::sin(2 * kPi * f * k * dt);
    }
    return 2 * std::hypot(re, im) / n;
  };
  const double each = 0.5 * std::sqrt(2.0 / 5);  // rms sqrt(2/N) per sine
  for (double f : {0.01, 0.02, 0.03, 0.04, 0.05}) EXPECT_NEAR(amplitude(f), each, 1e-10) << f;
  for (double f : {0.06, 0.07, 0.1, 0.5}) EXPECT_NEAR(amplitude(f), 0.0, 1e-10) << f;
  // The seed picks the phases: another seed, another signal with the same spectrum.
  const InputSignal other =
      ParseInputSignal("multisine(rms=0.5, mean=2.5, band=0.01:0.05, sines=5, seed=4)", "input");
  EXPECT_GT(std::abs(other.At(10.0) - s.At(10.0)), 1e-3);
  EXPECT_NEAR(ParseInputSignal("multisine(rms=0.5, band=0.01:0.05, sines=5, seed=3)", "i").At(7.0),
              s.At(7.0) - 2.5, 1e-14);
}

TEST(InputSignal, PrbsIsAMaximumLengthSequenceForEveryOrder) {
  for (int order = 2; order <= 16; ++order) {
    const std::vector<bool> bits = MaximumLengthSequence(order, 1);
    const size_t length = (size_t(1) << order) - 1;
    ASSERT_EQ(bits.size(), length);
    size_t ones = 0;
    std::set<unsigned> windows;  // every cyclic window of `order` bits
    for (size_t j = 0; j < length; ++j) {
      ones += bits[j];
      unsigned w = 0;
      for (int i = 0; i < order; ++i) w = (w << 1) | unsigned(bits[(j + i) % length]);
      windows.insert(w);
    }
    EXPECT_EQ(ones, size_t(1) << (order - 1)) << order;
    EXPECT_EQ(windows.size(), length) << order;  // all nonzero patterns, once each
    EXPECT_EQ(windows.count(0u), 0u) << order;
  }
  // Held `period` seconds per bit around `mean`, repeating after 2^n - 1 bits.
  const InputSignal s = ParseInputSignal("prbs(amplitude=0.5, mean=1, period=2, order=4, seed=9)",
                                         "input");
  const std::vector<bool> bits = MaximumLengthSequence(4, 9);
  for (int j = 0; j < 40; ++j) {
    const double expected = bits[size_t(j) % 15] ? 1.5 : 0.5;
    EXPECT_EQ(s.At(2.0 * j), expected) << j;
    EXPECT_EQ(s.At(2.0 * j + 1.999), expected) << j;
  }
}

TEST(InputSignal, StepsAndConstantsByHand) {
  const InputSignal s = ParseInputSignal(" steps(2.5, 200:3, 500:2) ", "input");
  EXPECT_EQ(s.At(0.0), 2.5);
  EXPECT_EQ(s.At(199.999), 2.5);
  EXPECT_EQ(s.At(200.0), 3.0);
  EXPECT_EQ(s.At(499.0), 3.0);
  EXPECT_EQ(s.At(500.0), 2.0);
  EXPECT_EQ(s.At(1e6), 2.0);
  // k dt rounding: 3 x 0.3 = 0.8999999999999999 reaches a step at 0.9.
  EXPECT_EQ(ParseInputSignal("steps(0, 0.9:1)", "input").At(3 * 0.3), 1.0);
  EXPECT_TRUE(std::isnan(s.At(std::nan(""))));
  const InputSignal c = ParseInputSignal("0.25", "input");
  EXPECT_EQ(c.kind, InputSignal::kConstant);
  EXPECT_EQ(c.At(3.0), 0.25);
}

// file(...): each row's value held until the next row's time; a relative
// path is relative to the base folder; Covers refuses times outside the rows.
TEST(InputSignal, RecordedFileIsHeldRowToRow) {
  const std::string dir = ::testing::TempDir() + "/estlab_input_signal";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/pump.csv") << "t,volts,u\n0,1,9\n1.5,2,9\n4,3,9\n";
  const InputSignal s = ParseInputSignal("file(pump.csv, volts)", "input", dir);
  EXPECT_EQ(s.kind, InputSignal::kRecorded);
  const std::vector<std::pair<double, double>> at = {
      {0.0, 1.0}, {1.4999, 1.0}, {1.5, 2.0}, {3.9, 2.0}, {4.0, 3.0}};
  for (const auto& [t, u] : at) EXPECT_EQ(s.At(t), u) << t;
  EXPECT_EQ(s.Covers(0.0, 4.0), "");
  EXPECT_NE(s.Covers(0.0, 4.5).find("covers t = 0 .. 4, not 0 .. 4.5"), std::string::npos)
      << s.Covers(0.0, 4.5);
  EXPECT_EQ(ParseInputSignal("file(" + dir + "/pump.csv)", "input").At(2.0), 9.0);  // column u
  std::ofstream(dir + "/back.csv") << "t,u\n0,1\n2,2\n1,3\n";
  std::ofstream(dir + "/hole.csv") << "t,u\n0,1\n1,\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"file(back.csv)", "back.csv:4: t = 1 does not increase"},
      {"file(hole.csv)", "hole.csv:3: missing u"},
      {"file(pump.csv, amps)", "pump.csv has no 'amps' column"},
      {"file()", "expected file(path) or file(path, column)"}};
  ExpectErrors(cases, dir);
}

TEST(InputSignal, ErrorsNameTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"prbs(period=2)", "input prbs(...): 'amplitude=' is required"},
      {"prbs(amplitude=1, order=30)", "input prbs(...) order: expected a whole number in 2..20"},
      {"prbs(amplitude=1, period=0)", "input prbs(...) period: must be > 0 s"},
      {"multisine(rms=1, band=0.05:0.01)", "input multisine(...) band: expected 0 < f1 < f2"},
      {"multisine(rms=1)", "input multisine(...): 'band=f1:f2' (Hz) is required"},
      {"multisine(rms=1, band=1:1, sines=2)", "band: expected 0 < f1 < f2, got '1:1'"},
      {"multisine(rms=1, band=0.1:0.2, colour=red)", "unknown key 'colour'"},
      {"multisine(rms=1, rms=2, band=0.1:0.2)", "'rms' given twice"},
      {"steps(1, 5:2, 3:1)", "input steps(...): step times must increase, got 3 after 5"},
      {"steps(1, 5)", "expected time:value, got '5'"},
      {"sine(1)", "input: unknown signal 'sine'"},
      {"2.5x", "input"}};
  ExpectErrors(cases, "");
}

}  // namespace
}  // namespace estlab
