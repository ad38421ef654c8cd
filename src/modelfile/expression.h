// Expressions of the model-file language: the syntax tree, its parser and a
// double-precision evaluator.
// User reference of the language (sections, functions, every error): docs/model-language.md
//
//   sum      = product { ("+" | "-") product }          left-associative
//   product  = unary { ("*" | "/") unary }              left-associative
//   unary    = ("-" | "+") unary | power                -a*b = (-a)*b
//   power    = primary [ "^" unary ]                    right-assoc; -x^2 = -(x^2)
//   primary  = number | "pi" | name | name "(" [sum {"," sum}] ")" | "(" sum ")"
//
// Numbers are C-style decimals (2, 0.5, .5, 1e-3). Functions and their arity:
// sin cos tan asin acos atan sinh cosh tanh exp log log1p sqrt abs (1),
// atan2 pow min max (2). Unary plus is dropped while parsing; everything else
// is kept exactly as written (no constant folding, no reassociation), so the
// generated C++ performs the same floating-point operations in the same order.
//
// Usage:
//   std::vector<Diagnostic> problems;
//   std::optional<Expr> e = ParseExpression("w2 * sin(theta)", {12, 9}, &problems);
//   double v = Evaluate(*e, [](const std::string& name) { return name == "w2" ? 64.0 : 0.3; });
//
// WARNING: ParseExpression checks syntax and functions only; which names exist
// is decided by the model-file checker (model_check.h), which also fills in
// Expr::ref and Expr::index.
#ifndef ESTLAB_MODELFILE_EXPRESSION_H_
#define ESTLAB_MODELFILE_EXPRESSION_H_

#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "src/modelfile/diagnostic.h"

namespace estlab::modelfile {

// Parentheses, unary operators and '^' nest at most this deep; longer chains
// of binary operators at most kMaxExpressionDepth (the tree's height). Deeper
// input is rejected with a diagnostic, so no recursion can exhaust the stack.
inline constexpr int kMaxExpressionNesting = 200;
inline constexpr int kMaxExpressionDepth = 1000;

enum class ExprKind {
  kNumber,
  kPi,
  kName,
  kNegate,
  kAdd,
  kSubtract,
  kMultiply,
  kDivide,
  kPower,
  kCall
};

enum class Function {
  kSin,
  kCos,
  kTan,
  kAsin,
  kAcos,
  kAtan,
  kAtan2,
  kSinh,
  kCosh,
  kTanh,
  kExp,
  kLog,
  kLog1p,
  kSqrt,
  kAbs,
  kPow,
  kMin,
  kMax
};

struct FunctionInfo {
  const char* name;
  Function id;
  int arity;
};

// The function table in the order listed above.
const std::vector<FunctionInfo>& Functions();
// nullptr when `name` is not a function.
const FunctionInfo* FindFunction(std::string_view name);

// What a name refers to, filled in by the checker.
enum class NameRef { kUnresolved, kState, kParam, kLet, kInput, kTime, kStepLength };

struct Expr {
  ExprKind kind = ExprKind::kNumber;
  SourcePos pos;                       // the token: number, name, operator or function name
  double value = 0.0;                  // kNumber
  std::string text;                    // kNumber: as written; kName: the name; kCall: the function
  Function function = Function::kSin;  // kCall
  std::vector<Expr> args;              // operands: 1 (kNegate), 2 (binary), arity (kCall)
  NameRef ref = NameRef::kUnresolved;  // kName
  int index = -1;                      // kName: state, parameter or let index
  int depth = 1;                       // height of this subtree
};

// Parses one expression. `start` is the position of text[0] in the file.
// On error appends diagnostics (pointing at the offending token) and returns
// nullopt; unknown functions and wrong arities are reported too.
std::optional<Expr> ParseExpression(std::string_view text, SourcePos start,
                                    std::vector<Diagnostic>* diagnostics);

// The value in double. `lookup` gives the value of each kName node (pi is
// built in). Functions map to <cmath>; min(a, b) = b < a ? b : a and
// max(a, b) = a < b ? b : a, as in the generated code (model_functions.h).
double Evaluate(const Expr& e, const std::function<double(const std::string&)>& lookup);

// Calls fn on every kName node of e, left to right.
void ForEachName(const Expr& e, const std::function<void(const Expr&)>& fn);
void ForEachName(Expr& e, const std::function<void(Expr&)>& fn);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_EXPRESSION_H_
