// Model-file expressions: precedence and associativity, every function
// against <cmath>, and syntax errors with the column of the offending token.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "src/modelfile/expression.h"

namespace estlab::modelfile {
namespace {

// Parses `text` as if it started at line 3, column 5.
std::optional<Expr> Parse(const std::string& text, std::vector<Diagnostic>* problems) {
  return ParseExpression(text, {3, 5}, problems);
}

double Eval(const std::string& text, const std::map<std::string, double>& values = {}) {
  std::vector<Diagnostic> problems;
  const std::optional<Expr> e = Parse(text, &problems);
  EXPECT_TRUE(e.has_value()) << text << ": " << (problems.empty() ? "" : problems[0].message);
  if (!e) return std::nan("");
  return Evaluate(*e, [&](const std::string& name) { return values.at(name); });
}

// The single diagnostic of a malformed expression, as "LINE:COL: message".
std::string Error(const std::string& text) {
  std::vector<Diagnostic> problems;
  EXPECT_FALSE(Parse(text, &problems).has_value()) << text;
  if (problems.size() != 1)
    return "expected one diagnostic, got " + std::to_string(problems.size());
  return std::to_string(problems[0].line) + ":" + std::to_string(problems[0].column) + ": " +
         problems[0].message;
}

TEST(Expression, PrecedenceAndAssociativity) {
  EXPECT_EQ(Eval("1 + 2 * 3"), 7.0);
  EXPECT_EQ(Eval("(1 + 2) * 3"), 9.0);
  EXPECT_EQ(Eval("1 - 2 - 3"), -4.0);  // left-associative
  EXPECT_EQ(Eval("1 - (2 - 3)"), 2.0);
  EXPECT_EQ(Eval("8 / 4 / 2"), 1.0);    // left-associative
  EXPECT_EQ(Eval("2 ^ 3 ^ 2"), 512.0);  // right-associative: 2^(3^2)
  EXPECT_EQ(Eval("-2 ^ 2"), -4.0);      // -(2^2), as in mathematics
  EXPECT_EQ(Eval("-x^2", {{"x", 3}}), -9.0);
  EXPECT_EQ(Eval("2 ^ -1"), 0.5);
  EXPECT_EQ(Eval("2 * -3"), -6.0);
  EXPECT_EQ(Eval("- -3"), 3.0);
  EXPECT_EQ(Eval("+3 - +1"), 2.0);
  EXPECT_EQ(Eval("2 * 3 ^ 2"), 18.0);
  EXPECT_EQ(Eval("12 / 2 * 3"), 18.0);
  EXPECT_EQ(Eval("1e-3 * 1000"), 1.0);
  EXPECT_EQ(Eval(".5 + 1.e1"), 10.5);
  EXPECT_DOUBLE_EQ(Eval("2 * pi"), 2 * M_PI);
}

TEST(Expression, TreeKeepsTheWrittenShape) {
  std::vector<Diagnostic> problems;
  const std::optional<Expr> e = Parse("a - b * c", &problems);
  ASSERT_TRUE(e.has_value());
  EXPECT_EQ(e->kind, ExprKind::kSubtract);
  EXPECT_EQ(e->pos.column, 7);  // the '-' at offset 2 of a text starting at column 5
  ASSERT_EQ(e->args.size(), 2u);
  EXPECT_EQ(e->args[0].kind, ExprKind::kName);
  EXPECT_EQ(e->args[0].text, "a");
  EXPECT_EQ(e->args[1].kind, ExprKind::kMultiply);
  EXPECT_EQ(e->args[1].args[1].pos.column, 13);  // c
  // -a * b is (-a) * b, -a ^ 2 is -(a ^ 2).
  EXPECT_EQ(Parse("-a * b", &problems)->kind, ExprKind::kMultiply);
  EXPECT_EQ(Parse("-a ^ 2", &problems)->kind, ExprKind::kNegate);
  EXPECT_EQ(Parse("pi", &problems)->kind, ExprKind::kPi);
  EXPECT_TRUE(problems.empty());
}

TEST(Expression, EveryFunctionMatchesCmath) {
  const double x = 0.3, y = -1.7;
  const std::map<std::string, double> v = {{"x", x}, {"y", y}};
  EXPECT_EQ(Eval("sin(x)", v), std::sin(x));
  EXPECT_EQ(Eval("cos(x)", v), std::cos(x));
  EXPECT_EQ(Eval("tan(x)", v), std::tan(x));
  EXPECT_EQ(Eval("asin(x)", v), std::asin(x));
  EXPECT_EQ(Eval("acos(x)", v), std::acos(x));
  EXPECT_EQ(Eval("atan(y)", v), std::atan(y));
  EXPECT_EQ(Eval("atan2(y, x)", v), std::atan2(y, x));
  EXPECT_EQ(Eval("sinh(y)", v), std::sinh(y));
  EXPECT_EQ(Eval("cosh(y)", v), std::cosh(y));
  EXPECT_EQ(Eval("tanh(y)", v), std::tanh(y));
  EXPECT_EQ(Eval("exp(y)", v), std::exp(y));
  EXPECT_EQ(Eval("log(x)", v), std::log(x));
  EXPECT_EQ(Eval("log1p(x)", v), std::log1p(x));
  EXPECT_EQ(Eval("sqrt(x)", v), std::sqrt(x));
  EXPECT_EQ(Eval("abs(y)", v), std::abs(y));
  EXPECT_EQ(Eval("pow(x, y)", v), std::pow(x, y));
  EXPECT_EQ(Eval("x ^ y", v), std::pow(x, y));
  EXPECT_EQ(Eval("min(x, y)", v), y);
  EXPECT_EQ(Eval("max(x, y)", v), x);
  EXPECT_EQ(Eval("max(min(x, 0), y)", v), 0.0);
  EXPECT_EQ(Functions().size(), 18u);
  EXPECT_EQ(FindFunction("atan2")->arity, 2);
  EXPECT_EQ(FindFunction("theta"), nullptr);
}

TEST(Expression, SyntaxErrorsPointAtTheOffendingToken) {
  // The text starts at column 5: offset i is column 5 + i.
  EXPECT_EQ(Error(""), "3:5: empty expression");
  EXPECT_EQ(Error("1 +"), "3:7: '+' has no right operand");
  EXPECT_EQ(Error("(1 + 2"), "3:5: unbalanced parenthesis: '(' is never closed");
  EXPECT_EQ(Error("1 + 2)"), "3:10: unbalanced parenthesis: unexpected ')'");
  EXPECT_EQ(Error("sin(x"), "3:8: unbalanced parenthesis: '(' is never closed");
  EXPECT_EQ(Error("1 * * 2"), "3:9: expected a number, name or '(' after '*' but found '*'");
  EXPECT_EQ(Error("x y"), "3:7: expected an operator before 'y'");
  EXPECT_EQ(Error("(x y)"), "3:8: expected an operator or ')' before 'y'");
  EXPECT_EQ(Error("()"), "3:6: empty parentheses");
  EXPECT_EQ(Error("1.2.3"), "3:5: bad number '1.2.3'");
  EXPECT_EQ(Error("2 * 3x"), "3:9: bad number '3x'");
  EXPECT_EQ(Error("1e"), "3:5: bad number '1e'");
  EXPECT_EQ(Error("1e999"), "3:5: number '1e999' is out of range");
  EXPECT_EQ(Error("x @ y"), "3:7: unexpected character '@'");
  EXPECT_EQ(Error("x\x01"), "3:6: unexpected character '\\x01'");
  EXPECT_EQ(Error("atan2(x)"), "3:5: 'atan2' takes 2 arguments, got 1");
  EXPECT_EQ(Error("sin(x, y)"), "3:5: 'sin' takes 1 argument, got 2");
  EXPECT_EQ(Error("1 + sinn(x)"), "3:9: unknown function 'sinn'; did you mean 'sin'?");
  EXPECT_EQ(Error("foo(x)"), "3:5: unknown function 'foo'");
  EXPECT_EQ(Error("max(x,)"), "3:11: expected a number, name or '(' after ',' but found ')'");
  EXPECT_EQ(Error("min(x y)"), "3:11: expected ',' or ')' in the call of 'min' before 'y'");
}

TEST(Expression, FunctionErrorsAreAllReported) {
  std::vector<Diagnostic> problems;
  EXPECT_FALSE(Parse("foo(1) + sin(1, 2) + bar(2)", &problems).has_value());
  ASSERT_EQ(problems.size(), 3u);
  EXPECT_EQ(problems[0].column, 5);
  EXPECT_EQ(problems[1].column, 14);
  EXPECT_EQ(problems[2].column, 26);
}

TEST(Expression, DeepNestingIsRejectedNotRecursedInto) {
  const std::string deep = std::string(100000, '(') + "1" + std::string(100000, ')');
  const std::string ok = std::string(150, '(') + "1" + std::string(150, ')');
  EXPECT_EQ(Eval(ok), 1.0);
  EXPECT_NE(Error(deep).find("nested too deeply"), std::string::npos);
  EXPECT_NE(Error(std::string(100000, '-') + "1").find("nested too deeply"), std::string::npos);
  std::string exponent_chain = "2";
  for (int i = 0; i < 5000; ++i) exponent_chain += "^2";
  EXPECT_NE(Error(exponent_chain).find("nested too deeply"), std::string::npos);
  std::string long_sum = "1";
  for (int i = 0; i < 5000; ++i) long_sum += "+1";
  EXPECT_NE(Error(long_sum).find("expression too long"), std::string::npos);
  std::string sum_ok = "1";
  for (int i = 0; i < 900; ++i) sum_ok += "+1";
  EXPECT_EQ(Eval(sum_ok), 901.0);
}

}  // namespace
}  // namespace estlab::modelfile
