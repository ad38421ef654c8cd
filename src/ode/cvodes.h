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
// One solver memory per instance, created on the first call and reused with
// CVodeReInit / CVodeSensReInit; the nonlinear solvers and sensitivity
// vectors are created once too, so a step allocates nothing of its own. A
// Step() that starts where the previous one ended (same time, same state, no
// sensitivities) continues the integration without re-initialising, so a
// truth trajectory keeps CVODES' step size and order history. A fresh start stops exactly at t1; a
// continuing step lets CVODES step past t1 and interpolate (see Integrate).
//
// WARNING: not thread-safe; one instance per thread. Callbacks never throw:
// a non-finite right-hand side returns 1 (recoverable, CVODES retries with a
// smaller step); a CVODES failure throws NumericalError from Step().
#ifndef ESTLAB_ODE_CVODES_H_
#define ESTLAB_ODE_CVODES_H_

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string>

#include "src/ode/autodiff.h"
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
  ~CvodesTransition() override { Free(); }
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
    if (mem_ == nullptr) Create(x, t0);
    const bool want_sens = F != nullptr;
    const bool continuing = !want_sens && !sens_on_ && have_last_ && t0 == last_t1_ &&
                            x == last_x_ && this->input_ == last_input_;
    if (!continuing) {
      Copy(x, y_);
      if (initialised_) {
        Check(CVodeReInit(mem_, t0, y_), "CVodeReInit");
      }
      initialised_ = true;
      // Warm start: the first step CVODES took after the previous restart
      // (accepted at order 1, where every restart begins) rather than the
      // last step of the previous interval, which was sized for a higher
      // order and fails the order-1 error test (double pendulum, rtol 1e-8,
      // dt 0.01: 22 instead of 36 right-hand sides per step).
      if (last_h0_ > 0)
        Check(CVodeSetInitStep(mem_, std::min(last_h0_, std::abs(t1 - t0))), "CVodeSetInitStep");
      if (want_sens) {
        for (int j = 0; j < kN; ++j) {
          N_VConst(0.0, yS_[j]);
          NV_Ith_S(yS_[j], j) = 1.0;
        }
        if (!sens_created_) {
          Check(CVodeSensInit(mem_, kN, CV_SIMULTANEOUS, &SensRhs, yS_), "CVodeSensInit");
          Check(CVodeSensEEtolerances(mem_), "CVodeSensEEtolerances");
          Check(CVodeSetSensErrCon(mem_, SUNTRUE), "CVodeSetSensErrCon");
          if (fixed_point_) {
            nls_sens_ = SUNNonlinSol_FixedPointSens(kN + 1, y_, 0, ctx_);
            if (nls_sens_ == nullptr) throw NumericalError("SUNNonlinSol_FixedPointSens failed");
            Check(CVodeSetNonlinearSolverSensSim(mem_, nls_sens_),
                  "CVodeSetNonlinearSolverSensSim");
          }
          sens_created_ = true;
        } else {
          Check(CVodeSensReInit(mem_, CV_SIMULTANEOUS, yS_), "CVodeSensReInit");
        }
        sens_on_ = true;
      } else if (sens_on_) {
        Check(CVodeSensToggleOff(mem_), "CVodeSensToggleOff");
        sens_on_ = false;
      }
    }
    // A continuing step has no stop time: forcing an internal step to end at
    // every output time disturbs the high-order Adams error estimator (double
    // pendulum, rtol 1e-10, outputs every 0.01 s for 20 s: energy drift 3e-8
    // and 7765 steps with a stop time at every t1, 2e-9 and 4590 steps
    // without). Stepping past t1 is safe because continuing requires an
    // unchanged input. "No stop time" is a stop time at +max: SUNDIALS 6.4
    // has no CVodeClearStopTime and leaves a stop time equal to tout set
    // after CV_NORMAL returns there (fixed in 6.6.1).
    Check(CVodeSetStopTime(mem_, continuing ? std::numeric_limits<double>::max() : t1),
          "CVodeSetStopTime");
    callback_error_.clear();
    sunrealtype t_reached = t0;
    const long steps_before = NumSteps();
    const int flag = CVode(mem_, t1, y_, &t_reached, CV_NORMAL);
    this->stats_.internal_steps += NumSteps() - steps_before;
    if (flag < 0) {
      have_last_ = false;
      std::ostringstream msg;
      msg << "CVODES failed at t = " << t_reached << " while stepping from t = " << t0
          << " to t = " << t1 << ": ";
      // CVodeGetReturnFlagName returns a malloc'd string that the caller frees.
      char* flag_name = CVodeGetReturnFlagName(flag);
      msg << (flag_name != nullptr ? flag_name : "unknown CVODES flag");
      std::free(flag_name);
      if (!callback_error_.empty()) msg << " (" << callback_error_ << ")";
      throw NumericalError(msg.str());
    }
    State x1;
    for (int i = 0; i < kN; ++i) x1(i) = NV_Ith_S(y_, i);
    if (want_sens) {
      Check(CVodeGetSens(mem_, &t_reached, yS_), "CVodeGetSens");
      for (int j = 0; j < kN; ++j)
        for (int i = 0; i < kN; ++i) (*F)(i, j) = NV_Ith_S(yS_[j], i);
    }
    sunrealtype h = 0;
    if (CVodeGetLastStep(mem_, &h) == CV_SUCCESS && h > 0) last_h_ = h;
    if (!continuing && CVodeGetActualInitStep(mem_, &h) == CV_SUCCESS && h > 0) last_h0_ = h;
    last_t1_ = t1;
    last_x_ = x1;
    last_input_ = this->input_;
    have_last_ = true;
    return x1;
  }

  long NumSteps() const {
    long n = 0;
    CVodeGetNumSteps(mem_, &n);
    return n;
  }

  // Builds the solver, or throws with nothing of it kept: a half-made solver
  // (mem_ set, yS_ not) would be taken for a whole one by the next step.
  void Create(const State& x, double t0) {
    Free();
    try {
      Build(x, t0);
    } catch (...) {
      Free();
      throw;
    }
  }

  void Build(const State& x, double t0) {
    Check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
    y_ = N_VNew_Serial(kN, ctx_);
    if (y_ == nullptr) throw NumericalError("N_VNew_Serial failed");
    // Fused vector operations (one call for a linear combination of many
    // vectors, as the sensitivity corrector and the Nordsieck update need):
    // off by default in SUNDIALS; the clones CVODES makes inherit them.
    Check(N_VEnableFusedOps_Serial(y_, SUNTRUE), "N_VEnableFusedOps_Serial");
    Copy(x, y_);
    mem_ = CVodeCreate(use_bdf_ ? CV_BDF : CV_ADAMS, ctx_);
    if (mem_ == nullptr) throw NumericalError("CVodeCreate failed");
    Check(CVodeInit(mem_, &Rhs, t0, y_), "CVodeInit");
    Check(CVodeSStolerances(mem_, options_.rtol, options_.atol), "CVodeSStolerances");
    Check(CVodeSetUserData(mem_, this), "CVodeSetUserData");
    Check(CVodeSetErrHandlerFn(mem_, &ErrorHandler, this), "CVodeSetErrHandlerFn");
    Check(CVodeSetMaxNumSteps(mem_, options_.max_steps), "CVodeSetMaxNumSteps");
    if (fixed_point_) {
      nls_ = SUNNonlinSol_FixedPoint(y_, 0, ctx_);
      if (nls_ == nullptr) throw NumericalError("SUNNonlinSol_FixedPoint failed");
      Check(CVodeSetNonlinearSolver(mem_, nls_), "CVodeSetNonlinearSolver");
    } else {
      A_ = SUNDenseMatrix(kN, kN, ctx_);
      if (A_ == nullptr) throw NumericalError("SUNDenseMatrix failed");
      linear_solver_ = SUNLinSol_Dense(y_, A_, ctx_);
      if (linear_solver_ == nullptr) throw NumericalError("SUNLinSol_Dense failed");
      Check(CVodeSetLinearSolver(mem_, linear_solver_, A_), "CVodeSetLinearSolver");
      Check(CVodeSetJacFn(mem_, &JacobianFn), "CVodeSetJacFn");
    }
    yS_ = N_VCloneVectorArray(kN, y_);
    if (yS_ == nullptr) throw NumericalError("N_VCloneVectorArray failed");
    initialised_ = true;
  }

  // Frees what exists and forgets it (Create may run again after a throw).
  void Free() {
    if (yS_ != nullptr) N_VDestroyVectorArray(yS_, kN);
    if (mem_ != nullptr) CVodeFree(&mem_);
    if (nls_ != nullptr) SUNNonlinSolFree(nls_);
    if (nls_sens_ != nullptr) SUNNonlinSolFree(nls_sens_);
    if (linear_solver_ != nullptr) SUNLinSolFree(linear_solver_);
    if (A_ != nullptr) SUNMatDestroy(A_);
    if (y_ != nullptr) N_VDestroy(y_);
    if (ctx_ != nullptr) SUNContext_Free(&ctx_);
    yS_ = nullptr;
    mem_ = nullptr;
    nls_ = nls_sens_ = nullptr;
    linear_solver_ = nullptr;
    A_ = nullptr;
    y_ = nullptr;
    ctx_ = nullptr;
    initialised_ = sens_created_ = sens_on_ = have_last_ = false;
  }

  static void Copy(const State& x, N_Vector v) {
    for (int i = 0; i < kN; ++i) NV_Ith_S(v, i) = x(i);
  }
  static State Load(N_Vector v) {
    State x;
    for (int i = 0; i < kN; ++i) x(i) = NV_Ith_S(v, i);
    return x;
  }

  static void Check(int flag, const char* call) {
    if (flag < 0) {
      throw NumericalError(std::string("CVODES call ") + call + " failed with flag " +
                           std::to_string(flag));
    }
  }

  // df/dx at (t, y) by forward-mode AD.
  Jacobian EvalJacobian(double t, const State& x) {
    ++this->stats_.jacobian_evals;
    Jacobian J;
    const InputOf<Model>& u = this->input_;
    const Params& p = this->params_;
    ValueAndJacobian<kN, kN>(
        [&](const auto& xj) {
          using J_t = typename std::decay_t<decltype(xj)>::Scalar;
          return Model::Rhs(J_t(t), xj, u, p);
        },
        x, &J);
    return J;
  }

  // Keeps CVODES' message for our error instead of printing it to stderr.
  static void ErrorHandler(int /*error_code*/, const char* /*module*/, const char* function,
                           char* msg, void* user_data) {
    static_cast<CvodesTransition*>(user_data)->callback_error_ = std::string(function) + ": " + msg;
  }

  static int Rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<CvodesTransition*>(user_data);
    ++self->stats_.rhs_evals;
    const State f = Model::Rhs(double(t), Load(y), self->input_, self->params_);
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
  SUNNonlinearSolver nls_ = nullptr;
  SUNNonlinearSolver nls_sens_ = nullptr;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector* yS_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver linear_solver_ = nullptr;
  bool initialised_ = false;
  bool sens_created_ = false;
  bool sens_on_ = false;
  bool have_last_ = false;
  double last_t1_ = 0.0;
  double last_h_ = 0.0;
  double last_h0_ = 0.0;
  InputOf<Model> last_input_ = InputFrom<Model>(nullptr);
  State last_x_ = State::Zero();
  std::string callback_error_;
};

}  // namespace estlab

#endif  // ESTLAB_ODE_CVODES_H_
