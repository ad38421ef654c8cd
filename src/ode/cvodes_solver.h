// One SUNDIALS CVODES integrator and everything it owns, made and freed in
// one place: the context, the state vector, the solver memory, its
// nonlinear solver (fixed point, or Newton with a dense linear solver) and
// the forward-sensitivity vectors. Both CVODES users build on it: the
// transition (src/ode/cvodes.h: sensitivities in x0 for the flow Jacobian)
// and the parameter flow (src/ode/cvodes_theta_flow.h: sensitivities in the
// tuner's theta). Compiled once (cvodes_solver.cpp), not per model.
//
// Usage:
//   CvodesSetup setup;
//   setup.size = n;  setup.rhs = &Rhs;  setup.user_data = this;  ...
//   CvodesSolver solver;
//   solver.Build(setup);                 // throws NumericalError, keeps nothing
//   solver.StartSensitivities(&SensRhs); // CVodeSensInit on the cloned vectors
//   const int flag = CVode(solver.mem(), t1, solver.y(), &t, CV_NORMAL);
//   if (flag < 0) solver.Fail(flag, "CVODES", t0, t1, t);
//
// Every SUNDIALS call's return is checked (Check); CVODES' own error text is
// kept by the error handler and appended to the failure message instead of
// being printed. WARNING: not thread-safe, like the memory it owns.
#ifndef ESTLAB_ODE_CVODES_SOLVER_H_
#define ESTLAB_ODE_CVODES_SOLVER_H_

#include <cvodes/cvodes.h>
#include <sundials/sundials_context.h>

#include <string>

namespace estlab {

struct CvodesSetup {
  int size = 0;              // components of the integrated vector
  bool bdf = false;          // BDF, else Adams
  bool fixed_point = false;  // fixed-point corrector, else Newton + dense solver
  double rtol = 1e-10;
  double atol = 1e-12;
  long max_steps = 500000;
  CVRhsFn rhs = nullptr;
  void* user_data = nullptr;  // handed to rhs, jacobian and the sensitivities
  // Newton only: the exact Jacobian; null for CVODES' difference quotients.
  CVLsJacFn jacobian = nullptr;
  // Sensitivity vectors cloned at Build (StartSensitivities initialises them).
  int sensitivities = 0;
  // SUNDIALS' fused vector operations (off by default there).
  bool fused_ops = false;
};

class CvodesSolver {
 public:
  CvodesSolver() = default;
  ~CvodesSolver() { Free(); }
  CvodesSolver(const CvodesSolver&) = delete;
  CvodesSolver& operator=(const CvodesSolver&) = delete;

  // Makes everything for `setup` with the state at t0 (y() zero); throws
  // NumericalError naming the call that failed and keeps nothing of it.
  void Build(const CvodesSetup& setup, double t0 = 0.0);
  // CVodeSensInit (simultaneous corrector) with the sensitivities' error
  // control on, for setup.sensitivities vectors; a fixed-point solver gets
  // its sensitivity twin.
  void StartSensitivities(CVSensRhsFn sens_rhs);
  void Free();

  bool built() const { return mem_ != nullptr; }
  void* mem() const { return mem_; }
  N_Vector y() const { return y_; }
  N_Vector* yS() const { return yS_; }
  long NumSteps() const;

  // Before a CVode call: forget the previous failure's text.
  void ClearError() { callback_error_.clear(); }
  // Throws NumericalError("<what> failed at t = .. while stepping from t = ..
  // to t = ..: CV_FLAG (CVODES' own message)").
  [[noreturn]] void Fail(int flag, const char* what, double t0, double t1, double t_reached) const;
  // Throws NumericalError when a SUNDIALS call returned a failure.
  static void Check(int flag, const char* call);

 private:
  static void ErrorHandler(int error_code, const char* module, const char* function, char* msg,
                           void* user_data);

  CvodesSetup setup_;
  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector* yS_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver linear_solver_ = nullptr;
  SUNNonlinearSolver nls_ = nullptr;
  SUNNonlinearSolver nls_sens_ = nullptr;
  std::string callback_error_;
};

}  // namespace estlab

#endif  // ESTLAB_ODE_CVODES_SOLVER_H_
