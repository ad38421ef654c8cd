#include "src/modelfile/diagnostic.h"

#include <algorithm>
#include <cstdio>

namespace estlab::modelfile {
namespace {

std::vector<Diagnostic> Sorted(std::vector<Diagnostic> diagnostics) {
  std::stable_sort(diagnostics.begin(), diagnostics.end(),
                   [](const Diagnostic& a, const Diagnostic& b) {
                     return a.line != b.line ? a.line < b.line : a.column < b.column;
                   });
  return diagnostics;
}

}  // namespace

ModelFileError::ModelFileError(const std::string& path, std::vector<Diagnostic> diagnostics)
    : InputError(FormatDiagnostics(path, Sorted(diagnostics))),
      path_(path),
      diagnostics_(Sorted(std::move(diagnostics))) {}

std::string FormatDiagnostics(const std::string& path, const std::vector<Diagnostic>& diagnostics) {
  std::string out;
  for (const Diagnostic& d : diagnostics) {
    if (!out.empty()) out += '\n';
    out += path + ":" + std::to_string(d.line) + ":" + std::to_string(d.column) + ": " + d.message;
  }
  return out;
}

std::string Quoted(std::string_view text) {
  std::string out = "'";
  for (const char c : text) {
    const unsigned char byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", byte);
      out += buf;
    }
  }
  return out + "'";
}

}  // namespace estlab::modelfile
