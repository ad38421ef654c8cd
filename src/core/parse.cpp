#include "src/core/parse.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "src/core/types.h"

namespace estlab {

std::vector<std::string> SplitTrimmed(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, sep)) parts.push_back(Trim(part));
  if (!text.empty() && text.back() == sep) parts.push_back("");
  return parts;
}

namespace {
std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::string cur;
  std::istringstream in(s);
  while (std::getline(in, cur, sep)) parts.push_back(cur);
  if (!s.empty() && s.back() == sep) parts.push_back("");
  return parts;
}

// `text` for an error message: control bytes (NUL, tab, ...) as \xNN, so the
// message is neither cut at a NUL nor garbled; UTF-8 letters are kept.
std::string Printable(const std::string& text) {
  std::string out;
  for (const unsigned char c : text) {
    if (c >= 0x20 && c != 0x7f) {
      out += char(c);
      continue;
    }
    const char* hex = "0123456789abcdef";
    out += {'\\', 'x', hex[c >> 4], hex[c & 15]};
  }
  return out;
}
}  // namespace

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

double ParseNumber(const std::string& raw, const std::string& option) {
  const std::string text = Trim(raw);
  if (text.empty()) throw InputError(option + ": empty value where a number was expected");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) {
    throw InputError(option + ": '" + Printable(text) + "' is not a number");
  }
  // strtod sets ERANGE for overflow (v = ±HUGE_VAL) and for results below
  // DBL_MIN: subnormals such as 4.9e-324 are exact enough and accepted; only
  // a nonzero text that rounds to 0 (1e-400) is refused as underflow.
  if (!std::isfinite(v) || (errno == ERANGE && std::fabs(v) > 1)) {
    throw InputError(option + ": '" + text + "' is not a finite number");
  }
  if (errno == ERANGE && v == 0) {
    throw InputError(option + ": '" + text + "' is too small (underflows to 0)");
  }
  return v;
}

std::vector<double> ParseList(const std::string& text, const std::string& option) {
  std::vector<double> out;
  for (const auto& part : Split(text, ',')) out.push_back(ParseNumber(part, option));
  if (out.empty()) throw InputError(option + ": empty list");
  return out;
}

std::vector<std::pair<std::string, double>> ParseAssignments(const std::vector<std::string>& items,
                                                             const std::string& option) {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& item : items) {
    for (const auto& part : Split(item, ',')) {
      const auto eq = part.find('=');
      if (eq == std::string::npos) {
        throw InputError(option + ": expected name=value, got '" + Trim(part) + "'");
      }
      out.emplace_back(Trim(part.substr(0, eq)), ParseNumber(part.substr(eq + 1), option));
    }
  }
  return out;
}

std::vector<double> ParseMatrix(const std::string& text, int n, const std::string& option) {
  std::vector<double> out;
  const auto rows = Split(text, ';');
  if (int(rows.size()) != n) {
    throw InputError(option + ": expected " + std::to_string(n) + " rows separated by ';', got " +
                     std::to_string(rows.size()));
  }
  for (const auto& row : rows) {
    const auto values = ParseList(row, option);
    if (int(values.size()) != n) {
      throw InputError(option + ": expected " + std::to_string(n) + " values per row, got " +
                       std::to_string(values.size()) + " in '" + Trim(row) + "'");
    }
    out.insert(out.end(), values.begin(), values.end());
  }
  return out;
}

void RequireLength(const std::vector<double>& v, size_t n, const std::string& option,
                   const std::string& what) {
  if (v.size() != n) {
    throw InputError(option + ": expected " + std::to_string(n) + " values (" + what + "), got " +
                     std::to_string(v.size()));
  }
}

void RequireNonNegative(const std::vector<double>& v, const std::string& option) {
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] < 0) {
      throw InputError(option + ": variance " + std::to_string(i + 1) + " is negative (" +
                       FormatNumber(v[i]) + ")");
    }
  }
}

long ParseInteger(const std::string& text, const std::string& what, long min_value) {
  const double v = ParseNumber(text, what);
  if (v != std::floor(v) || std::abs(v) > 1e15)
    throw InputError(what + ": '" + text + "' is not an integer");
  if (v < double(min_value))
    throw InputError(what + ": must be >= " + std::to_string(min_value) + ", got " + text);
  return long(v);
}

int ParseCount(const std::string& text, const std::string& what, int min_value, int max_value) {
  const long v = ParseInteger(text, what, min_value);
  if (v > max_value)
    throw InputError(what + ": must be in [" + std::to_string(min_value) + ", " +
                     std::to_string(max_value) + "], got " + text);
  return int(v);
}

bool ParseBool(const std::string& text, const std::string& what) {
  if (text == "true" || text == "yes" || text == "1") return true;
  if (text == "false" || text == "no" || text == "0") return false;
  throw InputError(what + ": expected true or false, got '" + text + "'");
}

}  // namespace estlab
