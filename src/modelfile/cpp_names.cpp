#include "src/modelfile/cpp_names.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <set>

namespace estlab::modelfile {
namespace {

const std::set<std::string, std::less<>>& Keywords() {
  static const std::set<std::string, std::less<>> kKeywords = {
      "alignas",       "alignof",     "and",
      "and_eq",        "asm",         "auto",
      "bitand",        "bitor",       "bool",
      "break",         "case",        "catch",
      "char",          "char8_t",     "char16_t",
      "char32_t",      "class",       "compl",
      "concept",       "const",       "consteval",
      "constexpr",     "constinit",   "const_cast",
      "continue",      "co_await",    "co_return",
      "co_yield",      "decltype",    "default",
      "delete",        "do",          "double",
      "dynamic_cast",  "else",        "enum",
      "explicit",      "export",      "extern",
      "false",         "float",       "for",
      "friend",        "goto",        "if",
      "inline",        "int",         "long",
      "mutable",       "namespace",   "new",
      "noexcept",      "not",         "not_eq",
      "nullptr",       "operator",    "or",
      "or_eq",         "private",     "protected",
      "public",        "register",    "reinterpret_cast",
      "requires",      "return",      "short",
      "signed",        "sizeof",      "static",
      "static_assert", "static_cast", "struct",
      "switch",        "template",    "this",
      "thread_local",  "throw",       "true",
      "try",           "typedef",     "typeid",
      "typename",      "union",       "unsigned",
      "using",         "virtual",     "void",
      "volatile",      "wchar_t",     "while",
      "xor",           "xor_eq",      "final",
      "override",      "import",      "module"};
  return kKeywords;
}

bool IsUpperName(std::string_view name) {
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isupper(static_cast<unsigned char>(c)) ||
           std::isdigit(static_cast<unsigned char>(c)) || c == '_';
  });
}

bool StartsWith(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}

}  // namespace

bool IsCppKeyword(std::string_view name) { return Keywords().count(name) > 0; }

bool LooksLikeMacro(std::string_view name) {
  static const std::set<std::string, std::less<>> kMacros = {
      "NULL",      "EOF",    "NAN",      "INFINITY",   "HUGE_VAL", "HUGE_VALF",
      "HUGE_VALL", "BUFSIZ", "RAND_MAX", "MB_CUR_MAX", "CHAR_BIT", "DECIMAL_DIG",
      "assert",    "errno",  "unix",     "linux",      "i386",     "math_errhandling",
      "offsetof",  "setjmp", "va_arg",   "va_start",   "va_end",   "stdin",
      "stdout",    "stderr", "isnan",    "isinf",      "signbit",  "fpclassify",
      "isfinite"};
  if (kMacros.count(name) > 0) return true;
  if (name.size() >= 2 && name[0] == '_' && std::isupper(static_cast<unsigned char>(name[1])))
    return true;
  if (!IsUpperName(name)) return false;
  for (const char* prefix :
       {"M_", "FP_", "FLT_", "DBL_", "LDBL_", "INT", "UINT", "SIZE_", "PTRDIFF_", "WCHAR_", "SIG",
        "EXIT_", "EIGEN_", "CERES_", "ESTLAB_", "GLOG_", "MATH_"}) {
    if (StartsWith(name, prefix)) return true;
  }
  // errno values (EDOM, ERANGE, EINVAL, ...).
  return name.size() >= 3 && name[0] == 'E' && name.find('_') == std::string_view::npos &&
         std::none_of(name.begin(), name.end(),
                      [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

std::string LocalName(const std::string& name) { return kValuePrefix + name; }

std::string MemberName(const std::string& name) { return kValuePrefix + name; }

std::string CamelCase(std::string_view name) {
  std::string out;
  bool upper = true;
  for (const char c : name) {
    if (c == '-' || c == '_') {
      upper = true;
    } else {
      out += upper ? char(std::toupper(static_cast<unsigned char>(c))) : c;
      upper = false;
    }
  }
  return out;
}

std::string UpperSnakeCase(std::string_view camel) {
  std::string out;
  for (size_t i = 0; i < camel.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(camel[i]);
    if (i > 0 && std::isupper(c) && !std::isupper(static_cast<unsigned char>(camel[i - 1])) &&
        camel[i - 1] != '_')
      out += '_';
    out += char(std::toupper(c));
  }
  return out;
}

std::string CppStringLiteral(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    const unsigned char byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\%03o", byte);
      out += buf;
    }
  }
  return out + "\"";
}

std::string CommentText(std::string_view text) {
  std::string out;
  for (const char c : text) {
    const unsigned char byte = static_cast<unsigned char>(c);
    out += (byte >= 0x20 && byte < 0x7f && c != '\\') ? c : '?';
  }
  return out;
}

std::string FormatDouble(double v) {
  char buf[40];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  std::string out = buf;
  if (out.find_first_of(".eEn") == std::string::npos) out += ".0";
  return out;
}

}  // namespace estlab::modelfile
