#include "src/filters/filter_options.h"

#include <string>

#include "src/core/types.h"

namespace estlab {

bool AdaptSpec::IsValid(std::string* error) const {
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (rule.empty()) return true;
  if (rule != "sage-husa" && rule != "innovation-matching")
    return fail("adapt: unknown rule '" + rule + "' (expected sage-husa or innovation-matching)");
  if (!adapt_q && !adapt_r) return fail("adapt-what: adapts neither q nor r");
  if (!(forgetting > 0 && forgetting < 1))
    return fail("forgetting: must be in (0, 1), got " + FormatNumber(forgetting));
  if (window < 1) return fail("window: must be >= 1, got " + std::to_string(window));
  if (!(eigen_floor >= 0)) return fail("adapt: the eigenvalue floor must be >= 0");
  return true;
}

}  // namespace estlab
