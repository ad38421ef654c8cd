// Deterministic mutation fuzzing of the model-file front end: mutated example
// files (byte flips, inserted tokens, deletions, truncations, moved lines)
// must either parse or throw ModelFileError, never anything else, never
// crash or hang; whatever parses must also generate a header.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "src/modelfile/codegen.h"
#include "src/modelfile/model_file.h"

#ifndef ESTLAB_SOURCE_DIR
#error "ESTLAB_SOURCE_DIR must be defined to the project root"
#endif

namespace estlab::modelfile {
namespace {

std::vector<std::string> ExampleTexts() {
  std::vector<std::string> texts;
  const std::filesystem::path dir = std::filesystem::path(ESTLAB_SOURCE_DIR) / "examples/models";
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".model") continue;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    texts.push_back(text.str());
  }
  std::sort(texts.begin(), texts.end());  // directory order is not deterministic
  return texts;
}

const char* const kTokens[] = {"(",
                               ")",
                               "^",
                               "[",
                               "]",
                               "=",
                               "#",
                               "\n",
                               "-",
                               "+",
                               "*",
                               "/",
                               ",",
                               ":",
                               " ",
                               "\t",
                               "\r",
                               "1e999",
                               "1.2.3",
                               "0",
                               "-0",
                               "pi",
                               "t",
                               "dt",
                               "u",
                               "x",
                               "theta",
                               "omega",
                               "angle",
                               "sin(",
                               "atan2(",
                               "pow(",
                               "min(1,",
                               "[let]",
                               "[rhs]",
                               "[step]",
                               "[states]",
                               "[params]",
                               "[model]",
                               "[measurement",
                               "[measurement m]",
                               "[invariant e]",
                               "conserved-if-zero = ",
                               "input = u\n",
                               "name = n\n",
                               "> 0",
                               ">= 0",
                               "< 0",
                               "[rad]",
                               "\n[rhs]\n",
                               "\nx = x\n",
                               "((((((((",
                               "__",
                               "\xff",
                               "\xc3\xa9",
                               "_"};  // NUL bytes: inserted separately below

// One random edit of `text`.
void Mutate(std::string* text, std::mt19937* rng) {
  auto pick = [&](size_t n) { return n == 0 ? size_t(0) : size_t((*rng)() % n); };
  const size_t at = pick(text->size() + 1);
  switch ((*rng)() % 6) {
    case 0:  // byte flip
      if (!text->empty()) (*text)[pick(text->size())] = char((*rng)() % 256);
      break;
    case 1: {  // inserted token
      const std::string token =
          (*rng)() % 20 == 0 ? std::string(1, '\0') : kTokens[pick(std::size(kTokens))];
      text->insert(at, token);
      break;
    }
    case 2:  // deletion
      text->erase(at, 1 + pick(20));
      break;
    case 3:  // truncation
      text->resize(at);
      break;
    case 4: {  // a copy of a random piece somewhere else
      const size_t from = pick(text->size() + 1);
      text->insert(at, text->substr(from, 1 + pick(80)));
      break;
    }
    default:  // a digit or letter changed
      if (!text->empty()) (*text)[pick(text->size())] = "0123456789abcxyz_-.e"[pick(20)];
      break;
  }
}

TEST(ModelFileFuzz, MutatedExamplesParseOrThrowModelFileError) {
  const std::vector<std::string> examples = ExampleTexts();
  ASSERT_GE(examples.size(), 5u);
  std::mt19937 rng(20240611);
  int parsed = 0, rejected = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string text = examples[size_t(i) % examples.size()];
    const int edits = 1 + int(rng() % 3);
    for (int k = 0; k < edits; ++k) Mutate(&text, &rng);
    try {
      const ModelFile m = ParseModelFile(text, "fuzz.model");
      EXPECT_NO_THROW(GenerateModelHeader(m, DefaultTypeName(m))) << text;
      ++parsed;
    } catch (const ModelFileError& e) {
      EXPECT_FALSE(e.diagnostics().empty());
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "unexpected " << e.what() << " for:\n" << text;
    }
  }
  // Both outcomes happen: the mutations neither all miss nor all break.
  EXPECT_GT(parsed, 1000);
  EXPECT_GT(rejected, 5000);
}

TEST(ModelFileFuzz, PathologicalInputs) {
  std::mt19937 rng(7);
  std::string random_bytes(1 << 16, '\0');
  for (char& c : random_bytes) c = char(rng() % 256);
  const std::string inputs[] = {
      "",
      std::string(1, '\0'),
      random_bytes,
      "[rhs]\nx = " + std::string(1 << 20, '('),
      "[rhs]\nx = " + std::string(1 << 20, '-') + "x",
      std::string(1 << 16, '['),
      std::string(1 << 16, '\n'),
      std::string(1 << 16, '='),
      "[states]\n" + std::string(50000, 'a') + " = angle\n[rhs]\n" + std::string(50000, 'a') +
          "b = 1\n",
  };
  for (const std::string& text : inputs) {
    try {
      ParseModelFile(text, "p.model");
      ADD_FAILURE() << "accepted a pathological input";
    } catch (const ModelFileError& e) {
      EXPECT_FALSE(e.diagnostics().empty());
    }
  }
}

}  // namespace
}  // namespace estlab::modelfile
