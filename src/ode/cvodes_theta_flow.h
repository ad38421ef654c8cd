// The CVODES flow of an ODE model, differentiated exactly in C directions
// theta (the tuner's gradient chunk) by CVODES forward sensitivities: what
// InnovationLikelihood<..>::Run<ceres::Jet<double, C>> needs for its
// transition with --integrator cvodes.
//
// The input is a state x(t0) and parameters p whose values and derivatives
// dx0/dtheta, dp/dtheta are Jets. The output is x(t1) as Jets (value and
// dx(t1)/dtheta) and, for the EKF, the flow Jacobian F = dx(t1)/dx(t0) as
// Jets too (its value and dF/dtheta).
//
// The EKF needs dF/dtheta, the parameter and state derivative of the flow
// Jacobian. It comes from the variational system integrated with the state:
//
//   z = [x; vec S],   x' = f(x, p),   S' = (df/dx)(x, p) S,   S(t0) = I,
//
// so F = S(t1). CVODES then integrates the forward sensitivities of z in C
// directions,
//
//   s_i = dz/dtheta_i,   s_i' = (dg/dz) s_i + (dg/dp) dp/dtheta_i,
//   s_i(t0) = [dx0/dtheta_i; 0],
//
// where g is the right-hand side of z. All C of them come from one
// evaluation of g on Jets (z with s_i as its derivative parts, p as given):
// a Jet over theta of df/dx, itself taken by forward AD over x, i.e. a
// NestedJet (src/ode/nested_jet.h). Sensitivities are in the error test
// (CVodeSetSensErrCon), with CVodeSensEEtolerances. Without F (sigma-point
// filters) z = x. This is the route the issue names ("an augmented
// sensitivity system"), chosen over second-order adjoints because the
// filter recursion is forward and every step needs the derivatives at once.
//
// Each call re-initialises CVODES (no step-size history kept, no initial
// step set), so the result is a function of the inputs alone. Non-stiff
// models integrate with Adams and the fixed-point solvers; stiff ones with
// BDF, Newton and a dense difference-quotient Jacobian of g (an exact one
// would need third derivatives of f; the Jacobian only affects convergence of
// the corrector, not the solution).
//
// Usage (InnovationLikelihood::Propagate):
//   CvodesThetaFlow<models::Pendulum, 4> flow(options);
//   Eigen::Matrix<ceres::Jet<double, 4>, 2, 2> F;
//   x1 = flow.Propagate(x0, t0, t1, u, p, &F);   // p: Params or ParamsT<Jet<4>>
//
// WARNING: not thread-safe; one instance per thread. A CVODES failure
// throws NumericalError naming t; a non-finite right-hand side is returned
// to CVODES as recoverable (it retries with a smaller step).
#ifndef ESTLAB_ODE_CVODES_THETA_FLOW_H_
#define ESTLAB_ODE_CVODES_THETA_FLOW_H_

#include <ceres/jet.h>
#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <array>
#include <cstdlib>
#include <sstream>
#include <string>
#include <type_traits>

#include "models/model_params.h"
#include "src/core/types.h"
#include "src/ode/autodiff.h"
#include "src/ode/nested_jet.h"
#include "src/ode/transition.h"

namespace estlab {

// C of ceres::Jet<double, C>.
template <class T>
struct JetSize;
template <int C>
struct JetSize<ceres::Jet<double, C>> {
  static constexpr int value = C;
};

template <class Model, int C>
class CvodesThetaFlow {
 public:
  static constexpr int kN = Model::kStateDim;
  using J = ceres::Jet<double, C>;
  using StateJ = Eigen::Matrix<J, kN, 1>;
  using JacobianJ = Eigen::Matrix<J, kN, kN>;

  explicit CvodesThetaFlow(const TransitionOptions& options) : options_(options) {
    use_bdf_ = options.method == CvodesMethod::kBdf ||
               (options.method == CvodesMethod::kDefault && Model::kStiff);
  }
  ~CvodesThetaFlow() {
    for (Memory& m : memory_) m.Free();
    if (ctx_ != nullptr) SUNContext_Free(&ctx_);
  }
  CvodesThetaFlow(const CvodesThetaFlow&) = delete;
  CvodesThetaFlow& operator=(const CvodesThetaFlow&) = delete;

  // CVODES internal steps taken by every Propagate so far.
  long steps() const { return steps_; }

  // x(t1) from x(t0) = x under constant input u and parameters p (Params, or
  // ParamsT<J> when physical parameters are differentiated); F = dx(t1)/dx(t0)
  // when F is not null.
  template <class P>
  StateJ Propagate(const StateJ& x, double t0, double t1, const InputOf<Model>& u, const P& p,
                   JacobianJ* F) {
    with_jacobian_ = F != nullptr;
    Memory& m = memory_[with_jacobian_ ? 1 : 0];
    if (m.mem == nullptr) Create(&m, with_jacobian_ ? kN + kN * kN : kN);
    params_ = &p;
    input_ = u;
    rhs_ = &RhsFor<P>;
    sens_rhs_ = &SensRhsFor<P>;
    // z(t0) = [x; vec I], s_i(t0) = [dx/dtheta_i; 0].
    N_VConst(0.0, m.y);
    for (int k = 0; k < kN; ++k) NV_Ith_S(m.y, k) = x(k).a;
    if (with_jacobian_)
      for (int k = 0; k < kN; ++k) NV_Ith_S(m.y, kN + k * kN + k) = 1.0;
    for (int i = 0; i < C; ++i) {
      N_VConst(0.0, m.yS[i]);
      for (int k = 0; k < kN; ++k) NV_Ith_S(m.yS[i], k) = x(k).v(i);
    }
    Check(CVodeReInit(m.mem, t0, m.y), "CVodeReInit");
    Check(CVodeSensReInit(m.mem, CV_SIMULTANEOUS, m.yS), "CVodeSensReInit");
    Check(CVodeSetStopTime(m.mem, t1), "CVodeSetStopTime");
    callback_error_.clear();
    sunrealtype t_reached = t0;
    const int flag = CVode(m.mem, t1, m.y, &t_reached, CV_NORMAL);
    long steps = 0;  // since the ReInit above
    if (CVodeGetNumSteps(m.mem, &steps) == CV_SUCCESS) steps_ += steps;
    if (flag < 0) Fail(flag, t0, t1, t_reached);
    Check(CVodeGetSens(m.mem, &t_reached, m.yS), "CVodeGetSens");
    StateJ x1;
    for (int k = 0; k < kN; ++k) x1(k) = Load(m, k);
    if (F != nullptr)
      for (int c = 0; c < kN; ++c)
        for (int r = 0; r < kN; ++r) (*F)(r, c) = Load(m, kN + c * kN + r);
    return x1;
  }

 private:
  // One CVODES memory per size of z (n, or n + n^2 with F).
  struct Memory {
    void* mem = nullptr;
    N_Vector y = nullptr;
    N_Vector* yS = nullptr;
    SUNNonlinearSolver nls = nullptr, nls_sens = nullptr;
    SUNMatrix A = nullptr;
    SUNLinearSolver linear_solver = nullptr;
    void Free() {
      if (yS != nullptr) N_VDestroyVectorArray(yS, C);
      if (mem != nullptr) CVodeFree(&mem);
      if (nls != nullptr) SUNNonlinSolFree(nls);
      if (nls_sens != nullptr) SUNNonlinSolFree(nls_sens);
      if (linear_solver != nullptr) SUNLinSolFree(linear_solver);
      if (A != nullptr) SUNMatDestroy(A);
      if (y != nullptr) N_VDestroy(y);
      *this = Memory();
    }
  };

  void Create(Memory* m, int size) {
    if (ctx_ == nullptr) Check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
    m->y = N_VNew_Serial(size, ctx_);
    if (m->y == nullptr) throw NumericalError("N_VNew_Serial failed");
    N_VConst(0.0, m->y);
    m->mem = CVodeCreate(use_bdf_ ? CV_BDF : CV_ADAMS, ctx_);
    if (m->mem == nullptr) throw NumericalError("CVodeCreate failed");
    Check(CVodeInit(m->mem, &Rhs, 0.0, m->y), "CVodeInit");
    Check(CVodeSStolerances(m->mem, options_.rtol, options_.atol), "CVodeSStolerances");
    Check(CVodeSetUserData(m->mem, this), "CVodeSetUserData");
    Check(CVodeSetErrHandlerFn(m->mem, &ErrorHandler, this), "CVodeSetErrHandlerFn");
    Check(CVodeSetMaxNumSteps(m->mem, options_.max_steps), "CVodeSetMaxNumSteps");
    if (!use_bdf_ && !Model::kStiff) {
      m->nls = SUNNonlinSol_FixedPoint(m->y, 0, ctx_);
      if (m->nls == nullptr) throw NumericalError("SUNNonlinSol_FixedPoint failed");
      Check(CVodeSetNonlinearSolver(m->mem, m->nls), "CVodeSetNonlinearSolver");
    } else {
      m->A = SUNDenseMatrix(size, size, ctx_);
      m->linear_solver = SUNLinSol_Dense(m->y, m->A, ctx_);
      if (m->A == nullptr || m->linear_solver == nullptr)
        throw NumericalError("SUNLinSol_Dense failed");
      Check(CVodeSetLinearSolver(m->mem, m->linear_solver, m->A), "CVodeSetLinearSolver");
    }
    m->yS = N_VCloneVectorArray(C, m->y);
    if (m->yS == nullptr) throw NumericalError("N_VCloneVectorArray failed");
    for (int i = 0; i < C; ++i) N_VConst(0.0, m->yS[i]);
    Check(CVodeSensInit(m->mem, C, CV_SIMULTANEOUS, &SensRhs, m->yS), "CVodeSensInit");
    Check(CVodeSensEEtolerances(m->mem), "CVodeSensEEtolerances");
    Check(CVodeSetSensErrCon(m->mem, SUNTRUE), "CVodeSetSensErrCon");
    if (m->nls != nullptr) {
      m->nls_sens = SUNNonlinSol_FixedPointSens(C + 1, m->y, 0, ctx_);
      if (m->nls_sens == nullptr) throw NumericalError("SUNNonlinSol_FixedPointSens failed");
      Check(CVodeSetNonlinearSolverSensSim(m->mem, m->nls_sens), "CVodeSetNonlinearSolverSensSim");
    }
  }

  // Component k of z as a Jet: value y_k, derivatives s_i,k.
  static J Load(const Memory& m, int k) {
    J v(NV_Ith_S(m.y, k));
    for (int i = 0; i < C; ++i) v.v(i) = NV_Ith_S(m.yS[i], k);
    return v;
  }

  // The parameters' values as double Params.
  template <class P>
  static typename Model::Params Values(const P& p) {
    if constexpr (std::is_same_v<P, typename Model::Params>) {
      return p;
    } else {
      const auto jets = ParamValues<Model>(p);
      std::array<double, Model::kParams.size()> values;
      for (std::size_t i = 0; i < values.size(); ++i) values[i] = jets[i].a;
      return MakeParams<Model, double>(values);
    }
  }

  // g(z) in double: f(x) and, with F, (df/dx) S.
  template <class P>
  static int RhsFor(CvodesThetaFlow* self, double t, N_Vector y, N_Vector ydot) {
    const typename Model::Params p = Values(*static_cast<const P*>(self->params_));
    const InputOf<Model>& u = self->input_;
    Vec<double, kN> x;
    for (int k = 0; k < kN; ++k) x(k) = NV_Ith_S(y, k);
    if (!self->with_jacobian_) {
      const Vec<double, kN> f = Model::Rhs(t, x, u, p);
      if (!f.allFinite()) return 1;
      for (int k = 0; k < kN; ++k) NV_Ith_S(ydot, k) = f(k);
      return 0;
    }
    Mat<kN, kN> fx;
    const Vec<double, kN> f = ValueAndJacobian<kN, kN>(
        [&](const auto& xj) {
          using S = typename std::decay_t<decltype(xj)>::Scalar;
          return Model::Rhs(S(t), xj, u, p);
        },
        x, &fx);
    const Mat<kN, kN> S = Eigen::Map<const Mat<kN, kN>>(N_VGetArrayPointer(y) + kN);
    const Mat<kN, kN> dS = fx * S;
    if (!f.allFinite() || !dS.allFinite()) return 1;
    for (int k = 0; k < kN; ++k) NV_Ith_S(ydot, k) = f(k);
    Eigen::Map<Mat<kN, kN>>(N_VGetArrayPointer(ydot) + kN) = dS;
    return 0;
  }

  // All C sensitivities s_i' at once: g evaluated on Jets over theta.
  template <class P>
  static int SensRhsFor(CvodesThetaFlow* self, double t, N_Vector y, N_Vector* yS,
                        N_Vector* ySdot) {
    const P& p = *static_cast<const P*>(self->params_);
    const InputOf<Model>& u = self->input_;
    auto jet = [&](int k) {
      J v(NV_Ith_S(y, k));
      for (int i = 0; i < C; ++i) v.v(i) = NV_Ith_S(yS[i], k);
      return v;
    };
    auto store = [&](int k, const J& v) {
      for (int i = 0; i < C; ++i) NV_Ith_S(ySdot[i], k) = v.v(i);
      return std::isfinite(v.a) && v.v.allFinite();
    };
    StateJ x;
    for (int k = 0; k < kN; ++k) x(k) = jet(k);
    bool finite = true;
    if (!self->with_jacobian_) {
      const StateJ f = Model::Rhs(J(t), x, u, ParamsAs<Model, J>(p));
      for (int k = 0; k < kN; ++k) finite = store(k, f(k)) && finite;
      return finite ? 0 : 1;
    }
    JacobianJ fx, S;
    const StateJ f = ValueAndJacobianT<kN, kN>(
        [&](const auto& xs) {
          using Sc = typename std::decay_t<decltype(xs)>::Scalar;
          return Model::Rhs(Sc(t), xs, u, ParamsAs<Model, Sc>(p));
        },
        x, &fx);
    for (int c = 0; c < kN; ++c)
      for (int r = 0; r < kN; ++r) S(r, c) = jet(kN + c * kN + r);
    const JacobianJ dS = fx * S;
    for (int k = 0; k < kN; ++k) finite = store(k, f(k)) && finite;
    for (int c = 0; c < kN; ++c)
      for (int r = 0; r < kN; ++r) finite = store(kN + c * kN + r, dS(r, c)) && finite;
    return finite ? 0 : 1;
  }

  static int Rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
    auto* self = static_cast<CvodesThetaFlow*>(user_data);
    return self->rhs_(self, t, y, ydot);
  }
  static int SensRhs(int /*ns*/, sunrealtype t, N_Vector y, N_Vector /*ydot*/, N_Vector* yS,
                     N_Vector* ySdot, void* user_data, N_Vector, N_Vector) {
    auto* self = static_cast<CvodesThetaFlow*>(user_data);
    return self->sens_rhs_(self, t, y, yS, ySdot);
  }
  static void ErrorHandler(int /*error_code*/, const char* /*module*/, const char* function,
                           char* msg, void* user_data) {
    static_cast<CvodesThetaFlow*>(user_data)->callback_error_ = std::string(function) + ": " + msg;
  }

  [[noreturn]] void Fail(int flag, double t0, double t1, double t_reached) const {
    std::ostringstream msg;
    msg << "CVODES (sensitivities in theta) failed at t = " << t_reached
        << " while stepping from t = " << t0 << " to t = " << t1 << ": ";
    char* flag_name = CVodeGetReturnFlagName(flag);  // malloc'd, the caller frees
    msg << (flag_name != nullptr ? flag_name : "unknown CVODES flag");
    std::free(flag_name);
    if (!callback_error_.empty()) msg << " (" << callback_error_ << ")";
    throw NumericalError(msg.str());
  }
  static void Check(int flag, const char* call) {
    if (flag < 0) {
      throw NumericalError(std::string("CVODES call ") + call + " failed with flag " +
                           std::to_string(flag));
    }
  }

  TransitionOptions options_;
  long steps_ = 0;
  bool use_bdf_ = false;
  SUNContext ctx_ = nullptr;
  std::array<Memory, 2> memory_;  // [0]: z = x, [1]: z = [x; vec S]
  // The current call's inputs, read by the callbacks.
  bool with_jacobian_ = false;
  const void* params_ = nullptr;
  InputOf<Model> input_ = InputFrom<Model>(nullptr);
  int (*rhs_)(CvodesThetaFlow*, double, N_Vector, N_Vector) = nullptr;
  int (*sens_rhs_)(CvodesThetaFlow*, double, N_Vector, N_Vector*, N_Vector*) = nullptr;
  std::string callback_error_;
};

}  // namespace estlab

#endif  // ESTLAB_ODE_CVODES_THETA_FLOW_H_
