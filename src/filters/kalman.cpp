#include "src/filters/kalman.h"

#include <cmath>
#include <string>

namespace estlab {

bool KfOptions::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  for (size_t i = 0; i < operating_point.size(); ++i) {
    if (!std::isfinite(operating_point[i]))
      return fail("linearize-at: operating point component " + std::to_string(i) +
                  " is not finite");
  }
  if (!std::isfinite(operating_input)) return fail("input: the operating input u* is not finite");
  return true;
}

}  // namespace estlab
