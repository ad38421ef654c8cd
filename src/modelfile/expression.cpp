// Recursive-descent parser of model-file expressions (grammar: expression.h).
#include "src/modelfile/expression.h"

#include <algorithm>
#include <utility>

#include "src/modelfile/expression_tokens.h"
#include "src/modelfile/names.h"

namespace estlab::modelfile {
namespace {

// Thrown inside the parser at the first syntax error; caught in
// ParseExpression, which reports it.
struct SyntaxError {
  Diagnostic diagnostic;
};

std::string Describe(const Token& t) {
  return t.kind == TokenKind::kEnd ? "the end of the expression" : Quoted(t.text);
}

class Parser {
 public:
  Parser(std::vector<Token> tokens, std::vector<Diagnostic>* diagnostics)
      : tokens_(std::move(tokens)), diagnostics_(diagnostics) {}

  // The whole expression; throws SyntaxError.
  Expr ParseAll() {
    if (Peek().kind == TokenKind::kEnd) Fail(Peek(), "empty expression");
    Expr e = ParseSum();
    if (Peek().kind == TokenKind::kRightParen)
      Fail(Peek(), "unbalanced parenthesis: unexpected ')'");
    if (Peek().kind != TokenKind::kEnd)
      Fail(Peek(), "expected an operator before " + Describe(Peek()));
    return e;
  }

  // Problems that do not stop parsing (unknown function, wrong arity).
  bool had_errors() const { return had_errors_; }

 private:
  const Token& Peek() const { return tokens_[next_]; }
  const Token& Take() { return tokens_[next_++]; }

  [[noreturn]] static void Fail(const Token& at, std::string message) {
    throw SyntaxError{MakeDiagnostic(at.pos, std::move(message))};
  }

  Expr Node(ExprKind kind, const Token& at, std::vector<Expr> args) {
    Expr e;
    e.kind = kind;
    e.pos = at.pos;
    int depth = 0;
    for (const Expr& a : args) depth = std::max(depth, a.depth);
    e.depth = depth + 1;
    e.args = std::move(args);
    if (e.depth > kMaxExpressionDepth) {
      Fail(at, "expression too long: operators nest more than " +
                   std::to_string(kMaxExpressionDepth) + " deep");
    }
    return e;
  }

  Expr ParseSum() {
    Expr left = ParseProduct();
    while (Peek().kind == TokenKind::kPlus || Peek().kind == TokenKind::kMinus) {
      const Token& op = Take();
      Expr right = ParseProduct();
      const ExprKind kind = op.kind == TokenKind::kPlus ? ExprKind::kAdd : ExprKind::kSubtract;
      left = Binary(kind, op, std::move(left), std::move(right));
    }
    return left;
  }

  Expr ParseProduct() {
    Expr left = ParseUnary();
    while (Peek().kind == TokenKind::kStar || Peek().kind == TokenKind::kSlash) {
      const Token& op = Take();
      Expr right = ParseUnary();
      const ExprKind kind = op.kind == TokenKind::kStar ? ExprKind::kMultiply : ExprKind::kDivide;
      left = Binary(kind, op, std::move(left), std::move(right));
    }
    return left;
  }

  Expr Binary(ExprKind kind, const Token& op, Expr left, Expr right) {
    std::vector<Expr> args;
    args.push_back(std::move(left));
    args.push_back(std::move(right));
    return Node(kind, op, std::move(args));
  }

  Expr ParseUnary() {
    if (++nesting_ > kMaxExpressionNesting) {
      Fail(Peek(), "expression nested too deeply (more than " +
                       std::to_string(kMaxExpressionNesting) + " levels)");
    }
    Expr e;
    if (Peek().kind == TokenKind::kMinus) {
      const Token& op = Take();
      std::vector<Expr> args;
      args.push_back(ParseUnary());
      e = Node(ExprKind::kNegate, op, std::move(args));
    } else if (Peek().kind == TokenKind::kPlus) {
      Take();
      e = ParseUnary();
    } else {
      e = ParsePower();
    }
    --nesting_;
    return e;
  }

  Expr ParsePower() {
    Expr base = ParsePrimary();
    if (Peek().kind != TokenKind::kCaret) return base;
    const Token& op = Take();
    Expr exponent = ParseUnary();
    return Binary(ExprKind::kPower, op, std::move(base), std::move(exponent));
  }

  Expr ParsePrimary() {
    const Token& t = Peek();
    switch (t.kind) {
      case TokenKind::kNumber: {
        Take();
        Expr e = Node(ExprKind::kNumber, t, {});
        e.value = t.value;
        e.text = std::string(t.text);
        return e;
      }
      case TokenKind::kName:
        Take();
        if (Peek().kind == TokenKind::kLeftParen) return ParseCall(t);
        return NameNode(t);
      case TokenKind::kLeftParen:
        return ParseParenthesized();
      default:
        MissingOperand(t);
    }
  }

  Expr NameNode(const Token& t) {
    Expr e = Node(t.text == "pi" ? ExprKind::kPi : ExprKind::kName, t, {});
    e.text = std::string(t.text);
    return e;
  }

  Expr ParseParenthesized() {
    const Token& open = Take();
    Expr inner = ParseSum();
    if (Peek().kind == TokenKind::kEnd) Fail(open, "unbalanced parenthesis: '(' is never closed");
    if (Peek().kind != TokenKind::kRightParen)
      Fail(Peek(), "expected an operator or ')' before " + Describe(Peek()));
    Take();
    return inner;
  }

  [[noreturn]] void MissingOperand(const Token& t) {
    const Token* previous = next_ > 0 ? &tokens_[next_ - 1] : nullptr;
    if (previous == nullptr) Fail(t, "expected a number, name or '(' but found " + Describe(t));
    if (previous->kind == TokenKind::kLeftParen && t.kind == TokenKind::kRightParen)
      Fail(t, "empty parentheses");
    if (t.kind == TokenKind::kEnd)
      Fail(*previous, Quoted(previous->text) + " has no right operand");
    Fail(t, "expected a number, name or '(' after " + Quoted(previous->text) + " but found " +
                Describe(t));
  }

  Expr ParseCall(const Token& name) {
    const Token& open = Take();
    std::vector<Expr> args;
    if (Peek().kind != TokenKind::kRightParen) {
      args.push_back(ParseSum());
      while (Peek().kind == TokenKind::kComma) {
        Take();
        args.push_back(ParseSum());
      }
    }
    if (Peek().kind == TokenKind::kEnd) Fail(open, "unbalanced parenthesis: '(' is never closed");
    if (Peek().kind != TokenKind::kRightParen)
      Fail(Peek(), "expected ',' or ')' in the call of " + Quoted(name.text) + " before " +
                       Describe(Peek()));
    Take();
    CheckCall(name, args.size());
    Expr e = Node(ExprKind::kCall, name, std::move(args));
    e.text = std::string(name.text);
    if (const FunctionInfo* f = FindFunction(name.text)) e.function = f->id;
    return e;
  }

  void CheckCall(const Token& name, size_t arg_count) {
    const FunctionInfo* f = FindFunction(name.text);
    if (f == nullptr) {
      std::vector<std::string> names;
      for (const FunctionInfo& info : Functions()) names.push_back(info.name);
      Report(name, "unknown function " + Quoted(name.text) + DidYouMean(name.text, names));
    } else if (int(arg_count) != f->arity) {
      Report(name, Quoted(name.text) + " takes " + std::to_string(f->arity) +
                       (f->arity == 1 ? " argument" : " arguments") + ", got " +
                       std::to_string(arg_count));
    }
  }

  void Report(const Token& at, std::string message) {
    diagnostics_->push_back(MakeDiagnostic(at.pos, std::move(message)));
    had_errors_ = true;
  }

  std::vector<Token> tokens_;
  std::vector<Diagnostic>* diagnostics_;
  size_t next_ = 0;
  int nesting_ = 0;
  bool had_errors_ = false;
};

}  // namespace

const std::vector<FunctionInfo>& Functions() {
  static const std::vector<FunctionInfo> kFunctions = {
      {"sin", Function::kSin, 1},     {"cos", Function::kCos, 1},   {"tan", Function::kTan, 1},
      {"asin", Function::kAsin, 1},   {"acos", Function::kAcos, 1}, {"atan", Function::kAtan, 1},
      {"atan2", Function::kAtan2, 2}, {"sinh", Function::kSinh, 1}, {"cosh", Function::kCosh, 1},
      {"tanh", Function::kTanh, 1},   {"exp", Function::kExp, 1},   {"log", Function::kLog, 1},
      {"log1p", Function::kLog1p, 1}, {"sqrt", Function::kSqrt, 1}, {"abs", Function::kAbs, 1},
      {"pow", Function::kPow, 2},     {"min", Function::kMin, 2},   {"max", Function::kMax, 2},
  };
  return kFunctions;
}

const FunctionInfo* FindFunction(std::string_view name) {
  for (const FunctionInfo& f : Functions()) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

std::optional<Expr> ParseExpression(std::string_view text, SourcePos start,
                                    std::vector<Diagnostic>* diagnostics) {
  std::vector<Token> tokens;
  if (!Tokenize(text, start, &tokens, diagnostics)) return std::nullopt;
  Parser parser(std::move(tokens), diagnostics);
  try {
    Expr e = parser.ParseAll();
    if (parser.had_errors()) return std::nullopt;
    return e;
  } catch (const SyntaxError& error) {
    diagnostics->push_back(error.diagnostic);
    return std::nullopt;
  }
}

}  // namespace estlab::modelfile
