#include "src/options/sensor_rates.h"

#include <cmath>

#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/options/group_items.h"

namespace estlab {

namespace {

// The groups of `meas`, or one of its own name over every output.
std::vector<OutputGroup> GroupsOf(const MeasurementDesc& meas) {
  if (!meas.groups.empty()) return meas.groups;
  return {{meas.name, 0, int(meas.outputs.size())}};
}

std::string Names(const std::vector<OutputGroup>& groups) {
  std::string out;
  for (const OutputGroup& g : groups) out += (out.empty() ? "" : ", ") + g.name;
  return out;
}

// Rows per sample of "GROUP=VALUE": VALUE in Hz (rate) or rows (every).
int Period(const std::string& value, bool rate, double dt, const std::string& key,
           const std::string& group) {
  if (!rate) return ParseCount(value, key + " (" + group + ")", 1, 1000000000);
  const double hz = ParseNumber(value, key);
  if (!(hz > 0)) throw InputError(key + ": the rate of '" + group + "' must be > 0 Hz");
  if (!(dt > 0))
    throw InputError(key + ": a rate needs rows on a uniform grid (--dt); use the every-k form");
  const double rows = 1.0 / (hz * dt);
  const double k = std::round(rows);
  if (k < 1 || k > 1e9 || std::abs(rows - k) > 1e-6 * rows) {
    throw InputError(key + ": " + group + " at " + FormatNumber(hz) + " Hz is " +
                     FormatNumber(rows) + " rows of " + FormatNumber(dt) +
                     " s: give a rate that is a whole number of rows");
  }
  return int(k);
}

}  // namespace

std::vector<int> OutputEvery(const MeasurementDesc& meas, const std::string& rate_text,
                             const std::string& every_text, double dt, const std::string& rate_key,
                             const std::string& every_key) {
  const std::vector<OutputGroup> groups = GroupsOf(meas);
  std::vector<int> every(meas.outputs.size(), 1);
  std::vector<bool> seen(groups.size(), false);
  for (const bool rate : {true, false}) {
    const std::string& text = rate ? rate_text : every_text;
    const std::string& key = rate ? rate_key : every_key;
    if (Trim(text).empty()) continue;
    for (const auto& [name, value] : ParseGroupItems(text, key, rate ? "HZ" : "K")) {
      size_t g = 0;
      while (g < groups.size() && groups[g].name != name) ++g;
      if (g == groups.size()) {
        throw InputError(key + ": unknown sensor group '" + name + "' (groups of " + meas.name +
                         ": " + Names(groups) + ")");
      }
      if (seen[g]) throw InputError(key + ": sensor group '" + name + "' is given twice");
      seen[g] = true;
      const int k = Period(value, rate, dt, key, name);
      for (int j = 0; j < groups[g].count; ++j) every[size_t(groups[g].first + j)] = k;
    }
  }
  return every;
}

}  // namespace estlab
