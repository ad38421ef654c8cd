// A bound-constrained L-BFGS that evaluates the objective only inside the box
// [lower, upper] (projected L-BFGS with an active set), in plain types:
// compiled once, not per model.
//
// Why not Ceres. ceres::GradientProblemSolver has no bounds; continuing the
// NLL outside the box by a penalty let it report values no admissible point
// has (issue 33: -1.2e10 on a trace whose admissible NLLs were all > 300) and
// evaluated the model beyond a parameter's constraint. Here every point the
// objective sees is P(x) = clamp(x, lower, upper), and every value reported
// (the trace, the final cost) is the objective at such a point.
//
// One iteration, from the feasible x_k with f_k = f(x_k), g_k = grad f(x_k):
//   1. Projected gradient  pg = x_k - P(x_k - g_k);  |pg|_inf <= gradient_tolerance: converged.
//   2. Active set A = { i : x_i at lower with g_i > 0, or at upper with g_i < 0 }.
//   3. Direction d = -H g on the free set (two-loop recursion over the last
//      `memory` pairs s = x_{k+1} - x_k, y = g_{k+1} - g_k, H_0 = gamma I,
//      gamma = s^T y / y^T y), d_i = 0 on A; not a descent direction
//      (g^T d >= 0): the memory is dropped and d = -g on the free set.
//   4. Line search on x(a) = P(x_k + a d): the first a in a0, a0/2, ... with f(x(a)) <=
//      f_k + c1 g^T (x(a) - x_k) (Armijo; a failed evaluation is rejected); where a0
//      passes inside the box but d^T g(x(a)) < c2 d^T g_k, c2 = 0.5 (Wolfe's curvature
//      test fails: the step is short), a grows up to 8 times (a0 = 1 with a memory).
//   5. |f_k - f_{k+1}| <= function_tolerance |f_k|, or
//      |x_{k+1} - x_k|_inf <= parameter_tolerance (|x_k|_inf + parameter_tolerance): converged.
// The accepted values decrease monotonically, so the final point is never
// worse than the start.
//
// Usage:
//   BoundedLbfgsOptions options;
//   BoundedLbfgsSummary s = MinimizeBounded(f, lower, upper, options, &x, callback);
//   if (s.converged) ...
#ifndef ESTLAB_ADAPTIVE_BOUNDED_LBFGS_H_
#define ESTLAB_ADAPTIVE_BOUNDED_LBFGS_H_

#include <functional>
#include <string>
#include <vector>

namespace estlab {

struct BoundedLbfgsOptions {
  int max_iterations = 200;
  int memory = 10;
  double function_tolerance = 1e-12;   // relative change of f
  double gradient_tolerance = 1e-8;    // max-norm of the projected gradient
  double parameter_tolerance = 1e-10;  // relative step
  double sufficient_decrease = 1e-4;   // c1 of the Armijo condition
  int max_backtracks = 60;             // halvings of the step per line search
  bool IsValid(std::string* error) const;
};

struct BoundedLbfgsSummary {
  bool usable = false;     // the start point could be evaluated
  bool converged = false;  // one of the tolerances was met
  std::string message;     // which one, or why it stopped
  int iterations = 0;      // accepted steps
  long evaluations = 0;    // objective calls
  double initial_cost = 0.0, final_cost = 0.0;
};

// f(x, &value, gradient): false when x is infeasible for the model (the
// filter failed); gradient may be null (value only).
using BoundedObjective = std::function<bool(const double* x, double* value, double* gradient)>;
// Called after every accepted step with its number (1, 2, ...), the new
// point, the value there and the change from the previous one (negative).
using BoundedIterationCallback =
    std::function<void(int iteration, const std::vector<double>& x, double value, double change)>;

// Minimises f over the box from *x (clamped into the box first). lower and
// upper may hold +-infinity; lower <= upper.
BoundedLbfgsSummary MinimizeBounded(const BoundedObjective& f, const std::vector<double>& lower,
                                    const std::vector<double>& upper,
                                    const BoundedLbfgsOptions& options, std::vector<double>* x,
                                    const BoundedIterationCallback& callback = {});

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_BOUNDED_LBFGS_H_
