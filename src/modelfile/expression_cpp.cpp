#include "src/modelfile/expression_cpp.h"

#include <initializer_list>
#include <string>
#include <string_view>

#include "src/modelfile/cpp_names.h"

namespace estlab::modelfile {
namespace {

constexpr double kPi = 3.14159265358979323846;

// C++ precedence of the emitted text: what a parent must parenthesize.
enum Precedence { kSum = 1, kProduct = 2, kUnary = 3, kAtom = 4 };

// Concatenation by appending. (GCC 12 at -O3 warns falsely, -Wrestrict, on
// a string literal plus a temporary std::string.)
std::string Cat(std::initializer_list<std::string_view> parts) {
  std::string out;
  for (std::string_view p : parts) out += p;
  return out;
}

struct Code {
  std::string text;
  int precedence;
};

class Emitter {
 public:
  Emitter(const CppScope& scope, std::set<std::string>* std_functions)
      : scope_(scope), std_functions_(std_functions) {}

  Code Emit(const Expr& e) {
    switch (e.kind) {
      case ExprKind::kNumber:
        return {FormatDouble(e.value), kAtom};
      case ExprKind::kPi:
        return {FormatDouble(kPi), kAtom};
      case ExprKind::kName:
        return {scope_.spell(e), kAtom};
      case ExprKind::kNegate:
        return {Cat({"-", Wrap(Emit(e.args[0]), kAtom)}), kUnary};
      case ExprKind::kAdd:
        return Binary(e, " + ", kSum);
      case ExprKind::kSubtract:
        return Binary(e, " - ", kSum);
      case ExprKind::kMultiply:
        return Binary(e, " * ", kProduct);
      case ExprKind::kDivide:
        return Binary(e, " / ", kProduct);
      case ExprKind::kPower:
        return Power(e.args[0], e.args[1]);
      case ExprKind::kCall:
        return Call(e);
    }
    return {"", kAtom};
  }

 private:
  static std::string Wrap(const Code& c, int needed) {
    return c.precedence < needed ? Cat({"(", c.text, ")"}) : c.text;
  }

  // Left-associative: the right operand is parenthesized at equal
  // precedence, so a + (b + c) keeps its order.
  Code Binary(const Expr& e, const char* op, int precedence) {
    return {Wrap(Emit(e.args[0]), precedence) + op + Wrap(Emit(e.args[1]), precedence + 1),
            precedence};
  }

  bool IsT(const Expr& e) const { return IsTValued(e, scope_); }

  // a as an argument that must have type T because `other` has.
  std::string AsT(const Expr& a, bool cast) {
    const std::string text = Emit(a).text;
    return cast ? Cat({"T(", text, ")"}) : text;
  }

  // f(a, b) with both arguments of one type.
  std::string SameTypeArgs(const Expr& a, const Expr& b) {
    const bool t = IsT(a) || IsT(b);
    return Cat({AsT(a, t && !IsT(a)), ", ", AsT(b, t && !IsT(b))});
  }

  Code Power(const Expr& base, const Expr& exponent) {
    const bool literal = exponent.kind == ExprKind::kNumber;
    if (literal && (exponent.value == 2.0 || exponent.value == 3.0)) {
      const bool cube = exponent.value == 3.0;
      const bool simple = base.kind == ExprKind::kName || base.kind == ExprKind::kNumber ||
                          base.kind == ExprKind::kPi;
      const std::string b = Emit(base).text;
      if (simple) return {Cat({"(", b, " * ", b, cube ? " * " : "", cube ? b : "", ")"}), kAtom};
      return {Cat({cube ? "model_fn::Cube(" : "model_fn::Square(", b, ")"}), kAtom};
    }
    if (!IsT(exponent)) {
      std_functions_->insert("pow");
      return {Cat({"pow(", Emit(base).text, ", ", Emit(exponent).text, ")"}), kAtom};
    }
    return {Cat({"model_fn::PowT(", SameTypeArgs(base, exponent), ")"}), kAtom};
  }

  Code Call(const Expr& e) {
    const std::string name = e.text;
    switch (e.function) {
      case Function::kPow:
        return Power(e.args[0], e.args[1]);
      case Function::kAtan2:
        std_functions_->insert("atan2");
        return {Cat({"atan2(", SameTypeArgs(e.args[0], e.args[1]), ")"}), kAtom};
      case Function::kMin:
      case Function::kMax:
        return {Cat({e.function == Function::kMin ? "model_fn::Min(" : "model_fn::Max(",
                     SameTypeArgs(e.args[0], e.args[1]), ")"}),
                kAtom};
      case Function::kAsin:
      case Function::kAcos:
      case Function::kAtan:
      case Function::kSinh:
      case Function::kCosh:
      case Function::kLog1p:
        return {Cat({"model_fn::", CamelCase(name), "(", Emit(e.args[0]).text, ")"}), kAtom};
      default:
        std_functions_->insert(name);
        return {Cat({name, "(", Emit(e.args[0]).text, ")"}), kAtom};
    }
  }

  const CppScope& scope_;
  std::set<std::string>* std_functions_;
};

}  // namespace

bool IsTValued(const Expr& e, const CppScope& scope) {
  if (!scope.is_t) return false;
  if (e.kind == ExprKind::kName) return scope.is_t(e);
  for (const Expr& a : e.args) {
    if (IsTValued(a, scope)) return true;
  }
  return false;
}

std::string ToCpp(const Expr& e, const CppScope& scope, std::set<std::string>* std_functions) {
  std::set<std::string> ignored;
  return Emitter(scope, std_functions ? std_functions : &ignored).Emit(e).text;
}

}  // namespace estlab::modelfile
