// The ini pieces of the study parser (studies/config/study_config_parts.h): sections
// and entries with their lines, comments, errors naming the line, and the
// '|' alternatives of scenario keys with their labels and product order.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "studies/config/study_config_parts.h"

namespace estlab::testing {
namespace {

using namespace estlab::study_config;

std::string ScanError(const std::string& text) {
  try {
    (void)Scan(text, ConfigErrors("s.ini"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(StudyConfigIni, ScanKeepsSectionsEntriesAndLines) {
  const std::string text =
      "# a study\n"
      "[study]\n"
      "name = x   # trailing comment\n"
      "\n"
      "[scenario.pend]\n"
      "dt = 0.01\n"
      "steps=25\n";
  const std::vector<Section> s = Scan(text, ConfigErrors("s.ini"));
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].full, "study");
  EXPECT_EQ(s[0].line, 2);
  ASSERT_EQ(s[0].entries.size(), 1u);
  EXPECT_EQ(s[0].entries[0].key, "name");
  EXPECT_EQ(s[0].entries[0].value, "x");
  EXPECT_EQ(s[0].entries[0].line, 3);
  EXPECT_EQ(s[1].kind, "scenario");
  EXPECT_EQ(s[1].name, "pend");
  ASSERT_NE(s[1].Find("steps"), nullptr);
  EXPECT_EQ(s[1].Find("steps")->value, "25");
  EXPECT_EQ(s[1].Find("steps")->line, 7);
}

TEST(StudyConfigIni, ScanErrorsNameTheLine) {
  EXPECT_EQ(ScanError("[study]\nname\n").rfind("s.ini:2: expected 'key = value'", 0), 0u);
  EXPECT_EQ(ScanError("x = 1\n").rfind("s.ini:1: key 'x' before the first [section]", 0), 0u);
  EXPECT_EQ(ScanError("[study]\n[study]\n").rfind("s.ini:2: section [study] given twice", 0), 0u);
  EXPECT_EQ(ScanError("[filter.a b]\n").rfind("s.ini:1: unknown section [filter.a b]", 0), 0u);
}

TEST(StudyConfigIni, AlternativesAndTheirProduct) {
  const ConfigErrors err("s.ini");
  const std::vector<Alternative> a =
      ParseAlternatives({"r", "small: 0.01 | large: 1", 4}, err, "[scenario.p] r");
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].label, "small");
  EXPECT_EQ(a[0].value, "0.01");
  EXPECT_EQ(a[1].label, "large");
  // Unlabelled alternatives are their own label when they can be one, else
  // the key and their position.
  const std::vector<Alternative> b = ParseAlternatives({"q", "1e-4|1e-2", 5}, err, "q");
  EXPECT_EQ(b[0].label, "1e-4");
  const std::vector<Alternative> c = ParseAlternatives({"q", "1,2|3,4", 5}, err, "q");
  EXPECT_EQ(c[0].label, "q1");
  EXPECT_EQ(c[1].label, "q2");
  EXPECT_EQ(c[1].value, "3,4");
  Section sec;
  sec.full = "scenario.p";
  sec.entries = {{"q", "1e-4|1e-2", 5}, {"r", "a: 0.1 | b: 1", 6}};
  const auto combos = ExpandScenario(sec, err);
  ASSERT_EQ(combos.size(), 4u);  // 2 x 2, the last key fastest
  EXPECT_EQ(combos[0].first.Find("q")->value, "1e-4");
  EXPECT_EQ(combos[0].first.Find("r")->value, "0.1");
  EXPECT_EQ(combos[1].first.Find("r")->value, "1");
  EXPECT_EQ(combos[2].first.Find("q")->value, "1e-2");
  EXPECT_EQ(combos[3].second.size(), 2u);
  EXPECT_EQ(combos[3].second[1].second, "b");
}

}  // namespace
}  // namespace estlab::testing
