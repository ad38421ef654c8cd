#include "adaptive/estimators.h"

#include <stdexcept>

#include "src/core/types.h"

namespace estlab {

namespace {

bool Differentiable(const FilterSpec& spec) { return InfoOf(spec.kind()).tunable; }
bool KfOrEkf(const FilterSpec& spec) {
  return spec.kind() == FilterKind::kKf || (spec.kind() == FilterKind::kEkf && !spec.iterated());
}
bool AnyFilter(const FilterSpec&) { return true; }

// The rows (help order). Keys of one estimator only: the `only` column of
// the tuner key table (src/options/tuner_settings.cpp).
const std::vector<EstimatorInfo> kEstimators = {
    {.id = Estimator::kMl,
     .name = "ml",
     .summary = "prediction-error maximum likelihood (the innovation NLL; --solver lbfgs | "
                "least-squares)",
     .default_max_iterations = 200,
     .noise = true,
     .params = true,
     .x0 = true,
     .multi_start = true,
     .burn_in = true,
     .tuner = true,
     .in_studies = true,
     .accepts = Differentiable,
     .filters = "the kf, ekf, iekf, ukf, ckf and ghkf"},
    {.id = Estimator::kEm,
     .name = "em",
     .summary = "expectation-maximisation, the smoother as E-step (Q, R and x0)",
     .default_max_iterations = 1000,
     .noise = true,
     .params = false,
     .x0 = true,
     .multi_start = false,
     .burn_in = false,
     .tuner = true,
     .in_studies = true,
     .accepts = Differentiable,
     .filters = "the kf, ekf, iekf, ukf, ckf and ghkf"},
    {.id = Estimator::kAls,
     .name = "als",
     .summary = "autocovariance least squares (Q and R; kf, ekf)",
     .default_max_iterations = 200,
     .noise = true,
     .params = false,
     .x0 = false,
     .multi_start = false,
     .burn_in = true,
     .tuner = true,
     .in_studies = true,
     .accepts = KfOrEkf,
     .filters = "the kf and the ekf (linearised along its own estimates)"},
    {.id = Estimator::kOutputError,
     .name = "output-error",
     .summary = "free simulation against the measurements, least squares (parameters, x0)",
     .default_max_iterations = 200,
     .noise = false,
     .params = true,
     .x0 = true,
     .multi_start = false,
     .burn_in = true,  // the validation's filter runs
     .tuner = false,
     .in_studies = false,
     .accepts = AnyFilter,
     .filters = "no filter (a free simulation)"},
};

}  // namespace

const std::vector<EstimatorInfo>& Estimators() { return kEstimators; }

const EstimatorInfo& InfoOf(Estimator estimator) {
  for (const EstimatorInfo& e : kEstimators)
    if (e.id == estimator) return e;
  throw std::logic_error("estimator without a row in kEstimators");
}

const char* EstimatorName(Estimator estimator) { return InfoOf(estimator).name; }

std::string EstimatorNames(const std::string& joiner, const std::string& last, bool studies_only) {
  std::vector<std::string> names;
  for (const EstimatorInfo& e : kEstimators)
    if (!studies_only || e.in_studies) names.push_back(e.name);
  std::string out;
  for (size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? last : joiner) + names[i];
  return out;
}

Estimator ParseEstimator(const std::string& name, const std::string& key, bool studies_only) {
  for (const EstimatorInfo& e : kEstimators)
    if (name == e.name && (!studies_only || e.in_studies)) return e.id;
  throw InputError(key + ": expected " + EstimatorNames(", ", " or ", studies_only) + ", got '" +
                   name + "'");
}

MlSolver ParseMlSolver(const std::string& name, const std::string& key) {
  if (name == "lbfgs") return MlSolver::kLbfgs;
  if (name == "least-squares") return MlSolver::kLeastSquares;
  throw InputError(key + ": expected lbfgs or least-squares, got '" + name + "'");
}

const char* MlSolverName(MlSolver solver) {
  switch (solver) {
    case MlSolver::kLbfgs:
      return "lbfgs";
    case MlSolver::kLeastSquares:
      return "least-squares";
  }
  return "?";
}

}  // namespace estlab
