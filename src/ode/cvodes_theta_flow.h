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

#include <array>
#include <string>
#include <type_traits>

#include "models/model_params.h"
#include "src/core/types.h"
#include "src/ode/autodiff.h"
#include "src/ode/cvodes_solver.h"
#include "src/ode/input_path.h"
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
  ~CvodesThetaFlow() = default;
  CvodesThetaFlow(const CvodesThetaFlow&) = delete;
  CvodesThetaFlow& operator=(const CvodesThetaFlow&) = delete;

  // CVODES internal steps taken by every Propagate so far.
  long steps() const { return steps_; }

  // x(t1) from x(t0) = x under the input u (held, or a line: input_path.h) and parameters p
  // (Params, or ParamsT<J> when physical parameters are differentiated); F = dx(t1)/dx(t0) when F
  // is not null.
  template <class P>
  StateJ Propagate(const StateJ& x, double t0, double t1, const InputPath<Model>& u, const P& p,
                   JacobianJ* F) {
    with_jacobian_ = F != nullptr;
    CvodesSolver& m = memory_[with_jacobian_ ? 1 : 0];
    if (!m.built()) Create(&m, with_jacobian_ ? kN + kN * kN : kN);
    void* const mem = m.mem();
    const N_Vector y = m.y();
    N_Vector* const yS = m.yS();
    params_ = &p;
    input_ = u;
    rhs_ = &RhsFor<P>;
    sens_rhs_ = &SensRhsFor<P>;
    // z(t0) = [x; vec I], s_i(t0) = [dx/dtheta_i; 0].
    N_VConst(0.0, y);
    for (int k = 0; k < kN; ++k) NV_Ith_S(y, k) = x(k).a;
    if (with_jacobian_)
      for (int k = 0; k < kN; ++k) NV_Ith_S(y, kN + k * kN + k) = 1.0;
    for (int i = 0; i < C; ++i) {
      N_VConst(0.0, yS[i]);
      for (int k = 0; k < kN; ++k) NV_Ith_S(yS[i], k) = x(k).v(i);
    }
    Check(CVodeReInit(mem, t0, y), "CVodeReInit");
    Check(CVodeSensReInit(mem, CV_SIMULTANEOUS, yS), "CVodeSensReInit");
    Check(CVodeSetStopTime(mem, t1), "CVodeSetStopTime");
    m.ClearError();
    sunrealtype t_reached = t0;
    const int flag = CVode(mem, t1, y, &t_reached, CV_NORMAL);
    steps_ += m.NumSteps();  // since the ReInit above
    if (flag < 0) m.Fail(flag, "CVODES (sensitivities in theta)", t0, t1, t_reached);
    Check(CVodeGetSens(mem, &t_reached, yS), "CVodeGetSens");
    StateJ x1;
    for (int k = 0; k < kN; ++k) x1(k) = Load(m, k);
    if (F != nullptr)
      for (int c = 0; c < kN; ++c)
        for (int r = 0; r < kN; ++r) (*F)(r, c) = Load(m, kN + c * kN + r);
    return x1;
  }

 private:
  // The solver for z of `size` components (n, or n + n^2 with F), with C
  // sensitivities. Stiff models: BDF, Newton and CVODES' difference-quotient
  // Jacobian of g; the others Adams with the fixed-point correctors.
  void Create(CvodesSolver* m, int size) {
    CvodesSetup setup;
    setup.size = size;
    setup.bdf = use_bdf_;
    setup.fixed_point = !use_bdf_ && !Model::kStiff;
    setup.rtol = options_.rtol;
    setup.atol = options_.atol;
    setup.max_steps = options_.max_steps;
    setup.rhs = &Rhs;
    setup.user_data = this;
    setup.sensitivities = C;
    m->Build(setup);
    try {
      m->StartSensitivities(&SensRhs);
    } catch (...) {
      m->Free();  // not a whole solver: the next call builds it again
      throw;
    }
  }

  // Component k of z as a Jet: value y_k, derivatives s_i,k.
  static J Load(const CvodesSolver& m, int k) {
    J v(NV_Ith_S(m.y(), k));
    for (int i = 0; i < C; ++i) v.v(i) = NV_Ith_S(m.yS()[i], k);
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
    const InputOf<Model> u = self->input_.At(t);
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
    const InputOf<Model> u = self->input_.At(t);
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
  static void Check(int flag, const char* call) { CvodesSolver::Check(flag, call); }

  TransitionOptions options_;
  long steps_ = 0;
  bool use_bdf_ = false;
  std::array<CvodesSolver, 2> memory_;  // [0]: z = x, [1]: z = [x; vec S]
  // The current call's inputs, read by the callbacks.
  bool with_jacobian_ = false;
  const void* params_ = nullptr;
  InputPath<Model> input_;  // over the running Propagate
  int (*rhs_)(CvodesThetaFlow*, double, N_Vector, N_Vector) = nullptr;
  int (*sens_rhs_)(CvodesThetaFlow*, double, N_Vector, N_Vector*, N_Vector*) = nullptr;
};

}  // namespace estlab

#endif  // ESTLAB_ODE_CVODES_THETA_FLOW_H_
