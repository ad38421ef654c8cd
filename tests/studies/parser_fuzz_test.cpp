// Issue 15, the fuzz target: a seeded random mutator over the three text
// parsers users feed by hand, the CSV reader, the study-config parser and
// the model-file parser. Every mutant must either parse or be refused with
// an InputError (estlab's "estlab: error: ...", exit 2); anything else (another
// exception, a crash, a hang, a leak: the sanitizer build runs this as a unit
// test) is a defect. Deterministic: fixed seeds, a fixed number of mutants,
// and the count printed.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "../cli/cli_test_util.h"
#include "src/core/random.h"
#include "src/core/types.h"
#include "src/io/csv_reader.h"
#include "src/modelfile/model_file.h"
#include "studies/config/study_config.h"
#include "study_test_util.h"

namespace estlab::testing {
namespace {

// Tokens worth inserting: the grammar's own punctuation and keywords, and
// the byte values that broke parsers before (NUL, CR, BOM, huge numbers).
const std::vector<std::string> kDictionary = {"=",
                                              ",",
                                              "[",
                                              "]",
                                              "\n",
                                              "\r",
                                              "\r\n",
                                              "#",
                                              ";",
                                              ":",
                                              "-",
                                              "+",
                                              "*",
                                              "^",
                                              "(",
                                              ")",
                                              "nan",
                                              "inf",
                                              "-inf",
                                              "1e308",
                                              "1e-400",
                                              "4.9e-324",
                                              "4294967297",
                                              "-1",
                                              "0",
                                              "pi",
                                              "tuned",
                                              "oracle",
                                              "[study]",
                                              "[scenario.x]",
                                              "[filter.f]",
                                              "[noise.n]",
                                              "runs =",
                                              "steps =",
                                              "model =",
                                              "kind =",
                                              "q-diag =",
                                              "params =",
                                              "[states]",
                                              "[params]",
                                              "[rhs]",
                                              "[let]",
                                              "[measurement m]",
                                              "angle",
                                              "> 0",
                                              std::string(1, '\0'),
                                              "\xEF\xBB\xBF",
                                              "\xFF\xFE",
                                              "  ",
                                              "\t"};

std::string Mutate(const std::string& seed, Rng* rng) {
  std::string s = seed;
  const int edits = 1 + int(rng->Uniform() * 4);
  for (int e = 0; e < edits; ++e) {
    const size_t at = s.empty() ? 0 : size_t(rng->Uniform() * double(s.size()));
    switch (int(rng->Uniform() * 5)) {
      case 0:  // flip a byte
        if (!s.empty()) s[at] = char(int(rng->Uniform() * 256));
        break;
      case 1:  // delete a range
        if (!s.empty()) s.erase(at, size_t(1 + rng->Uniform() * 16));
        break;
      case 2:  // duplicate a range
        if (!s.empty()) s.insert(at, s.substr(at, size_t(1 + rng->Uniform() * 32)));
        break;
      default:  // insert a token
        s.insert(at, kDictionary[size_t(rng->Uniform() * double(kDictionary.size()))]);
    }
  }
  return s;
}

// Runs `parse` on `count` mutants of each seed; returns the number of
// inputs tried, failing the test on anything but success or InputError.
template <class Parse>
long Fuzz(const std::vector<std::string>& seeds, int count, uint64_t seed, Parse parse) {
  Rng rng(seed);
  long tried = 0, refused = 0;
  for (const std::string& text : seeds) {
    for (int i = 0; i < count; ++i) {
      const std::string mutant = Mutate(text, &rng);
      ++tried;
      try {
        parse(mutant);
      } catch (const InputError&) {
        ++refused;
      } catch (const std::exception& e) {
        ADD_FAILURE() << "not an InputError: " << e.what() << "\ninput:\n" << mutant;
        return tried;
      }
    }
  }
  std::printf("  %ld inputs tried, %ld refused with an InputError, the rest parsed\n", tried,
              refused);
  return tried;
}

TEST(ParserFuzz, CsvReader) {
  const std::vector<std::string> seeds = {
      "t,z_theta,theta,omega\n0,0.1,0.1,0\n0.01,0.11,0.1,0.5\n0.02,,0.2,1\n",
      "# comment\nt,z_sin_theta\n0,0.7\n0.0125,nan\n0.025,0.71\n", "t,u,z_x\n0,1,2\n1,1e-3,-4\n"};
  EXPECT_EQ(Fuzz(seeds, 20000, 11, [](const std::string& text) { ParseCsv(text, "fuzz.csv"); }),
            60000);
}

TEST(ParserFuzz, StudyConfig) {
  const std::vector<std::string> seeds = {TinyStudy(2), TinyStudy(3, 10, 50, true)};
  // A path in a folder of its own: a mutated `data =` glob finds nothing.
  EXPECT_EQ(Fuzz(seeds, 4000, 12,
                 [](const std::string& text) {
                   ParseStudyConfig(text, "/nonexistent-estlab-fuzz/s.ini");
                 }),
            8000);
}

TEST(ParserFuzz, ModelFile) {
  const std::string pendulum =
      ReadFile(std::string(ESTLAB_SOURCE_DIR) + "/examples/models/pendulum.model");
  const std::string dp =
      ReadFile(std::string(ESTLAB_SOURCE_DIR) + "/examples/models/multiarm_double_pendulum.model");
  const std::string cv =
      ReadFile(std::string(ESTLAB_SOURCE_DIR) + "/examples/models/linear_cv.model");
  EXPECT_EQ(Fuzz({pendulum, dp, cv}, 10000, 13,
                 [](const std::string& text) { modelfile::ParseModelFile(text, "fuzz.model"); }),
            30000);
}

}  // namespace
}  // namespace estlab::testing
