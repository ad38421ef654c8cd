#include "src/ode/cvodes_solver.h"

#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <cstdlib>
#include <sstream>

#include "src/core/types.h"

namespace estlab {

void CvodesSolver::Check(int flag, const char* call) {
  if (flag < 0)
    throw NumericalError(std::string("CVODES call ") + call + " failed with flag " +
                         std::to_string(flag));
}

void CvodesSolver::Build(const CvodesSetup& setup, double t0) {
  Free();
  setup_ = setup;
  try {
    Check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create");
    y_ = N_VNew_Serial(setup.size, ctx_);
    if (y_ == nullptr) throw NumericalError("N_VNew_Serial failed");
    // Fused operations (one call for a linear combination of many vectors,
    // as the sensitivity corrector and the Nordsieck update need); the
    // clones CVODES makes inherit them.
    if (setup.fused_ops) Check(N_VEnableFusedOps_Serial(y_, SUNTRUE), "N_VEnableFusedOps_Serial");
    N_VConst(0.0, y_);
    mem_ = CVodeCreate(setup.bdf ? CV_BDF : CV_ADAMS, ctx_);
    if (mem_ == nullptr) throw NumericalError("CVodeCreate failed");
    Check(CVodeInit(mem_, setup.rhs, t0, y_), "CVodeInit");
    Check(CVodeSStolerances(mem_, setup.rtol, setup.atol), "CVodeSStolerances");
    Check(CVodeSetUserData(mem_, setup.user_data), "CVodeSetUserData");
    Check(CVodeSetErrHandlerFn(mem_, &ErrorHandler, this), "CVodeSetErrHandlerFn");
    Check(CVodeSetMaxNumSteps(mem_, setup.max_steps), "CVodeSetMaxNumSteps");
    if (setup.fixed_point) {
      nls_ = SUNNonlinSol_FixedPoint(y_, 0, ctx_);
      if (nls_ == nullptr) throw NumericalError("SUNNonlinSol_FixedPoint failed");
      Check(CVodeSetNonlinearSolver(mem_, nls_), "CVodeSetNonlinearSolver");
    } else {
      A_ = SUNDenseMatrix(setup.size, setup.size, ctx_);
      if (A_ == nullptr) throw NumericalError("SUNDenseMatrix failed");
      linear_solver_ = SUNLinSol_Dense(y_, A_, ctx_);
      if (linear_solver_ == nullptr) throw NumericalError("SUNLinSol_Dense failed");
      Check(CVodeSetLinearSolver(mem_, linear_solver_, A_), "CVodeSetLinearSolver");
      if (setup.jacobian != nullptr) Check(CVodeSetJacFn(mem_, setup.jacobian), "CVodeSetJacFn");
    }
    if (setup.sensitivities > 0) {
      yS_ = N_VCloneVectorArray(setup.sensitivities, y_);
      if (yS_ == nullptr) throw NumericalError("N_VCloneVectorArray failed");
      for (int i = 0; i < setup.sensitivities; ++i) N_VConst(0.0, yS_[i]);
    }
  } catch (...) {
    Free();  // a half-made solver would be taken for a whole one
    throw;
  }
}

void CvodesSolver::StartSensitivities(CVSensRhsFn sens_rhs) {
  const int count = setup_.sensitivities;
  Check(CVodeSensInit(mem_, count, CV_SIMULTANEOUS, sens_rhs, yS_), "CVodeSensInit");
  Check(CVodeSensEEtolerances(mem_), "CVodeSensEEtolerances");
  Check(CVodeSetSensErrCon(mem_, SUNTRUE), "CVodeSetSensErrCon");
  if (setup_.fixed_point) {
    nls_sens_ = SUNNonlinSol_FixedPointSens(count + 1, y_, 0, ctx_);
    if (nls_sens_ == nullptr) throw NumericalError("SUNNonlinSol_FixedPointSens failed");
    Check(CVodeSetNonlinearSolverSensSim(mem_, nls_sens_), "CVodeSetNonlinearSolverSensSim");
  }
}

void CvodesSolver::Free() {
  if (yS_ != nullptr) N_VDestroyVectorArray(yS_, setup_.sensitivities);
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
}

long CvodesSolver::NumSteps() const {
  long n = 0;
  if (mem_ != nullptr) CVodeGetNumSteps(mem_, &n);
  return n;
}

void CvodesSolver::Fail(int flag, const char* what, double t0, double t1, double t_reached) const {
  std::ostringstream msg;
  msg << what << " failed at t = " << t_reached << " while stepping from t = " << t0
      << " to t = " << t1 << ": ";
  char* flag_name = CVodeGetReturnFlagName(flag);  // malloc'd: the caller frees it
  msg << (flag_name != nullptr ? flag_name : "unknown CVODES flag");
  std::free(flag_name);
  if (!callback_error_.empty()) msg << " (" << callback_error_ << ")";
  throw NumericalError(msg.str());
}

// Keeps CVODES' message for our error instead of printing it to stderr.
void CvodesSolver::ErrorHandler(int /*error_code*/, const char* /*module*/, const char* function,
                                char* msg, void* user_data) {
  static_cast<CvodesSolver*>(user_data)->callback_error_ = std::string(function) + ": " + msg;
}

}  // namespace estlab
