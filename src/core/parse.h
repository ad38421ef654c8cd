// Strict parsing of command-line values: every number must parse completely
// and be finite; errors name the option and the offending text.
#ifndef ESTLAB_CORE_PARSE_H_
#define ESTLAB_CORE_PARSE_H_

#include <string>
#include <utility>
#include <vector>

namespace estlab {

// s without leading and trailing blanks, tabs and carriage returns.
std::string Trim(const std::string& s);
// "a, b,,c" -> {"a", "b", "", "c"}: the parts between the separators,
// trimmed; a separator at the end gives a last empty part.
std::vector<std::string> SplitTrimmed(const std::string& text, char sep);

// "1.5" -> 1.5; throws InputError("<option>: ...") on junk, NaN or inf.
double ParseNumber(const std::string& text, const std::string& option);
// "1,2,3" -> {1,2,3}
std::vector<double> ParseList(const std::string& text, const std::string& option);
// "a=1,b=2" (also repeated options) -> {{"a",1},{"b",2}}
std::vector<std::pair<std::string, double>> ParseAssignments(const std::vector<std::string>& items,
                                                             const std::string& option);
// "a,b;c,d" -> row-major square matrix of size n (throws on wrong shape).
std::vector<double> ParseMatrix(const std::string& text, int n, const std::string& option);

void RequireLength(const std::vector<double>& v, size_t n, const std::string& option,
                   const std::string& what);
void RequireNonNegative(const std::vector<double>& v, const std::string& option);

// An integer >= min_value written as a number ("100", "1e3"); throws
// InputError("<what>: ...") otherwise.
long ParseInteger(const std::string& text, const std::string& what, long min_value);
// A count (runs, steps, particles, ...) in [min_value, max_value]: the
// range is explicit so that nothing wraps when it becomes an int; throws
// InputError("<what>: must be in [min, max], got <text>") otherwise.
int ParseCount(const std::string& text, const std::string& what, int min_value, int max_value);
// true | yes | 1, false | no | 0; throws InputError("<what>: ...") otherwise.
bool ParseBool(const std::string& text, const std::string& what);

}  // namespace estlab

#endif  // ESTLAB_CORE_PARSE_H_
