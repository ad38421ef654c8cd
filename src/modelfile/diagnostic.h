// Problems found in a model file, and the one exception that reports them all.
// The model-file front end never stops at the first problem: it collects every
// diagnostic of the file and throws a single ModelFileError whose what() lists
// them as "FILE:LINE:COL: message" lines, sorted by position, the way a
// compiler reports errors.
//
// Usage:
//   std::vector<Diagnostic> problems;
//   problems.push_back({3, 7, "unknown name 'omgea'; did you mean 'omega'?"});
//   if (!problems.empty()) throw ModelFileError("pendulum.model", problems);
//   // what(): "pendulum.model:3:7: unknown name 'omgea'; did you mean 'omega'?"
#ifndef ESTLAB_MODELFILE_DIAGNOSTIC_H_
#define ESTLAB_MODELFILE_DIAGNOSTIC_H_

#include <string>
#include <string_view>
#include <vector>

#include "src/core/types.h"

namespace estlab::modelfile {

// A place in a model file; line and column are 1-based, columns count bytes.
struct SourcePos {
  int line = 1;
  int column = 1;
};

struct Diagnostic {
  int line = 1;
  int column = 1;
  std::string message;
};

inline Diagnostic MakeDiagnostic(SourcePos pos, std::string message) {
  return {pos.line, pos.column, std::move(message)};
}

// Thrown by ParseModelFile (model_file.h) with every problem of the file.
class ModelFileError : public InputError {
 public:
  // Sorts `diagnostics` by position (stable: same-position messages keep
  // their order).
  ModelFileError(const std::string& path, std::vector<Diagnostic> diagnostics);

  const std::string& path() const { return path_; }
  const std::vector<Diagnostic>& diagnostics() const { return diagnostics_; }

 private:
  std::string path_;
  std::vector<Diagnostic> diagnostics_;
};

// "PATH:LINE:COL: message" lines joined by '\n', in the order given.
std::string FormatDiagnostics(const std::string& path, const std::vector<Diagnostic>& diagnostics);

// `text` in single quotes, with bytes outside printable ASCII written as
// \xNN, so that messages stay readable whatever the file contains.
std::string Quoted(std::string_view text);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_DIAGNOSTIC_H_
