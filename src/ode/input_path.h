// The input over one step [t0, t1] as the integrators see it. Recorded
// inputs are samples u_k at the rows' times; between two samples the input
// is held one of two ways (--input-hold):
//
//   zoh     u(t) = u_k                                         (the default)
//   linear  u(t) = u_k + (t - t_k) / (t_k+1 - t_k) (u_k+1 - u_k)
//
// The run loops (src/run/step_loop.h) and the simulator decide the hold:
// they give a transition the samples at both ends of a step, u1 = u0 for
// zoh. A transition follows the line between the two; a step whose ends are
// equal (every zoh step, and a linear step over a constant stretch) is held
// exactly, with no arithmetic per evaluation. A discrete-time model's map
// sees u(t_k), the sample at the start of its step, under either hold.
#ifndef ESTLAB_ODE_INPUT_PATH_H_
#define ESTLAB_ODE_INPUT_PATH_H_

#include <string>

#include "models/model.h"

namespace estlab {

enum class InputHold { kZoh, kLinear };

// Parses "zoh", "linear"; throws InputError.
InputHold ParseInputHold(const std::string& name);
const char* InputHoldName(InputHold hold);

template <class Model>
struct InputPath {
  using Input = InputOf<Model>;
  Input u0 = InputFrom<Model>(nullptr);  // at t0
  Input u1 = u0;                         // at t1
  double t0 = 0.0;
  double t1 = 0.0;
  bool ramp = false;  // u1 != u0: the line; else u0 throughout

  InputPath() = default;
  // A held input. Implicit: every caller with one input means this.
  InputPath(const Input& u) : u0(u), u1(u) {}  // NOLINT(google-explicit-constructor)
  InputPath(const Input& a, const Input& b, double ta, double tb)
      : u0(a), u1(b), t0(ta), t1(tb), ramp(!(a == b) && tb > ta) {}

  // u(t) on the step.
  Input At(double t) const {
    if (!ramp) return u0;
    const double s = (t - t0) / (t1 - t0);
    return Input(u0 + s * (u1 - u0));
  }
};

}  // namespace estlab

#endif  // ESTLAB_ODE_INPUT_PATH_H_
