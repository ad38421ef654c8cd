#include "src/ode/transition.h"

#include <cmath>

namespace estlab {

// Fixed-step substeps per step: more is an hour of arithmetic per row, a
// typo, not a setting.
constexpr int kMaxSubsteps = 100000;

Integrator ParseIntegrator(const std::string& name) {
  if (name == "euler") return Integrator::kEuler;
  if (name == "semi-implicit-euler") return Integrator::kSemiImplicitEuler;
  if (name == "rk4") return Integrator::kRk4;
  if (name == "cvodes") return Integrator::kCvodes;
  if (name == "discrete") return Integrator::kDiscrete;
  throw InputError("unknown integrator '" + name +
                   "' (expected euler, semi-implicit-euler, rk4, cvodes or discrete)");
}

const char* IntegratorName(Integrator integrator) {
  switch (integrator) {
    case Integrator::kEuler:
      return "euler";
    case Integrator::kSemiImplicitEuler:
      return "semi-implicit-euler";
    case Integrator::kRk4:
      return "rk4";
    case Integrator::kCvodes:
      return "cvodes";
    case Integrator::kDiscrete:
      return "discrete";
  }
  return "?";
}

std::string CheckIntegratorForModel(Integrator integrator, bool discrete_time,
                                    const std::string& model) {
  if (discrete_time && integrator != Integrator::kDiscrete)
    return "model '" + model + "' is discrete-time (a [step] map): it runs with integrator " +
           "'discrete' only, got '" + IntegratorName(integrator) + "'";
  if (!discrete_time && integrator == Integrator::kDiscrete)
    return "integrator 'discrete' is for discrete-time models ([step]); model '" + model +
           "' is continuous: use rk4, euler, semi-implicit-euler or cvodes";
  return "";
}

InputHold ParseInputHold(const std::string& name) {
  if (name == "zoh") return InputHold::kZoh;
  if (name == "linear") return InputHold::kLinear;
  throw InputError("unknown input hold '" + name + "' (expected zoh or linear)");
}

const char* InputHoldName(InputHold hold) { return hold == InputHold::kLinear ? "linear" : "zoh"; }

bool TransitionOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (substeps < 1 || substeps > kMaxSubsteps)
    return fail("substeps: must be in [1, " + std::to_string(kMaxSubsteps) + "], got " +
                std::to_string(substeps));
  if (!(std::isfinite(rtol) && rtol > 0)) return fail("rtol: must be > 0 and finite");
  if (!(std::isfinite(atol) && atol > 0)) return fail("atol: must be > 0 and finite");
  if (max_steps < 1) return fail("max-steps: must be >= 1");
  return true;
}

}  // namespace estlab
