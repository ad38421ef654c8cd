#include "src/options/column_map.h"

#include <cmath>
#include <cstdlib>
#include <numbers>

#include "src/core/parse.h"
#include "src/core/types.h"

namespace estlab {

namespace {

// A finite number written completely, or `pi` / `-pi`.
bool ParseConstant(const std::string& text, double* value) {
  const std::string t = Trim(text);
  if (t == "pi" || t == "-pi") {
    *value = t[0] == '-' ? -std::numbers::pi : std::numbers::pi;
    return true;
  }
  if (t.empty() || t.find_first_of(" \t") != std::string::npos) return false;
  char* end = nullptr;
  *value = std::strtod(t.c_str(), &end);
  return end == t.c_str() + t.size() && std::isfinite(*value);
}

bool IsColumnName(const std::string& name) {
  double unused;
  return !name.empty() && name.front() != '+' && name.front() != '-' && name.back() != '+' &&
         name.back() != '-' && name.find_first_of("*= \t") == std::string::npos &&
         !ParseConstant(name, &unused);
}

}  // namespace

ColumnMap ParseColumnMap(const std::string& text) {
  const auto bad = [&]() {
    return InputError("--column: expected ours=[a*]theirs[+-b], got '" + text + "'");
  };
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw bad();
  ColumnMap map;
  map.ours = Trim(text.substr(0, eq));
  std::string rhs = Trim(text.substr(eq + 1));
  if (!IsColumnName(map.ours)) throw bad();
  // a*: the scale.
  const auto star = rhs.find('*');
  if (star != std::string::npos) {
    if (!ParseConstant(rhs.substr(0, star), &map.scale)) throw bad();
    rhs = Trim(rhs.substr(star + 1));
  }
  // +-b: the first sign after the name's first character followed by a constant.
  for (size_t p = 1; p < rhs.size(); ++p) {
    if (rhs[p] != '+' && rhs[p] != '-') continue;
    double b;
    if (!ParseConstant(rhs.substr(p + 1), &b)) continue;
    map.offset = rhs[p] == '-' ? -b : b;
    rhs = Trim(rhs.substr(0, p));
    break;
  }
  if (!IsColumnName(rhs)) throw bad();
  map.theirs = rhs;
  return map;
}

std::vector<ColumnMap> ParseColumnMaps(const std::vector<std::string>& items) {
  std::vector<ColumnMap> maps;
  for (const std::string& item : items) {
    ColumnMap map = ParseColumnMap(item);
    for (const ColumnMap& m : maps)
      if (m.ours == map.ours)
        throw InputError("--column: '" + map.ours + "' is mapped twice ('" + item + "')");
    maps.push_back(std::move(map));
  }
  return maps;
}

}  // namespace estlab
