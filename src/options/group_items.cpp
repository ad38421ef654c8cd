#include "src/options/group_items.h"

#include "src/core/parse.h"
#include "src/core/types.h"

namespace estlab {

std::vector<std::pair<std::string, std::string>> ParseGroupItems(const std::string& text,
                                                                 const std::string& key,
                                                                 const std::string& value_name) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string& item : SplitTrimmed(text, ',')) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos || Trim(item.substr(0, eq)).empty())
      throw InputError(key + ": expected GROUP=" + value_name + ", got '" + item + "'");
    const std::string group = Trim(item.substr(0, eq));
    for (const auto& [earlier, value] : out)
      if (earlier == group) throw InputError(key + ": sensor group '" + group + "' is given twice");
    out.emplace_back(group, Trim(item.substr(eq + 1)));
  }
  return out;
}

std::vector<std::string> SplitGroupValues(const std::string& text) {
  if (text.find('=') == std::string::npos) return {text};
  std::vector<std::string> out;
  for (const std::string& item : SplitTrimmed(text, ',')) {
    if (out.empty() || item.find('=') != std::string::npos)
      out.push_back(item);
    else
      out.back() += "," + item;
  }
  return out;
}

}  // namespace estlab
