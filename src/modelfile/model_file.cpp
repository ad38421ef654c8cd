#include "src/modelfile/model_file.h"

#include <utility>

#include "src/modelfile/ini_sections.h"
#include "src/modelfile/model_check.h"
#include "src/modelfile/model_reader.h"

namespace estlab::modelfile {

ModelFile ParseModelFile(const std::string& text, const std::string& path) {
  std::vector<Diagnostic> problems;
  RawModel raw = ReadModelSections(SplitIniSections(text, &problems), &problems);
  CheckModel(&raw, &problems);
  if (!problems.empty()) throw ModelFileError(path, std::move(problems));
  raw.model.path = path;
  return std::move(raw.model);
}

}  // namespace estlab::modelfile
