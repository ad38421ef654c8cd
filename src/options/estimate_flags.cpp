#include "src/options/estimate_flags.h"

#include <cmath>
#include <limits>
#include <sstream>

#include "src/core/parse.h"
#include "src/core/types.h"

namespace estlab {
namespace {

EstimatedParam* Find(std::vector<EstimatedParam>* out, const std::string& name,
                     const std::string& option) {
  for (EstimatedParam& e : *out)
    if (e.name == name) return &e;
  throw InputError(option + ": '" + name + "' is not in --estimate-param");
}

// NAME=REST -> (NAME, REST)
std::pair<std::string, std::string> Assignment(const std::string& item, const std::string& option,
                                               const char* form) {
  const size_t eq = item.find('=');
  if (eq == std::string::npos || Trim(item.substr(0, eq)).empty())
    throw InputError(option + ": expected " + form + ", got '" + item + "'");
  return {Trim(item.substr(0, eq)), Trim(item.substr(eq + 1))};
}

}  // namespace

std::vector<EstimatedParam> ParseEstimatedParams(const std::string& names,
                                                 const std::string& bounds,
                                                 const std::string& priors) {
  std::vector<EstimatedParam> out;
  if (!Trim(names).empty()) {
    for (const std::string& name : SplitTrimmed(names, ',')) {
      if (name.empty()) throw InputError("--estimate-param: empty name in '" + names + "'");
      for (const EstimatedParam& e : out)
        if (e.name == name) throw InputError("--estimate-param: '" + name + "' is named twice");
      out.push_back(EstimatedParam{.name = name});
    }
  }
  if (!Trim(bounds).empty()) {
    for (const std::string& item : SplitTrimmed(bounds, ',')) {
      const auto [name, range] = Assignment(item, "--param-bounds", "NAME=LO:HI");
      const size_t colon = range.find(':');
      if (colon == std::string::npos)
        throw InputError("--param-bounds: expected NAME=LO:HI, got '" + item + "'");
      EstimatedParam* e = Find(&out, name, "--param-bounds");
      const std::string lo = Trim(range.substr(0, colon)), hi = Trim(range.substr(colon + 1));
      const std::string what = "--param-bounds " + name;
      if (!lo.empty()) e->lower = ParseNumber(lo, what);
      if (!hi.empty()) e->upper = ParseNumber(hi, what);
    }
  }
  if (!Trim(priors).empty()) {
    for (const std::string& item : SplitTrimmed(priors, ',')) {
      const auto [name, rest] = Assignment(item, "--param-prior", "NAME=normal:MEAN:SD");
      const std::vector<std::string> parts = SplitTrimmed(rest, ':');
      if (parts.size() != 3 || parts[0] != "normal")
        throw InputError("--param-prior: expected NAME=normal:MEAN:SD, got '" + item + "'");
      EstimatedParam* e = Find(&out, name, "--param-prior");
      if (e->has_prior) throw InputError("--param-prior: '" + name + "' has two priors");
      e->has_prior = true;
      e->prior_mean = ParseNumber(parts[1], "--param-prior " + name);
      e->prior_sd = ParseNumber(parts[2], "--param-prior " + name);
      if (!(e->prior_sd > 0))
        throw InputError("--param-prior " + name + ": sd must be > 0, got " + parts[2]);
    }
  }
  return out;
}

std::vector<std::string> ParseEstimatedStates(const std::string& names) {
  std::vector<std::string> out;
  if (Trim(names).empty()) return out;
  for (const std::string& name : SplitTrimmed(names, ',')) {
    if (name.empty()) throw InputError("--estimate-x0: an empty state name in '" + names + "'");
    out.push_back(name);
  }
  return out;
}

}  // namespace estlab
