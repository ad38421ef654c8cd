// Template definitions behind MakeTransition. Include only from the
// per-model instantiation units (generated from models/model_list.cmake) and tests.
#ifndef ESTLAB_ODE_TRANSITION_IMPL_H_
#define ESTLAB_ODE_TRANSITION_IMPL_H_

#include <memory>
#include <string>

#include "src/ode/autodiff.h"
#include "src/ode/cvodes.h"
#include "src/ode/fixed_step.h"
#include "src/ode/packet_propagate.h"
#include "src/ode/transition.h"

namespace estlab {

// Euler, semi-implicit Euler or RK4 with `substeps` equal steps per call (or
// a discrete-time model's own map); the flow Jacobian is the exact derivative
// of the discrete map (AD through the steps), not of the continuous flow.
template <class Model>
class FixedStepTransition final : public Transition<Model> {
 public:
  static constexpr int kN = Model::kStateDim;
  using Base = Transition<Model>;
  using typename Base::Jacobian;
  using typename Base::Params;
  using typename Base::State;

  FixedStepTransition(const Params& params, const TransitionOptions& options)
      : Base(params), scheme_(options.integrator), substeps_(options.substeps) {}

  State Step(const State& x, double t0, double t1) override {
    Count(false);
    return FixedPropagate<Model, double>(scheme_, x, t0, t1, substeps_, this->Path(t0, t1),
                                         this->params_);
  }
  State StepWithJacobian(const State& x, double t0, double t1, Jacobian* F) override {
    Count(true);
    const InputPath<Model> u = this->Path(t0, t1);
    const Params& p = this->params_;
    return ValueAndJacobian<kN, kN>(
        [&](const auto& xj) {
          using T = typename std::decay_t<decltype(xj)>::Scalar;
          return FixedPropagate<Model, T>(scheme_, xj, t0, t1, substeps_, u, p);
        },
        x, F);
  }
  using typename Base::Points;
  // Sigma points one scalar call each: packets of 2 gave the same bits but
  // more instructions for a UKF's 5 or 9 points (the padded lane of the
  // last packet, gather and scatter; issue 39, docs/performance.md).
  void StepPoints(const Points& points, double t0, double t1, Points* out) override {
    const Eigen::Index count = points.cols();
    CountPoints(count);
    const InputPath<Model> u = this->Path(t0, t1);
    const Params& p = this->params_;
    for (Eigen::Index i = 0; i < count; ++i)
      out->col(i) =
          FixedPropagate<Model, double>(scheme_, State(points.col(i)), t0, t1, substeps_, u, p);
  }
  void StepCloud(const Points& points, double t0, double t1, Points* out) override {
    if constexpr (kPacketModel<Model>) {
      CountPoints(points.cols());
      FixedPropagatePoints<Model>(scheme_, points, t0, t1, substeps_, this->Path(t0, t1),
                                  this->params_,
                                  out);  // kPacketWidth points per model call
    } else {
      StepPoints(points, t0, t1, out);
    }
  }
  std::string Name() const override { return IntegratorName(scheme_); }

 private:
  void Count(bool jacobian) {
    this->stats_.internal_steps += substeps_;
    this->stats_.rhs_evals += long(substeps_) * RhsEvalsPerStep(scheme_);
    if (jacobian) this->stats_.jacobian_evals += long(substeps_) * RhsEvalsPerStep(scheme_);
  }
  void CountPoints(Eigen::Index count) {
    this->stats_.internal_steps += long(substeps_) * count;
    this->stats_.rhs_evals += long(substeps_) * RhsEvalsPerStep(scheme_) * count;
  }
  Integrator scheme_;
  int substeps_;
};

template <class Model>
std::unique_ptr<Transition<Model>> MakeTransition(const typename Model::Params& params,
                                                  const TransitionOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError(error);
  error = CheckIntegratorForModel(options.integrator, kDiscreteTime<Model>, Model::kName);
  if (!error.empty()) throw InputError(error);
  if constexpr (!kDiscreteTime<Model>) {
    if (options.integrator == Integrator::kCvodes)
      return std::make_unique<CvodesTransition<Model>>(params, options);
  }
  return std::make_unique<FixedStepTransition<Model>>(params, options);
}

}  // namespace estlab

#endif  // ESTLAB_ODE_TRANSITION_IMPL_H_
