#include "src/filters/filter.h"

namespace estlab {

const char* FilterStatusName(FilterStatus status) {
  switch (status) {
    case FilterStatus::kOk:
      return "ok";
    case FilterStatus::kFactorizationFailed:
      return "factorization-failed";
    case FilterStatus::kNonFinite:
      return "non-finite";
    case FilterStatus::kTransitionFailed:
      return "transition-failed";
  }
  return "unknown";
}

}  // namespace estlab
