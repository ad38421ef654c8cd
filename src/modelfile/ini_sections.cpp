#include "src/modelfile/ini_sections.h"

namespace estlab::modelfile {
namespace {

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

size_t SkipBlanks(std::string_view s, size_t i) {
  while (i < s.size() && IsBlank(s[i])) ++i;
  return i;
}

size_t TrimmedEnd(std::string_view s, size_t begin, size_t end) {
  while (end > begin && IsBlank(s[end - 1])) --end;
  return end;
}

// One line without its comment; `line` is its 1-based number.
struct Line {
  std::string_view text;
  int number;
  SourcePos At(size_t i) const { return {number, int(i) + 1}; }
};

// "[kind name]" starting at text[open]; false when the header is unusable.
bool ReadHeader(const Line& line, size_t open, IniSection* section,
                std::vector<Diagnostic>* diagnostics) {
  const std::string_view text = line.text;
  section->pos = line.At(open);
  size_t close = text.find(']', open);
  if (close == std::string_view::npos) {
    diagnostics->push_back(
        MakeDiagnostic(line.At(open), "unterminated section header (missing ']')"));
    close = TrimmedEnd(text, open, text.size());
  } else if (const size_t after = SkipBlanks(text, close + 1); after < text.size()) {
    diagnostics->push_back(MakeDiagnostic(line.At(after), "unexpected text after section header"));
  }
  std::vector<std::pair<std::string_view, size_t>> words;
  for (size_t i = SkipBlanks(text, open + 1); i < close; i = SkipBlanks(text, i)) {
    size_t end = i;
    while (end < close && !IsBlank(text[end])) ++end;
    words.push_back({text.substr(i, end - i), i});
    i = end;
  }
  if (words.empty()) {
    diagnostics->push_back(MakeDiagnostic(line.At(open), "empty section header"));
    return false;
  }
  section->kind = std::string(words[0].first);
  section->kind_pos = line.At(words[0].second);
  if (words.size() < 2) return true;
  // "name", or "name: group" with or without blanks around the ':'.
  const size_t rest = words[1].second;
  const size_t colon = text.substr(0, close).find(':', rest);
  const size_t name_end = colon == std::string_view::npos ? close : colon;
  size_t end = rest;
  while (end < name_end && !IsBlank(text[end])) ++end;
  section->name = std::string(text.substr(rest, end - rest));
  section->name_pos = line.At(rest);
  size_t extra = SkipBlanks(text, end);
  if (colon != std::string_view::npos && extra == colon) {
    const size_t g = SkipBlanks(text, colon + 1);
    size_t g_end = g;
    while (g_end < close && !IsBlank(text[g_end])) ++g_end;
    section->group = std::string(text.substr(g, g_end - g));
    section->group_pos = line.At(g);
    if (section->group.empty())
      diagnostics->push_back(MakeDiagnostic(line.At(colon), "missing group name after ':'"));
    extra = SkipBlanks(text, g_end);
  }
  if (extra < close)
    diagnostics->push_back(MakeDiagnostic(line.At(extra), "too many words in section header"));
  return true;
}

// "key = value" with the text starting at text[begin].
bool ReadEntry(const Line& line, size_t begin, IniEntry* entry,
               std::vector<Diagnostic>* diagnostics) {
  const std::string_view text = line.text;
  const size_t equals = text.find('=', begin);
  if (equals == std::string_view::npos) {
    diagnostics->push_back(MakeDiagnostic(line.At(begin), "expected 'name = value'"));
    return false;
  }
  const size_t key_end = TrimmedEnd(text, begin, equals);
  if (key_end == begin) {
    diagnostics->push_back(MakeDiagnostic(line.At(equals), "missing name before '='"));
    return false;
  }
  entry->key = std::string(text.substr(begin, key_end - begin));
  entry->key_pos = line.At(begin);
  const size_t value_begin = SkipBlanks(text, equals + 1);
  const size_t value_end = TrimmedEnd(text, value_begin, text.size());
  entry->value = std::string(text.substr(value_begin, value_end - value_begin));
  entry->value_pos = line.At(value_begin);
  return true;
}

}  // namespace

std::vector<IniSection> SplitIniSections(std::string_view text,
                                         std::vector<Diagnostic>* diagnostics) {
  std::vector<IniSection> sections;
  bool reported_orphan = false;
  bool skipping = false;  // inside an unusable header's section
  int number = 0;
  for (size_t start = 0; start <= text.size(); ++number) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    Line line{text.substr(start, end - start), number + 1};
    start = end + 1;
    if (!line.text.empty() && line.text.back() == '\r') line.text.remove_suffix(1);
    line.text = line.text.substr(0, line.text.find('#'));
    const size_t first = SkipBlanks(line.text, 0);
    if (first == line.text.size()) continue;
    if (line.text[first] == '[') {
      IniSection section;
      skipping = !ReadHeader(line, first, &section, diagnostics);
      if (!skipping) sections.push_back(std::move(section));
      continue;
    }
    IniEntry entry;
    if (sections.empty() && !skipping) {
      if (!reported_orphan)
        diagnostics->push_back(
            MakeDiagnostic(line.At(first), "text before the first section header"));
      reported_orphan = true;
    } else if (!ReadEntry(line, first, &entry, diagnostics)) {
      if (!sections.empty() && !skipping) ++sections.back().malformed_lines;
    } else if (!skipping) {
      sections.back().entries.push_back(std::move(entry));
    }
  }
  return sections;
}

}  // namespace estlab::modelfile
