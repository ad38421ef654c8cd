// Projected L-BFGS with an active set; the equations are in bounded_lbfgs.h.
#include "adaptive/bounded_lbfgs.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "src/core/types.h"

namespace estlab {

bool BoundedLbfgsOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (max_iterations < 0) return fail("max_iterations must be >= 0");
  if (memory < 1) return fail("memory must be >= 1");
  if (!(function_tolerance >= 0) || !(gradient_tolerance >= 0) || !(parameter_tolerance >= 0))
    return fail("tolerances must be >= 0");
  if (!(sufficient_decrease > 0 && sufficient_decrease < 1))
    return fail("sufficient_decrease must be in (0, 1)");
  if (max_backtracks < 1) return fail("max_backtracks must be >= 1");
  return true;
}

namespace {

using Vector = std::vector<double>;

// Step 4b's settings: the curvature constant of Wolfe's condition and how
// often a short step is extended. c2 = 0.5, stricter than the 0.9 usual for
// quasi-Newton directions: on the README's joint pendulum fit (K = 4) the
// steps that passed 0.9 still left 30-75 % of the slope, and L-BFGS took 30
// iterations (43 evaluations); with 0.5, 16 iterations (35 evaluations),
// 0.72x the wall (docs/performance.md, "Issue 33: a curvature condition").
constexpr double kCurvature = 0.5;
constexpr int kMaxExtensions = 8;

// Step 5's stop within rounding. A line search that finds no decrease at
// any of its halvings, with a correct gradient of a smooth f, means that the
// best decrease along d is below what f's rounding resolves: along the step
// p of a failed trial, f(x + t p) = f + t (-s) + 1/2 t^2 c with s = -g^T p
// and c the curvature, so the best decrease is s^2 / (2 c). c is read from
// the shortest failed trial whose rise is well measured (above
// kMeasurableRise max(1, |f|)) and trusted only when the quadratic model
// also predicts the rise of the trial before it (twice as long, unclamped)
// within 10 %: a gradient that does not match f gives a rise linear in t,
// which that check refuses. The point is then a minimum to within rounding
// when s^2 / (2 c) <= kRoundingDecrease max(1, |f|) (for an NLL of 3000, 3e-7
// nats: far below the 0.5 nats of one standard error).
constexpr double kMeasurableRise = 1e-9;
constexpr double kRoundingDecrease = 1e-10;

double Dot(const Vector& a, const Vector& b) {
  double s = 0.0;
  for (size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

double MaxNorm(const Vector& a) {
  double m = 0.0;
  for (double v : a) m = std::max(m, std::abs(v));
  return m;
}

// The state of the iteration: the current point, its value and gradient,
// the box and the curvature pairs.
struct State {
  Vector x, g, lower, upper;
  double f = 0.0;
  std::deque<std::pair<Vector, Vector>> pairs;  // (s, y), oldest first
};

Vector Project(const State& st, const Vector& x) {
  Vector p(x.size());
  for (size_t i = 0; i < x.size(); ++i) p[i] = std::clamp(x[i], st.lower[i], st.upper[i]);
  return p;
}

// Step 1: |x - P(x - g)|_inf.
double ProjectedGradientNorm(const State& st) {
  double m = 0.0;
  for (size_t i = 0; i < st.x.size(); ++i)
    m = std::max(m, std::abs(st.x[i] - std::clamp(st.x[i] - st.g[i], st.lower[i], st.upper[i])));
  return m;
}

// Step 2: whether x_i is held at a bound by its gradient.
std::vector<bool> ActiveSet(const State& st) {
  std::vector<bool> active(st.x.size(), false);
  for (size_t i = 0; i < st.x.size(); ++i)
    active[i] = (st.x[i] <= st.lower[i] && st.g[i] > 0) || (st.x[i] >= st.upper[i] && st.g[i] < 0);
  return active;
}

// Step 3: -H g on the free set by the two-loop recursion; -g there when the
// memory is empty or the result does not descend.
Vector Direction(State* st, const std::vector<bool>& active) {
  const size_t k = st->x.size();
  Vector q(k);
  for (size_t i = 0; i < k; ++i) q[i] = active[i] ? 0.0 : st->g[i];
  std::vector<double> alpha(st->pairs.size());
  for (size_t j = st->pairs.size(); j-- > 0;) {
    const auto& [s, y] = st->pairs[j];
    alpha[j] = Dot(s, q) / Dot(y, s);
    for (size_t i = 0; i < k; ++i) q[i] -= alpha[j] * y[i];
  }
  if (!st->pairs.empty()) {
    const auto& [s, y] = st->pairs.back();
    const double gamma = Dot(s, y) / Dot(y, y);
    for (double& v : q) v *= gamma;
  }
  for (size_t j = 0; j < st->pairs.size(); ++j) {
    const auto& [s, y] = st->pairs[j];
    const double beta = Dot(y, q) / Dot(y, s);
    for (size_t i = 0; i < k; ++i) q[i] += s[i] * (alpha[j] - beta);
  }
  Vector d(k);
  for (size_t i = 0; i < k; ++i) d[i] = active[i] ? 0.0 : -q[i];
  if (Dot(d, st->g) < 0.0) return d;
  st->pairs.clear();
  for (size_t i = 0; i < k; ++i) d[i] = active[i] ? 0.0 : -st->g[i];
  return d;
}

struct Trial {
  bool accepted = false;
  bool clamped = false;  // the projection moved the trial point off x_k + a d
  Vector x, g;
  double f = 0.0, a = 0.0;
  double first_predicted = 0.0;  // -g^T (x(a0) - x_k): the full step's first-order decrease
  // When no trial was accepted: the best decrease along d that the quadratic
  // model of the failed trials promises (step 5's stop within rounding);
  // +inf when no two well-measured trials confirmed the model.
  double best_decrease = std::numeric_limits<double>::infinity();
};

// Step 5: a failed trial p (rise f(x + p) - f, first-order decrease s =
// -g^T p) updates the quadratic model's best decrease when the trial before
// it, twice as long, had the rise the model predicts (-2 s + 2 c).
struct RiseModel {
  bool have_previous = false;
  double previous_rise = 0.0;
  void Add(double rise, double s, bool clamped, double scale, Trial* t) {
    const bool measured = !clamped && rise > kMeasurableRise * scale && s > 0.0;
    if (measured && have_previous) {
      const double c = 2.0 * (rise + s);
      if (std::abs(-2.0 * s + 2.0 * c - previous_rise) <= 0.1 * previous_rise)
        t->best_decrease = s * s / (2.0 * c);
    }
    have_previous = measured;
    previous_rise = rise;
  }
};

// x(a) = P(x_k + a d), and whether the projection moved it.
Vector TrialPoint(const State& st, const Vector& d, double a, bool* clamped) {
  Vector trial(st.x.size());
  *clamped = false;
  for (size_t i = 0; i < trial.size(); ++i) {
    const double free = st.x[i] + a * d[i];
    trial[i] = std::clamp(free, st.lower[i], st.upper[i]);
    *clamped = *clamped || trial[i] != free;
  }
  return trial;
}

// Step 4a: projected backtracking from a0 along d. The first trial is
// evaluated with its gradient (it is usually accepted); later ones are
// valued first (the cheap pass) and differentiated once accepted.
Trial Backtrack(const BoundedObjective& f, const State& st, const Vector& d, double a0,
                const BoundedLbfgsOptions& o, long* evaluations) {
  Trial t;
  t.g.resize(st.x.size());
  RiseModel model;
  const double scale = std::max(1.0, std::abs(st.f));
  double a = a0;
  for (int b = 0; b < o.max_backtracks; ++b, a *= 0.5) {
    bool clamped = false;
    const Vector trial = TrialPoint(st, d, a, &clamped);
    Vector step(trial.size());
    for (size_t i = 0; i < step.size(); ++i) step[i] = trial[i] - st.x[i];
    const double predicted = Dot(st.g, step);  // < 0
    if (b == 0) t.first_predicted = -predicted;
    if (MaxNorm(step) == 0.0) break;
    double value = 0.0;
    ++*evaluations;
    if (!f(trial.data(), &value, b == 0 ? t.g.data() : nullptr) || !std::isfinite(value)) {
      model.have_previous = false;
      continue;
    }
    if (!(value <= st.f + o.sufficient_decrease * predicted && value < st.f)) {
      model.Add(value - st.f, -predicted, clamped, scale, &t);
      continue;
    }
    if (b > 0) {  // the accepted value is the one returned with the gradient, checked again
      ++*evaluations;
      if (!f(trial.data(), &value, t.g.data()) || !std::isfinite(value)) continue;
      if (!(value <= st.f + o.sufficient_decrease * predicted && value < st.f)) continue;
    }
    t.accepted = true, t.clamped = clamped;
    t.x = trial, t.f = value, t.a = a;
    return t;
  }
  return t;
}

// Step 4b: where the first trial step was accepted, lies inside the box and
// the slope along d is still steep there (d^T g(x(a)) < c2 d^T g_k, the
// curvature condition of Wolfe fails), the step is too short: it is
// extended (a -> the secant's zero of the slope, within [2a, 10a]) while
// the value keeps falling below the Armijo line and the slope stays steep.
// The best point found is kept, so the values still decrease monotonically.
void Extend(const BoundedObjective& f, const State& st, const Vector& d,
            const BoundedLbfgsOptions& o, long* evaluations, Trial* t) {
  const double slope0 = Dot(st.g, d);  // < 0
  for (int e = 0; e < kMaxExtensions; ++e) {
    const double slope = Dot(t->g, d);
    if (t->clamped || !std::isfinite(slope) || slope >= kCurvature * slope0) return;
    const double secant = t->a * slope0 / (slope0 - slope);  // zero of the linear slope model
    const double a = std::clamp(secant, 2.0 * t->a, 10.0 * t->a);
    bool clamped = false;
    const Vector trial = TrialPoint(st, d, a, &clamped);
    double predicted = 0.0;
    for (size_t i = 0; i < trial.size(); ++i) predicted += st.g[i] * (trial[i] - st.x[i]);
    double value = 0.0;
    ++*evaluations;
    if (!f(trial.data(), &value, nullptr) || !std::isfinite(value)) return;
    if (!(value <= st.f + o.sufficient_decrease * predicted && value < t->f)) return;
    Vector g(trial.size());
    ++*evaluations;
    if (!f(trial.data(), &value, g.data()) || !std::isfinite(value) || !(value < t->f)) return;
    t->x = trial, t->g = std::move(g), t->f = value, t->a = a, t->clamped = clamped;
  }
}

// Step 4: backtrack, then extend a step that was too short.
Trial LineSearch(const BoundedObjective& f, const State& st, const Vector& d, double a0,
                 const BoundedLbfgsOptions& o, long* evaluations) {
  Trial t = Backtrack(f, st, d, a0, o, evaluations);
  if (t.accepted && t.a == a0) Extend(f, st, d, o, evaluations, &t);
  return t;
}

// Adds the pair (s, y) when it has positive curvature.
void Remember(State* st, const Vector& x_new, const Vector& g_new, int memory) {
  Vector s(x_new.size()), y(x_new.size());
  for (size_t i = 0; i < s.size(); ++i) s[i] = x_new[i] - st->x[i], y[i] = g_new[i] - st->g[i];
  const double sy = Dot(s, y);
  if (!(sy > 1e-12 * std::sqrt(Dot(s, s) * Dot(y, y)))) return;
  st->pairs.emplace_back(std::move(s), std::move(y));
  if (int(st->pairs.size()) > memory) st->pairs.pop_front();
}

}  // namespace

BoundedLbfgsSummary MinimizeBounded(const BoundedObjective& f, const Vector& lower,
                                    const Vector& upper, const BoundedLbfgsOptions& o, Vector* x,
                                    const BoundedIterationCallback& callback) {
  BoundedLbfgsSummary sum;
  State st;
  st.x = *x, st.g = Vector(x->size()), st.lower = lower, st.upper = upper;
  st.x = Project(st, st.x);
  *x = st.x;
  ++sum.evaluations;
  if (!f(st.x.data(), &st.f, st.g.data()) || !std::isfinite(st.f)) {
    sum.message = "the objective cannot be evaluated at the start point";
    return sum;
  }
  sum.usable = true;
  sum.initial_cost = sum.final_cost = st.f;
  bool retried = false;
  while (true) {
    const double pg = ProjectedGradientNorm(st);
    if (pg <= o.gradient_tolerance) {
      sum.converged = true;
      sum.message = "Projected gradient tolerance reached. |pg|_inf = " + FormatNumber(pg);
      break;
    }
    if (sum.iterations >= o.max_iterations) {
      sum.message = "Maximum number of iterations reached (" + std::to_string(o.max_iterations) +
                    "), |pg|_inf = " + FormatNumber(pg);
      break;
    }
    const Vector d = Direction(&st, ActiveSet(st));
    const double a0 = st.pairs.empty() ? std::min(1.0, 1.0 / std::max(MaxNorm(d), 1e-300)) : 1.0;
    const Trial t = LineSearch(f, st, d, a0, o, &sum.evaluations);
    if (!t.accepted) {
      if (!st.pairs.empty() && !retried) {  // the curvature memory misleads: drop it once
        st.pairs.clear();
        retried = true;
        continue;
      }
      // Even the first trial step promised a decrease below the rounding of
      // f, or the curvature along d leaves none that rounding resolves.
      const double scale = std::max(1.0, std::abs(st.f));
      const bool tiny_step = t.first_predicted <= 1e-8 * scale;
      sum.converged = tiny_step || t.best_decrease <= kRoundingDecrease * scale;
      sum.message =
          sum.converged
              ? "No decrease measurable within rounding" +
                    (tiny_step ? std::string()
                               : " (at best " + FormatNumber(t.best_decrease) +
                                     " along the projected gradient, by its curvature)") +
                    ". |pg|_inf = " + FormatNumber(pg)
              : "Line search failed: no decrease along the projected gradient. |pg|_inf = " +
                    FormatNumber(pg);
      break;
    }
    retried = false;
    ++sum.iterations;
    const double change = t.f - st.f;
    double step = 0.0;
    for (size_t i = 0; i < st.x.size(); ++i) step = std::max(step, std::abs(t.x[i] - st.x[i]));
    Remember(&st, t.x, t.g, o.memory);
    const double f_old = st.f;
    st.x = t.x, st.g = t.g, st.f = t.f;
    if (callback) callback(sum.iterations, st.x, st.f, change);
    if (std::abs(change) <= o.function_tolerance * std::abs(f_old)) {
      sum.converged = true;
      sum.message = "Function tolerance reached. |df|/|f| = " +
                    FormatNumber(std::abs(change) / std::max(std::abs(f_old), 1e-300));
      break;
    }
    if (step <= o.parameter_tolerance * (MaxNorm(st.x) + o.parameter_tolerance)) {
      sum.converged = true;
      sum.message = "Parameter tolerance reached. |dx|_inf = " + FormatNumber(step);
      break;
    }
  }
  *x = st.x;
  sum.final_cost = st.f;
  return sum;
}

}  // namespace estlab
