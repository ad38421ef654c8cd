#include "adaptive/initial_states.h"

#include <algorithm>

#include "src/core/types.h"

namespace estlab {

std::vector<std::string> InitialStates::Names(const std::vector<std::string>& states) const {
  std::vector<std::string> out;
  for (int row = 0; row < rows; ++row)
    for (int i : index)
      out.push_back((rows > 1 ? "x0[" + std::to_string(row + 1) + "] " : "x0 ") + states[i]);
  return out;
}

InitialStates ResolveInitialStates(const std::vector<std::string>& names, bool per_file,
                                   std::size_t datasets, const std::vector<std::string>& states,
                                   const std::string& model) {
  InitialStates out;
  for (const std::string& name : names) {
    if (name.empty()) throw InputError("--estimate-x0: an empty state name");
    const auto it = std::find(states.begin(), states.end(), name);
    if (it == states.end()) {
      std::string list;
      for (const std::string& s : states) list += (list.empty() ? "" : ", ") + s;
      throw InputError("--estimate-x0: '" + name + "' is not a state of model '" + model + "' (" +
                       list + ")");
    }
    const int i = int(it - states.begin());
    if (std::find(out.index.begin(), out.index.end(), i) != out.index.end())
      throw InputError("--estimate-x0: '" + name + "' is named twice");
    out.index.push_back(i);
  }
  if (per_file && names.empty())
    throw InputError("--x0-per-file needs --estimate-x0 (the states estimated per file)");
  if (per_file && datasets < 2)
    throw InputError("--x0-per-file needs two --data files or more (one x0 per file)");
  out.rows = names.empty() ? 0 : (per_file ? int(datasets) : 1);
  return out;
}

}  // namespace estlab
