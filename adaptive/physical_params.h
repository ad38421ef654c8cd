// The physical parameters that the innovation likelihood estimates together
// with Q and R (TunerOptions::estimate): their slice of theta, its names,
// start and bounds, the model parameters of scalar T at a theta, and the
// priors' NLL terms.
//
//   theta_j = log p_i   when p_i is constrained > 0 (so p_i stays positive)
//   theta_j = p_i       otherwise (a >= 0 constraint becomes the bound 0)
//   prior:  NLL += 1/2 ((p_i - mean) / sd)^2
//
// The model's parameters must be generic over the scalar
// (models/model_params.h); the others reach the physical parameters' AD only
// as a clear InputError.
//
// Usage (inside InnovationLikelihood):
//   PhysicalParams<Model> phys(options.estimate, spec.params);
//   auto p = phys.template At<T>(theta + q_count + r_count);  // ParamsT<T>
#ifndef ESTLAB_ADAPTIVE_PHYSICAL_PARAMS_H_
#define ESTLAB_ADAPTIVE_PHYSICAL_PARAMS_H_

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "adaptive/tuner.h"
#include "models/model_params.h"
#include "models/model_traits.h"
#include "src/core/params.h"
#include "src/core/types.h"

namespace estlab {

template <class Model>
class PhysicalParams {
 public:
  static constexpr std::size_t kCount = Model::kParams.size();

  // Throws InputError for an unknown or repeated name, a model whose
  // parameters are not generic, bad bounds or a bad prior.
  PhysicalParams(const std::vector<EstimatedParam>& estimate, const std::vector<double>& values)
      : nominal_(ParamsFromVector<Model>(values)) {
    if (estimate.empty()) return;
    if constexpr (!EstimableParams<Model>) {
      throw InputError(std::string("model '") + Model::kName +
                       "' does not declare its parameters generic over the scalar "
                       "(ParamsT, models/model_params.h), so --estimate-param cannot "
                       "differentiate through them");
    } else {
      if (!ParamOrderMatches<Model>())
        throw InputError(std::string("model '") + Model::kName +
                         "': the fields of Params are not in the order of kParams");
      for (const EstimatedParam& e : estimate) Add(e);
    }
  }

  int NumParams() const { return int(index_.size()); }
  bool empty() const { return index_.empty(); }
  const std::vector<EstimatedParam>& estimated() const { return given_; }
  // Index into Model::kParams of the j-th estimated parameter.
  int ModelIndex(int j) const { return index_[j]; }
  bool IsLog(int j) const { return is_log_[j]; }

  std::vector<double> InitialTheta() const {
    std::vector<double> theta;
    for (int j = 0; j < NumParams(); ++j) {
      const double v = Nominal(index_[j]);
      theta.push_back(is_log_[j] ? std::log(v) : v);
    }
    return theta;
  }
  std::vector<std::string> Names() const {
    std::vector<std::string> out;
    for (int j = 0; j < NumParams(); ++j)
      out.push_back((is_log_[j] ? "log " : "") + std::string(Model::kParams[index_[j]].name));
    return out;
  }
  // The natural-scale value of theta_j.
  double Natural(int j, double theta_j) const { return is_log_[j] ? std::exp(theta_j) : theta_j; }

  // Bounds of the slice on the theta scale: the user's (natural scale,
  // mapped), else >= 0 -> [0, inf) and log p -> initial +- bound_width.
  void Bounds(double bound_width, std::vector<double>* lower, std::vector<double>* upper) const {
    const std::vector<double> theta0 = InitialTheta();
    const double inf = std::numeric_limits<double>::infinity();
    for (int j = 0; j < NumParams(); ++j) {
      const EstimatedParam& e = given_[j];
      double lo = -inf, hi = inf;
      if (is_log_[j]) {
        lo = std::isnan(e.lower) ? theta0[j] - bound_width : std::log(e.lower);
        hi = std::isnan(e.upper) ? theta0[j] + bound_width : std::log(e.upper);
      } else {
        const bool non_negative = Model::kParams[index_[j]].constraint == Constraint::kNonNegative;
        lo = std::isnan(e.lower) ? (non_negative ? 0.0 : -inf) : e.lower;
        hi = std::isnan(e.upper) ? inf : e.upper;
      }
      lower->push_back(lo);
      upper->push_back(hi);
    }
  }

  // The model's parameters at theta (the slice), of scalar T.
  template <class T>
  auto At(const T* theta) const {
    std::array<T, kCount> v;
    for (std::size_t i = 0; i < kCount; ++i) v[i] = T(Nominal(int(i)));
    for (int j = 0; j < NumParams(); ++j) {
      using std::exp;
      v[index_[j]] = is_log_[j] ? exp(theta[j]) : theta[j];
    }
    return MakeParams<Model, T>(v);
  }

  // sum of the priors' NLL terms at theta (the slice); calls
  // residual(r_j) with r_j = (p_j - mean) / sd for each prior when given.
  template <class T, class F>
  void ForEachPriorResidual(const T* theta, F&& residual) const {
    for (int j = 0; j < NumParams(); ++j) {
      const EstimatedParam& e = given_[j];
      if (!e.has_prior) continue;
      using std::exp;
      const T p = is_log_[j] ? exp(theta[j]) : theta[j];
      residual((p - e.prior_mean) / e.prior_sd);
    }
  }
  int NumPriors() const {
    int n = 0;
    for (const EstimatedParam& e : given_) n += e.has_prior;
    return n;
  }

 private:
  double Nominal(int i) const { return nominal_.*(Model::kParams[i].member); }

  void Add(const EstimatedParam& e) {
    int found = -1;
    std::string known;
    for (std::size_t i = 0; i < kCount; ++i) {
      known += (i ? ", " : "") + std::string(Model::kParams[i].name);
      if (e.name == Model::kParams[i].name) found = int(i);
    }
    if (found < 0)
      throw InputError("--estimate-param: model '" + std::string(Model::kName) +
                       "' has no parameter '" + e.name + "' (it has " + known + ")");
    for (int i : index_)
      if (i == found) throw InputError("--estimate-param: '" + e.name + "' is named twice");
    const Constraint c = Model::kParams[found].constraint;
    const double v = Nominal(found);
    const bool log = c == Constraint::kPositive;
    if (log && !(v > 0))
      throw InputError("--estimate-param: the initial " + e.name + " must be > 0, got " +
                       FormatNumber(v));
    auto check_bound = [&](double b, const char* which) {
      if (std::isnan(b)) return;
      if (!std::isfinite(b) || (log && !(b > 0)) || (c == Constraint::kNonNegative && b < 0))
        throw InputError("--param-bounds: the " + std::string(which) + " bound of " + e.name +
                         " must be finite and " + ConstraintText(c) + ", got " + FormatNumber(b));
    };
    check_bound(e.lower, "lower");
    check_bound(e.upper, "upper");
    if (!std::isnan(e.lower) && !std::isnan(e.upper) && !(e.lower < e.upper))
      throw InputError("--param-bounds: " + e.name + "'s lower bound " + FormatNumber(e.lower) +
                       " is not below its upper bound " + FormatNumber(e.upper));
    if ((!std::isnan(e.lower) && v < e.lower) || (!std::isnan(e.upper) && v > e.upper))
      throw InputError("--param-bounds: the initial " + e.name + " = " + FormatNumber(v) +
                       " is outside its bounds");
    if (e.has_prior &&
        !(e.prior_sd > 0 && std::isfinite(e.prior_sd) && std::isfinite(e.prior_mean)))
      throw InputError("--param-prior: " + e.name + " needs a finite mean and sd > 0");
    index_.push_back(found);
    is_log_.push_back(log);
    given_.push_back(e);
  }

  typename Model::Params nominal_;
  std::vector<int> index_;
  std::vector<bool> is_log_;
  std::vector<EstimatedParam> given_;
};

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_PHYSICAL_PARAMS_H_
