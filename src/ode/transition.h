// Discrete transitions x(t1) = Phi(x(t0); t0, t1, u) of a continuous model,
// and their flow Jacobians dPhi/dx(t0). These are the process models of the
// filters and the truth generator of the simulator.
//
// Usage:
//   auto transition = MakeTransition<models::Pendulum>(params, options);
//   transition->SetInput(0.0);
//   Vec<double, 2> x1 = transition->Step(x0, 0.0, 0.01);
//   Mat<2, 2> F;
//   x1 = transition->StepWithJacobian(x0, 0.0, 0.01, &F);
//
// WARNING: a Transition is not thread-safe (CVODES keeps solver memory in the
// instance); make one per thread. Step throws NumericalError when the
// integrator fails (e.g. CVODES "too much work"); filters turn that into a
// status.
#ifndef ESTLAB_ODE_TRANSITION_H_
#define ESTLAB_ODE_TRANSITION_H_

#include <memory>
#include <string>

#include "models/model.h"
#include "src/core/types.h"
#include "src/ode/input_path.h"

namespace estlab {

// kDiscrete: the model's own step map (discrete-time models, and only those).
enum class Integrator { kEuler, kSemiImplicitEuler, kRk4, kCvodes, kDiscrete };
enum class CvodesMethod { kDefault, kBdf, kAdams };

// Parses "euler", "semi-implicit-euler", "rk4", "cvodes", "discrete"; throws
// InputError.
Integrator ParseIntegrator(const std::string& name);
const char* IntegratorName(Integrator integrator);

// "" when `integrator` can run a model that is (or is not) discrete-time,
// else the message saying why not: a discrete-time model takes kDiscrete
// only, a continuous one anything but kDiscrete.
std::string CheckIntegratorForModel(Integrator integrator, bool discrete_time,
                                    const std::string& model);

struct TransitionOptions {
  Integrator integrator = Integrator::kCvodes;
  // Fixed-step integrators: number of equal substeps per Step() call (for
  // kDiscrete: the model's map applied `substeps` times with dt / substeps).
  int substeps = 1;
  // CVODES settings. kDefault = BDF for stiff models, Adams otherwise.
  CvodesMethod method = CvodesMethod::kDefault;
  double rtol = 1e-10;
  double atol = 1e-12;
  long max_steps = 500000;
  // How recorded inputs are held between samples (src/ode/input_path.h).
  // The run loops and the simulator read it; a Transition follows the two
  // ends SetInput gives it.
  InputHold input_hold = InputHold::kZoh;

  bool IsValid(std::string* error) const;
};

struct TransitionStats {
  long rhs_evals = 0;       // right-hand side evaluations f(t, x)
  long jacobian_evals = 0;  // evaluations of df/dx (AD)
  long internal_steps = 0;  // integrator steps taken
};

template <DynamicModel Model>
class Transition {
 public:
  static constexpr int kN = Model::kStateDim;
  using State = Vec<double, kN>;
  using Jacobian = Mat<kN, kN>;
  using Params = typename Model::Params;

  explicit Transition(const Params& params) : params_(params) {}
  virtual ~Transition() = default;

  // x(t1) from x(t0) with the input SetInput gave (held, or its line).
  virtual State Step(const State& x, double t0, double t1) = 0;
  // Same, and *flow_jacobian = dx(t1)/dx(t0).
  virtual State StepWithJacobian(const State& x, double t0, double t1, Jacobian* flow_jacobian) = 0;
  virtual std::string Name() const = 0;

  // Step() for every column of `points` (kN x L), written to the same column
  // of *out (already L columns; not aliased with `points`). The same numbers
  // as L calls of Step(); the fixed-step transitions override it to loop
  // without a virtual call per point (sigma points, particles).
  using Points = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  virtual void StepPoints(const Points& points, double t0, double t1, Points* out) {
    for (Eigen::Index i = 0; i < points.cols(); ++i) out->col(i) = Step(points.col(i), t0, t1);
  }
  // StepPoints() for a particle cloud: the fixed-step transitions of a packet
  // model (src/core/packet.h) move kPacketWidth particles per model call.
  // The same numbers as StepPoints(), except with ESTLAB_VECTOR_MATH on,
  // where SLEEF's sin, cos and exp may move a column in the last bits. Not
  // for sigma points: a scaled UKF's weights (~1e6 for alpha = 1e-3) turn a
  // last-bit difference into 1e-8 in the covariance.
  virtual void StepCloud(const Points& points, double t0, double t1, Points* out) {
    StepPoints(points, t0, t1, out);
  }

  using Input = InputOf<Model>;  // double for models with at most one input
  // The input held over the next Step (and seen by h(x, u)).
  void SetInput(const Input& u) { input_ = input_end_ = u; }
  // The input at the next Step's start (u0) and end (u1): the Step follows
  // the line between them (linear hold; u1 = u0 is SetInput(u0)).
  void SetInput(const Input& u0, const Input& u1) {
    input_ = u0;
    input_end_ = u1;
  }
  // The input at the step's start (and of the measurement at that time).
  const Input& input() const { return input_; }
  const Params& params() const { return params_; }
  const TransitionStats& stats() const { return stats_; }

 protected:
  // The input over [t0, t1] (src/ode/input_path.h).
  InputPath<Model> Path(double t0, double t1) const {
    return InputPath<Model>(input_, input_end_, t0, t1);
  }

  Params params_;
  Input input_ = InputFrom<Model>(nullptr);
  Input input_end_ = InputFrom<Model>(nullptr);
  TransitionStats stats_;
};

// Factory defined in src/ode/transition_impl.h, instantiated per model.
template <class Model>
std::unique_ptr<Transition<Model>> MakeTransition(const typename Model::Params& params,
                                                  const TransitionOptions& options);

}  // namespace estlab

#endif  // ESTLAB_ODE_TRANSITION_H_
