// Name rules of the model-file language and "did you mean" suggestions.
//
//   identifier   [A-Za-z_][A-Za-z0-9_]*     states, parameters, lets, outputs
//   dashed name  [A-Za-z_][A-Za-z0-9_-]*    model and measurement names
//
// Names ending in '_' or containing "__" are reserved for the generated C++
// (cpp_names.h spells every user name "v_NAME"; "__" is reserved to the
// C++ implementation).
//
// Usage:
//   DidYouMean("omgea", {"theta", "omega"})  ->  "; did you mean 'omega'?"
#ifndef ESTLAB_MODELFILE_NAMES_H_
#define ESTLAB_MODELFILE_NAMES_H_

#include <string>
#include <string_view>
#include <vector>

namespace estlab::modelfile {

bool IsIdentifier(std::string_view name);
bool IsDashedName(std::string_view name);

// True for identifiers the generator reserves (trailing '_', "__").
bool IsReservedSpelling(std::string_view name);

// Optimal-string-alignment distance: insertions, deletions, substitutions
// and transpositions of neighbours each cost 1.
int EditDistance(std::string_view a, std::string_view b);

// "; did you mean 'X'?" for the closest candidate (same name in another case,
// else edit distance 1 for names up to 4 characters and 2 beyond; none for
// one-character names), or "" when no candidate is close.
std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_NAMES_H_
