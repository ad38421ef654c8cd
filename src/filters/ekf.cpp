#include "src/filters/ekf.h"

#include <string>

namespace estlab {

bool EkfOptions::IsValid(std::string* error) const {
  if (iterations < 1 || iterations > 100) {
    if (error != nullptr)
      *error = "iterations: must be in [1, 100], got " + std::to_string(iterations);
    return false;
  }
  return true;
}

}  // namespace estlab
