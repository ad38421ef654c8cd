// The recorded-data study of docs/real-data.md (studies/multiarm_hand_vs_auto.ini)
// on a subset, for `make test`: the same file, model file and settings, with
// the tuned Q/R fitted on two training pieces and scored on one validation
// piece. Label "plugin": it compiles the model file and its tuner (minutes).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_test_util.h"

namespace estlab::testing {
namespace {

namespace fs = std::filesystem;

std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "the study no longer has '" << from << "'";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The cells of the runs.csv column `name`, one per row.
std::vector<std::string> Column(const std::string& csv, const std::string& name) {
  std::vector<std::string> out;
  const auto lines = SplitLines(csv);
  std::vector<std::string> header;
  for (size_t i = 0; i < lines.size(); ++i) {
    std::vector<std::string> cells;
    std::stringstream s(lines[i]);
    std::string cell;
    while (std::getline(s, cell, ',')) cells.push_back(cell);
    if (lines[i].back() == ',') cells.push_back("");
    if (i == 0) {
      header = cells;
      continue;
    }
    for (size_t j = 0; j < header.size() && j < cells.size(); ++j)
      if (header[j] == name) out.push_back(cells[j]);
  }
  return out;
}

TEST(RecordedStudyFile, MultiarmStudyOnASubsetReportsMetricsWithoutTruth) {
  TempDir dir;
  const std::string src = ESTLAB_SOURCE_DIR;
  const std::string data = src + "/examples/data/multiarm/double/";
  std::string ini = ReadFile(src + "/studies/multiarm_hand_vs_auto.ini");
  ini = Replaced(ini, "model = ../examples/", "model = " + src + "/examples/");
  ini = Replaced(ini, "data = ../examples/data/multiarm/double/validate_*.csv",
                 "data = " + data + "validate_1.csv");
  ini = Replaced(ini, "tune-data = ../examples/data/multiarm/double/train_*.csv",
                 "tune-data = " + data + "train_01.csv, " + data + "train_02.csv");
  std::ofstream(dir.File("subset.ini")) << ini;
  const std::string cache = (fs::path(ESTLAB_BINARY).parent_path() / "test-model-cache").string();
  const RunResult r = RunEstlab(
      "--model-cache '" + cache + "' study subset.ini --out out --jobs 2 --quiet", dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;

  const std::string report = ReadFile(dir.File("out/report.md"));
  EXPECT_NE(report.find("**No truth**"), std::string::npos) << report;
  EXPECT_NE(report.find("RMSE, MAE and NEES are **not available**"), std::string::npos);
  EXPECT_NE(report.find("**No oracle**"), std::string::npos);
  EXPECT_NE(report.find("Metrics available without truth"), std::string::npos);

  const std::string runs = ReadFile(dir.File("out/runs.csv"));
  const auto noise = Column(runs, "noise"), nll = Column(runs, "nll_per_step");
  const auto status = Column(runs, "status"), rmse = Column(runs, "rmse_phi1");
  const auto pred = Column(runs, "pred_rmse_phi1"), nis = Column(runs, "mean_nis");
  ASSERT_EQ(nll.size(), 4u) << runs;  // 1 piece x {ekf, ukf} x {hand, tuned}
  ASSERT_EQ(noise.size(), 4u);
  double hand = 0.0, tuned = 0.0;
  for (size_t i = 0; i < nll.size(); ++i) {
    EXPECT_EQ(status[i], "ok");
    EXPECT_EQ(rmse[i], "") << "an RMSE without truth";
    EXPECT_TRUE(std::isfinite(std::stod(nll[i])));
    EXPECT_TRUE(std::isfinite(std::stod(nis[i])));
    // One 1 ms step ahead: far below a milliradian, above zero.
    EXPECT_TRUE(std::stod(pred[i]) > 0 && std::stod(pred[i]) < 1e-3) << pred[i];
    (noise[i] == "tuned" ? tuned : hand) += std::stod(nll[i]) / 2;
  }
  // Fitted on other pieces of the same swing, the tuned Q/R predict the
  // validation piece better than the hand guess (docs/real-data.md: 6 nats
  // per step on the full study).
  EXPECT_LT(tuned, hand - 1.0) << runs;
}

}  // namespace
}  // namespace estlab::testing
