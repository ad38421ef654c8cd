#include "studies/run/study_identification.h"

#include <chrono>
#include <cmath>
#include <exception>

namespace estlab {

double RelativeFrobeniusError(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.empty() || a.size() != b.size()) return std::numeric_limits<double>::quiet_NaN();
  double diff = 0.0, norm = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    diff += (a[i] - b[i]) * (a[i] - b[i]);
    norm += b[i] * b[i];
  }
  return norm > 0.0 ? std::sqrt(diff / norm) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> DiagonalRatios(const std::vector<double>& a, const std::vector<double>& b) {
  const size_t n = size_t(std::lround(std::sqrt(double(b.size()))));
  std::vector<double> out(n, std::numeric_limits<double>::quiet_NaN());
  if (a.size() != b.size() || n * n != b.size()) return out;
  for (size_t i = 0; i < n; ++i)
    if (b[i * n + i] != 0.0) out[i] = a[i * n + i] / b[i * n + i];
  return out;
}

RunIdentification IdentifyInRun(const ScenarioConfig& sc, const Combo& combo,
                                const FilterData& data, uint64_t seed) {
  RunIdentification id;
  id.attempted = true;
  TunerOptions options = combo.tuner;
  options.seed = seed;
  options.compute_std_errors = false;  // a Hessian per run, and nothing here uses it
  const auto t0 = std::chrono::steady_clock::now();
  TuneResult r;
  try {
    r = sc.model->tune(combo.spec, options, {data});
    if (!r.IsSolutionUsable()) id.failure = "tuning failed: " + r.message;
  } catch (const std::exception& e) {
    id.failure = std::string("tuning failed: ") + e.what();
  }
  id.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!id.failure.empty()) return id;
  id.spec = r.tuned_spec;
  id.iterations = r.iterations;
  id.converged = r.status == TuneStatus::kConverged;
  for (bool b : r.at_bound) id.at_bound = id.at_bound || b;
  if (options.q_param != NoiseParam::kFixed) {
    id.q_err = RelativeFrobeniusError(r.q, sc.oracle_q);
    id.q_ratio = DiagonalRatios(r.q, sc.oracle_q);
  }
  if (r.r_param != NoiseParam::kFixed) {  // the tuned kind: groups all fixed are fixed
    id.r_err = RelativeFrobeniusError(r.r, sc.oracle_r);
    id.r_ratio = DiagonalRatios(r.r, sc.oracle_r);
  }
  return id;
}

}  // namespace estlab
