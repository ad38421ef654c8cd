#include "src/modelfile/expression_tokens.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <string>

namespace estlab::modelfile {
namespace {

bool IsDigit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }
bool IsNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool IsNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

size_t SkipDigits(std::string_view text, size_t i) {
  while (i < text.size() && IsDigit(text[i])) ++i;
  return i;
}

// Length of the number at text[begin] (digits [. digits] [e [+-] digits]),
// or 0 when the exponent has no digits.
size_t NumberLength(std::string_view text, size_t begin) {
  size_t i = SkipDigits(text, begin);
  if (i < text.size() && text[i] == '.') i = SkipDigits(text, i + 1);
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    size_t j = i + 1;
    if (j < text.size() && (text[j] == '+' || text[j] == '-')) ++j;
    const size_t end = SkipDigits(text, j);
    if (end == j) return 0;
    i = end;
  }
  return i - begin;
}

// Reads the number at text[begin]; on error appends a diagnostic.
bool ReadNumber(std::string_view text, size_t begin, SourcePos pos, Token* token,
                std::vector<Diagnostic>* diagnostics) {
  const size_t length = NumberLength(text, begin);
  size_t end = begin + length;
  if (length == 0 || (end < text.size() && (IsNameChar(text[end]) || text[end] == '.'))) {
    while (end < text.size() && (IsNameChar(text[end]) || text[end] == '.')) ++end;
    diagnostics->push_back(
        MakeDiagnostic(pos, "bad number " + Quoted(text.substr(begin, end - begin))));
    return false;
  }
  token->text = text.substr(begin, length);
  token->value = std::strtod(std::string(token->text).c_str(), nullptr);
  if (!std::isfinite(token->value)) {
    diagnostics->push_back(
        MakeDiagnostic(pos, "number " + Quoted(token->text) + " is out of range"));
    return false;
  }
  return true;
}

TokenKind OperatorKind(char c) {
  switch (c) {
    case '+':
      return TokenKind::kPlus;
    case '-':
      return TokenKind::kMinus;
    case '*':
      return TokenKind::kStar;
    case '/':
      return TokenKind::kSlash;
    case '^':
      return TokenKind::kCaret;
    case '(':
      return TokenKind::kLeftParen;
    case ')':
      return TokenKind::kRightParen;
    case ',':
      return TokenKind::kComma;
    default:
      return TokenKind::kEnd;
  }
}

}  // namespace

bool Tokenize(std::string_view text, SourcePos start, std::vector<Token>* tokens,
              std::vector<Diagnostic>* diagnostics) {
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    Token token;
    token.pos = {start.line, start.column + int(i)};
    if (c == ' ' || c == '\t') {
      ++i;
      continue;
    }
    if (IsDigit(c) || (c == '.' && i + 1 < text.size() && IsDigit(text[i + 1]))) {
      token.kind = TokenKind::kNumber;
      if (!ReadNumber(text, i, token.pos, &token, diagnostics)) return false;
    } else if (IsNameStart(c)) {
      size_t end = i;
      while (end < text.size() && IsNameChar(text[end])) ++end;
      token.kind = TokenKind::kName;
      token.text = text.substr(i, end - i);
    } else if (OperatorKind(c) != TokenKind::kEnd) {
      token.kind = OperatorKind(c);
      token.text = text.substr(i, 1);
    } else {
      diagnostics->push_back(
          MakeDiagnostic(token.pos, "unexpected character " + Quoted(text.substr(i, 1))));
      return false;
    }
    i += token.text.size();
    tokens->push_back(token);
  }
  Token end;
  end.pos = {start.line, start.column + int(text.size())};
  tokens->push_back(end);
  return true;
}

}  // namespace estlab::modelfile
