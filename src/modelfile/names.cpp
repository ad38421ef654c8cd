#include "src/modelfile/names.h"

#include <algorithm>
#include <cctype>

namespace estlab::modelfile {
namespace {

bool IsNameStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool IsNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

bool SameIgnoringCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  }
  return true;
}

}  // namespace

bool IsIdentifier(std::string_view name) {
  if (name.empty() || !IsNameStart(name[0])) return false;
  return std::all_of(name.begin(), name.end(), IsNameChar);
}

bool IsDashedName(std::string_view name) {
  if (name.empty() || !IsNameStart(name[0])) return false;
  return std::all_of(name.begin(), name.end(), [](char c) { return IsNameChar(c) || c == '-'; });
}

bool IsReservedSpelling(std::string_view name) {
  return (!name.empty() && name.back() == '_') || name.find("__") != std::string_view::npos;
}

int EditDistance(std::string_view a, std::string_view b) {
  // d[i][j] = distance between a[0..i) and b[0..j), three rows kept.
  const size_t n = b.size();
  std::vector<int> before(n + 1), previous(n + 1), current(n + 1);
  for (size_t j = 0; j <= n; ++j) previous[j] = int(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    current[0] = int(i);
    for (size_t j = 1; j <= n; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        current[j] = std::min(current[j], before[j - 2] + 1);
    }
    std::swap(before, previous);
    std::swap(previous, current);
  }
  return previous[n];
}

std::string DidYouMean(std::string_view name, const std::vector<std::string>& candidates) {
  for (const std::string& c : candidates) {
    if (c != name && SameIgnoringCase(c, name)) return "; did you mean '" + c + "'?";
  }
  if (name.size() < 2 || name.size() > 64) return "";  // long names: no O(n m) work
  const int limit = name.size() <= 4 ? 1 : 2;
  const std::string* best = nullptr;
  int best_distance = limit + 1;
  for (const std::string& c : candidates) {
    if (c == name || c.size() > name.size() + 2 || name.size() > c.size() + 2) continue;
    const int d = EditDistance(name, c);
    if (d < best_distance) {
      best_distance = d;
      best = &c;
    }
  }
  return best ? "; did you mean '" + *best + "'?" : "";
}

}  // namespace estlab::modelfile
