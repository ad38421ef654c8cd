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
//   PhysicalParams<Model> phys(options.estimate, spec.params, options.bound_width);
//   auto p = phys.template At<T>(theta + q_count + r_count);  // ParamsT<T>
#ifndef ESTLAB_ADAPTIVE_PHYSICAL_PARAMS_H_
#define ESTLAB_ADAPTIVE_PHYSICAL_PARAMS_H_

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "adaptive/theta_scale.h"
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
  PhysicalParams(const std::vector<EstimatedParam>& estimate, const std::vector<double>& values,
                 [[maybe_unused]] double bound_width)
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
      for (const EstimatedParam& e : estimate) Add(e, bound_width);
    }
  }

  int NumParams() const { return int(index_.size()); }
  bool empty() const { return index_.empty(); }
  const std::vector<EstimatedParam>& estimated() const { return given_; }
  // Index into Model::kParams of the j-th estimated parameter.
  int ModelIndex(int j) const { return index_[j]; }
  bool IsLog(int j) const { return scale_[j].is_log; }

  std::vector<double> InitialTheta() const {
    std::vector<double> theta;
    for (const ThetaScale& s : scale_) theta.push_back(s.theta0);
    return theta;
  }
  std::vector<std::string> Names() const {
    std::vector<std::string> out;
    for (int j = 0; j < NumParams(); ++j)
      out.push_back((IsLog(j) ? "log " : "") + std::string(Model::kParams[index_[j]].name));
    return out;
  }
  // The natural-scale value of theta_j.
  double Natural(int j, double theta_j) const { return scale_[j].Natural(theta_j); }

  // Bounds of the slice on the theta scale (theta_scale.h).
  void Bounds(std::vector<double>* lower, std::vector<double>* upper) const {
    for (const ThetaScale& s : scale_) {
      lower->push_back(s.lower);
      upper->push_back(s.upper);
    }
  }

  // The model's parameters at theta (the slice), of scalar T.
  template <class T>
  auto At(const T* theta) const {
    std::array<T, kCount> v;
    for (std::size_t i = 0; i < kCount; ++i) v[i] = T(Nominal(int(i)));
    for (int j = 0; j < NumParams(); ++j) {
      using std::exp;
      v[index_[j]] = IsLog(j) ? exp(theta[j]) : theta[j];
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
      const T p = IsLog(j) ? exp(theta[j]) : theta[j];
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

  void Add(const EstimatedParam& e, double bound_width) {
    std::vector<std::string> names;
    for (const auto& spec : Model::kParams) names.push_back(spec.name);
    const int found = FindEstimatedParam(e.name, names, Model::kName);
    for (int i : index_)
      if (i == found) throw InputError("--estimate-param: '" + e.name + "' is named twice");
    scale_.push_back(
        ResolveThetaScale(e, Model::kParams[found].constraint, Nominal(found), bound_width));
    index_.push_back(found);
    given_.push_back(e);
  }

  typename Model::Params nominal_;
  std::vector<int> index_;
  std::vector<ThetaScale> scale_;
  std::vector<EstimatedParam> given_;
};

}  // namespace estlab

#endif  // ESTLAB_ADAPTIVE_PHYSICAL_PARAMS_H_
