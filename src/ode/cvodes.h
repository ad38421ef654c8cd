// CVODES transition: SUNDIALS CVODES (BDF or Adams, Newton iteration with a
// dense linear solver and the exact AD Jacobian df/dx) with forward
// sensitivities s_j = dx(t)/dx_j(t0), s_j' = (df/dx) s_j, s_j(t0) = e_j, so
// one call gives both x(t1) and the flow Jacobian dx(t1)/dx(t0).
//
// Usage:
//   CvodesTransition<models::DoublePendulum> cv(params, options);
//   Mat<4, 4> F;
//   Vec<double, 4> x1 = cv.StepWithJacobian(x0, 0.0, 0.01, &F);
//
// Non-stiff models with Adams (the default for them) use the fixed-point
// nonlinear solver (state and simultaneous sensitivity corrector): no
// Jacobian factorisations; stiff models, and Adams forced on a stiff model,
// keep Newton with the dense solver.
//
// One solver (src/ode/cvodes_solver.h) per instance, created on the first
// call and reused with CVodeReInit / CVodeSensReInit; the nonlinear solvers
// and sensitivity vectors are created once too, so a step allocates nothing
// of its own. A Step() that starts where the previous one ended (same time,
// same state, no sensitivities, the same held input) continues the
// integration without re-initialising, so a truth trajectory keeps CVODES'
// step size and order history. A fresh start stops exactly at t1; a
// continuing step lets CVODES step past t1 and interpolate (see Integrate).
// The input follows the path SetInput gave (src/ode/input_path.h): held, or
// the line between the samples, whose kinks are where a step restarts.
//
// WARNING: not thread-safe; one instance per thread. Callbacks never throw:
// a non-finite right-hand side returns 1 (recoverable, CVODES retries with a
// smaller step); a CVODES failure throws NumericalError from Step().
#ifndef ESTLAB_ODE_CVODES_H_
#define ESTLAB_ODE_CVODES_H_

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "src/ode/autodiff.h"
#include "src/ode/cvodes_solver.h"
#include "src/ode/input_path.h"
#include "src/ode/transition.h"

namespace estlab {

template <class Model>
class CvodesTransition final : public Transition<Model> {
 public:
  static constexpr int kN = Model::kStateDim;
  using Base = Transition<Model>;
  using typename Base::Jacobian;
  using typename Base::Params;
  using typename Base::State;

  CvodesTransition(const Params& params, const TransitionOptions& options)
      : Base(params), options_(options) {
    use_bdf_ = options.method == CvodesMethod::kBdf ||
               (options.method == CvodesMethod::kDefault && Model::kStiff);
    fixed_point_ = !use_bdf_ && !Model::kStiff;
  }
  ~CvodesTransition() override = default;
  CvodesTransition(const CvodesTransition&) = delete;
  CvodesTransition& operator=(const CvodesTransition&) = delete;

  State Step(const State& x, double t0, double t1) override {
    return Integrate(x, t0, t1, nullptr);
  }
  State StepWithJacobian(const State& x, double t0, double t1, Jacobian* F) override {
    return Integrate(x, t0, t1, F);
  }
  std::string Name() const override { return use_bdf_ ? "cvodes-bdf" : "cvodes-adams"; }

 private:
  State Integrate(const State& x, double t0, double t1, Jacobian* F) {
    if (!solver_.built()) Create(t0);
    void* const mem = solver_.mem();
    const N_Vector y = solver_.y();
    N_Vector* const yS = solver_.yS();
    const bool want_sens = F != nullptr;
    // The input over this step: held, or the line of a linear hold. A step
    // that starts at an input sample restarts the integrator there unless
    // the input is the one held before: the input's kinks are where the
    // integrator stops, never points it steps over.
    path_ = this->Path(t0, t1);
    const bool continuing = !want_sens && !sens_on_ && have_last_ && t0 == last_t1_ &&
                            x == last_x_ && !path_.ramp && !last_ramp_ &&
                            this->input_ == last_input_;
    if (!continuing) {
      Copy(x, y);
      Check(CVodeReInit(mem, t0, y), "CVodeReInit");
      // Warm start: the first step CVODES took after the previous restart
      // (accepted at order 1, where every restart begins) rather than the
      // last step of the previous interval, which was sized for a higher
      // order and fails the order-1 error test (double pendulum, rtol 1e-8,
      // dt 0.01: 22 instead of 36 right-hand sides per step).
      if (last_h0_ > 0)
        Check(CVodeSetInitStep(mem, std::min(last_h0_, std::abs(t1 - t0))), "CVodeSetInitStep");
      if (want_sens) {
        for (int j = 0; j < kN; ++j) {
          N_VConst(0.0, yS[j]);
          NV_Ith_S(yS[j], j) = 1.0;
        }
        if (!sens_created_) {
          try {
            solver_.StartSensitivities(&SensRhs);
          } catch (...) {
            solver_.Free();  // half made: the next call builds it again
            throw;
          }
          sens_created_ = true;
        } else {
          Check(CVodeSensReInit(mem, CV_SIMULTANEOUS, yS), "CVodeSensReInit");
        }
        sens_on_ = true;
      } else if (sens_on_) {
        Check(CVodeSensToggleOff(mem), "CVodeSensToggleOff");
        sens_on_ = false;
      }
    }
    // A continuing step has no stop time: forcing an internal step to end at
    // every output time disturbs the high-order Adams error estimator (double
    // pendulum, rtol 1e-10, outputs every 0.01 s for 20 s: energy drift 3e-8
    // and 7765 steps with a stop time at every t1, 2e-9 and 4590 steps
    // without). Stepping past t1 is safe because continuing requires an
    // unchanged, held input. "No stop time" is a stop time at +max: SUNDIALS 6.4
    // has no CVodeClearStopTime and leaves a stop time equal to tout set
    // after CV_NORMAL returns there (fixed in 6.6.1).
    Check(CVodeSetStopTime(mem, continuing ? std::numeric_limits<double>::max() : t1),
          "CVodeSetStopTime");
    solver_.ClearError();
    sunrealtype t_reached = t0;
    const long steps_before = solver_.NumSteps();
    const int flag = CVode(mem, t1, y, &t_reached, CV_NORMAL);
    this->stats_.internal_steps += solver_.NumSteps() - steps_before;
    if (flag < 0) {
      have_last_ = false;
      solver_.Fail(flag, "CVODES", t0, t1, t_reached);
    }
    State x1 = Load(y);
    if (want_sens) {
      Check(CVodeGetSens(mem, &t_reached, yS), "CVodeGetSens");
      for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) (*F)(i, j) = NV_Ith_S(yS[j], i);
    }
    sunrealtype h = 0;
    if (CVodeGetLastStep(mem, &h) == CV_SUCCESS && h > 0) last_h_ = h;
    if (!continuing && CVodeGetActualInitStep(mem, &h) == CV_SUCCESS && h > 0) last_h0_ = h;
    last_t1_ = t1;
    last_x_ = x1;
    last_input_ = this->input_;
    last_ramp_ = path_.ramp;
    have_last_ = true;
    return x1;
  }

  // The solver, with the state's sensitivity vectors cloned for the flow
  // Jacobian (initialised on the first StepWithJacobian).
  void Create(double t0) {
    CvodesSetup setup;
    setup.size = kN;
    setup.bdf = use_bdf_;
    setup.fixed_point = fixed_point_;
    setup.rtol = options_.rtol;
    setup.atol = options_.atol;
    setup.max_steps = options_.max_steps;
    setup.rhs = &Rhs;
    setup.user_data = this;
    setup.jacobian = &JacobianFn;
    setup.sensitivities = kN;
    setup.fused_ops = true;
    sens_created_ = sens_on_ = have_last_ = false;
    solver_.Build(setup, t0);
  }

  static void Copy(const State& x, N_Vector v) {
    for (int i = 0; i < kN; ++i) NV_Ith_S(v, i) = x(i);
  }
  static State Load(N_Vector v) {
    State x;
    for (int i = 0; i < kN; ++i) x(i) = NV_Ith_S(v, i);
    return x;
  }

  static void Check(int flag, const char* call) { CvodesSolver::Check(flag, call); }

  // df/dx at (t, y) by forward-mode AD.
  Jacobian EvalJacobian(double t, const State& x) {
    ++this->stats_.jacobian_evals;
    Jacobian J;
    const InputOf<Model> u = path_.At(t);
    const Params& p = this->params_;
    ValueAndJacobian<kN, kN>(
        [&](const auto& xj) {
          using J_t = typename std::decay_t<decltype(xj)>::Scalar;
          return Model::Rhs(J_t(t), xj, u, p);
        },
        x, &J);
    return J;
  }

  static int Rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<CvodesTransition*>(user_data);
    ++self->stats_.rhs_evals;
    const State f = Model::Rhs(double(t), Load(y), self->path_.At(t), self->params_);
    if (!f.allFinite()) return 1;  // recoverable: CVODES retries with a smaller step
    Copy(f, ydot);
    return 0;
  }

  static int JacobianFn(sunrealtype t, N_Vector y, N_Vector /*fy*/, SUNMatrix J, void* user_data,
                        N_Vector, N_Vector, N_Vector) {
    auto* self = static_cast<CvodesTransition*>(user_data);
    const Jacobian jac = self->EvalJacobian(t, Load(y));
    if (!jac.allFinite()) return 1;
    for (int j = 0; j < kN; ++j)
      for (int i = 0; i < kN; ++i) SM_ELEMENT_D(J, i, j) = jac(i, j);
    return 0;
  }

  // s_j' = (df/dx)(t, y) s_j for all j at once (one Jacobian per call).
  static int SensRhs(int ns, sunrealtype t, N_Vector y, N_Vector /*ydot*/, N_Vector* yS,
                     N_Vector* ySdot, void* user_data, N_Vector, N_Vector) {
    auto* self = static_cast<CvodesTransition*>(user_data);
    const Jacobian jac = self->EvalJacobian(t, Load(y));
    if (!jac.allFinite()) return 1;
    for (int j = 0; j < ns; ++j) Copy(jac * Load(yS[j]), ySdot[j]);
    return 0;
  }

  TransitionOptions options_;
  bool use_bdf_ = false;
  bool fixed_point_ = false;
  CvodesSolver solver_;
  bool sens_created_ = false;
  bool sens_on_ = false;
  bool have_last_ = false;
  double last_t1_ = 0.0;
  double last_h_ = 0.0;
  double last_h0_ = 0.0;
  InputOf<Model> last_input_ = InputFrom<Model>(nullptr);
  bool last_ramp_ = false;
  InputPath<Model> path_;  // the input over the running step
  State last_x_ = State::Zero();
};

}  // namespace estlab

#endif  // ESTLAB_ODE_CVODES_H_
