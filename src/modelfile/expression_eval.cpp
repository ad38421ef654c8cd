// Evaluate and ForEachName of expression.h.
#include <cmath>

#include "src/modelfile/expression.h"

namespace estlab::modelfile {
namespace {

constexpr double kPi = 3.14159265358979323846;

double CallFunction(Function f, const std::vector<double>& a) {
  switch (f) {
    case Function::kSin:
      return std::sin(a[0]);
    case Function::kCos:
      return std::cos(a[0]);
    case Function::kTan:
      return std::tan(a[0]);
    case Function::kAsin:
      return std::asin(a[0]);
    case Function::kAcos:
      return std::acos(a[0]);
    case Function::kAtan:
      return std::atan(a[0]);
    case Function::kAtan2:
      return std::atan2(a[0], a[1]);
    case Function::kSinh:
      return std::sinh(a[0]);
    case Function::kCosh:
      return std::cosh(a[0]);
    case Function::kTanh:
      return std::tanh(a[0]);
    case Function::kExp:
      return std::exp(a[0]);
    case Function::kLog:
      return std::log(a[0]);
    case Function::kLog1p:
      return std::log1p(a[0]);
    case Function::kSqrt:
      return std::sqrt(a[0]);
    case Function::kAbs:
      return std::abs(a[0]);
    case Function::kPow:
      return std::pow(a[0], a[1]);
    case Function::kMin:
      return a[1] < a[0] ? a[1] : a[0];
    case Function::kMax:
      return a[0] < a[1] ? a[1] : a[0];
  }
  return std::nan("");
}

}  // namespace

double Evaluate(const Expr& e, const std::function<double(const std::string&)>& lookup) {
  switch (e.kind) {
    case ExprKind::kNumber:
      return e.value;
    case ExprKind::kPi:
      return kPi;
    case ExprKind::kName:
      return lookup(e.text);
    case ExprKind::kNegate:
      return -Evaluate(e.args[0], lookup);
    case ExprKind::kAdd:
      return Evaluate(e.args[0], lookup) + Evaluate(e.args[1], lookup);
    case ExprKind::kSubtract:
      return Evaluate(e.args[0], lookup) - Evaluate(e.args[1], lookup);
    case ExprKind::kMultiply:
      return Evaluate(e.args[0], lookup) * Evaluate(e.args[1], lookup);
    case ExprKind::kDivide:
      return Evaluate(e.args[0], lookup) / Evaluate(e.args[1], lookup);
    case ExprKind::kPower:
      return std::pow(Evaluate(e.args[0], lookup), Evaluate(e.args[1], lookup));
    case ExprKind::kCall: {
      std::vector<double> args;
      for (const Expr& a : e.args) args.push_back(Evaluate(a, lookup));
      return CallFunction(e.function, args);
    }
  }
  return std::nan("");
}

void ForEachName(const Expr& e, const std::function<void(const Expr&)>& fn) {
  if (e.kind == ExprKind::kName) fn(e);
  for (const Expr& a : e.args) ForEachName(a, fn);
}

void ForEachName(Expr& e, const std::function<void(Expr&)>& fn) {
  if (e.kind == ExprKind::kName) fn(e);
  for (Expr& a : e.args) ForEachName(a, fn);
}

}  // namespace estlab::modelfile
