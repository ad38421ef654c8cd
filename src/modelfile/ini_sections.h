// The INI layer of the model-file language: splits the text into sections
// ("[kind name]") and "key = value" entries, with 1-based line and column of
// every piece. '#' starts a comment anywhere on a line; blank lines, comments
// and a trailing '\r' are dropped. What the kinds and keys mean is decided by
// the model reader (model_reader.h).
//
// Usage:
//   std::vector<IniSection> sections = SplitIniSections(text, &problems);
//   for (const IniEntry& e : sections[0].entries) ... e.key, e.value, e.value_pos ...
#ifndef ESTLAB_MODELFILE_INI_SECTIONS_H_
#define ESTLAB_MODELFILE_INI_SECTIONS_H_

#include <string>
#include <string_view>
#include <vector>

#include "src/modelfile/diagnostic.h"

namespace estlab::modelfile {

struct IniEntry {
  std::string key;  // trimmed text before the first '='
  SourcePos key_pos;
  std::string value;    // trimmed text after it, comment removed
  SourcePos value_pos;  // first character of value (just after '=' when empty)
};

struct IniSection {
  SourcePos pos;     // the '['
  std::string kind;  // first word of the header ("measurement")
  SourcePos kind_pos;
  std::string name;  // second word, "" when absent ("angle-rate")
  SourcePos name_pos;
  std::string group;  // "[kind name: group]": the word after ':', else ""
  SourcePos group_pos;
  std::vector<IniEntry> entries;
  int malformed_lines = 0;  // lines of the section that are not "key = value"
};

// Problems reported here: text before the first section, a header without
// ']' (read as if closed), text after ']', an empty header, more than two
// words in a header (a ':' and a group name after the name excepted), a line
// without '=', an empty key.
std::vector<IniSection> SplitIniSections(std::string_view text,
                                         std::vector<Diagnostic>* diagnostics);

}  // namespace estlab::modelfile

#endif  // ESTLAB_MODELFILE_INI_SECTIONS_H_
