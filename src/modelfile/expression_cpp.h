// A checked model-file expression as C++ for the generated model headers.
// The tree is emitted exactly as parsed (parentheses only where C++ needs
// them to keep its shape), so the double results are bit-identical to a
// hand-written expression with the same operations in the same order.
//
// Scalar types: inside Rhs/Step/Eval every value is either a double
// (numbers, pi, parameters, the input, dt and what is computed from them
// only) or the template scalar T (states, t, and what depends on them). Mixed
// + - * / is fine for every T estlab uses (double, ceres::Jet, NestedJet);
// where a function needs both arguments of type T (atan2, min, max, pow with
// a T exponent) the double one is cast with T(...).
//
// Functions: sin cos tan exp log sqrt abs tanh atan2 are called unqualified
// (the caller emits "using std::sin;" etc. for each name put in
// *std_functions, so that ADL finds the Jet overloads); asin acos atan sinh
// cosh log1p min max go through estlab::model_fn (model_functions.h), which
// also covers NestedJet. Powers: x^2 and x^3 with a literal exponent become
// (x * x) and (x * x * x) for a name or number x, model_fn::Square/Cube(...)
// otherwise; a double exponent gives pow(x, e); a T exponent
// model_fn::PowT(x, e) = exp(e log x).
//
// Usage:
//   CppScope scope;
//   scope.spell = [&](const Expr& n) { return n.ref == NameRef::kParam ? "p." + n.text : n.text; };
//   scope.is_t = [&](const Expr& n) { return n.ref == NameRef::kState; };
//   std::set<std::string> using_std;
//   std::string code = ToCpp(expr, scope, &using_std);  // "-(p.g / p.L) * sin(theta)"
#ifndef ESTLAB_MODELFILE_EXPRESSION_CPP_H_
#define ESTLAB_MODELFILE_EXPRESSION_CPP_H_

#include <functional>
#include <set>
#include <string>

#include "src/modelfile/expression.h"

namespace estlab::modelfile {

struct CppScope {
  // The C++ spelling of a kName node ("theta", "p.g", "u").
  std::function<std::string(const Expr&)> spell;
  // True when a kName node has type T; unset means every value is double
  // (as in Invariants).
  std::function<bool(const Expr&)> is_t;
};

std::string ToCpp(const Expr& e, const CppScope& scope, std::set<std::string>* std_functions);

// True when the C++ value of e has type T.
bool IsTValued(const Expr& e, const CppScope& scope);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_EXPRESSION_CPP_H_
