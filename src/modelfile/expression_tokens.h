// The tokenizer of model-file expressions (expression.h): numbers, names,
// operators, parentheses and commas, each with its position in the file.
//
// Usage:
//   std::vector<Token> tokens;
//   if (Tokenize("2 * x", {4, 9}, &tokens, &problems)) ...  // tokens end with kEnd
#ifndef ESTLAB_MODELFILE_EXPRESSION_TOKENS_H_
#define ESTLAB_MODELFILE_EXPRESSION_TOKENS_H_

#include <string_view>
#include <vector>

#include "src/modelfile/diagnostic.h"

namespace estlab::modelfile {

enum class TokenKind {
  kNumber,
  kName,
  kPlus,
  kMinus,
  kStar,
  kSlash,
  kCaret,
  kLeftParen,
  kRightParen,
  kComma,
  kEnd
};

struct Token {
  TokenKind kind = TokenKind::kEnd;
  std::string_view text;  // points into the tokenized text
  SourcePos pos;
  double value = 0.0;  // kNumber
};

// Splits `text` (text[0] at `start`) into tokens followed by one kEnd token.
// Returns false and appends a diagnostic on an unexpected character or a
// malformed or out-of-range number ("1.2.3", "3x", "1e", "1e999").
bool Tokenize(std::string_view text, SourcePos start, std::vector<Token>* tokens,
              std::vector<Diagnostic>* diagnostics);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_EXPRESSION_TOKENS_H_
