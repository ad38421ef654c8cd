// Seeded input signals; the equations are in input_signal.h.
#include "src/sim/input_signal.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <map>
#include <set>

#include "src/core/parse.h"
#include "src/core/random.h"
#include "src/core/types.h"
#include "src/io/csv_reader.h"
#include "src/io/output_file.h"

namespace estlab {

namespace {

constexpr double kPi = 3.14159265358979323846;

// t moved forward by the slack within which a switching time counts as
// reached (input_signal.h): 1e-9 relative, at least 1e-9 s.
double Reached(double t) { return t + 1e-9 * std::max(1.0, std::abs(t)); }

// The taps of a primitive polynomial per order (x^order + ... + 1), as bit
// positions 1..order: a Galois register with these taps runs through all
// 2^order - 1 nonzero states.
const std::map<int, std::vector<int>>& PrimitiveTaps() {
  static const std::map<int, std::vector<int>> taps = {
      {2, {2, 1}},         {3, {3, 2}},         {4, {4, 3}},           {5, {5, 3}},
      {6, {6, 5}},         {7, {7, 6}},         {8, {8, 6, 5, 4}},     {9, {9, 5}},
      {10, {10, 7}},       {11, {11, 9}},       {12, {12, 6, 4, 1}},   {13, {13, 4, 3, 1}},
      {14, {14, 5, 3, 1}}, {15, {15, 14}},      {16, {16, 15, 13, 4}}, {17, {17, 14}},
      {18, {18, 11}},      {19, {19, 6, 2, 1}}, {20, {20, 17}}};
  return taps;
}

// "name(a, k=v, ...)" -> name and its arguments, blanks trimmed.
bool SplitCall(const std::string& text, std::string* name, std::vector<std::string>* args) {
  const size_t open = text.find('(');
  if (open == std::string::npos || text.back() != ')') return false;
  *name = Trim(text.substr(0, open));
  const std::string inside = text.substr(open + 1, text.size() - open - 2);
  size_t from = 0;
  while (from <= inside.size()) {
    const size_t comma = std::min(inside.find(',', from), inside.size());
    args->push_back(Trim(inside.substr(from, comma - from)));
    from = comma + 1;
  }
  if (args->size() == 1 && args->front().empty()) args->clear();
  return true;
}

// The k=v arguments of multisine and prbs, each key at most once and known.
std::map<std::string, std::string> KeyValues(const std::vector<std::string>& args,
                                             const std::set<std::string>& known,
                                             const std::string& where) {
  std::map<std::string, std::string> kv;
  for (const std::string& a : args) {
    const size_t eq = a.find('=');
    const std::string key = Trim(a.substr(0, eq));
    if (eq == std::string::npos || key.empty())
      throw InputError(where + ": expected key=value, got '" + a + "'");
    if (!known.count(key)) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw InputError(where + ": unknown key '" + key + "' (expected " + list + ")");
    }
    if (!kv.emplace(key, Trim(a.substr(eq + 1))).second)
      throw InputError(where + ": '" + key + "' given twice");
  }
  return kv;
}

double Number(const std::map<std::string, std::string>& kv, const std::string& key, double fallback,
              const std::string& where, bool required = false) {
  const auto it = kv.find(key);
  if (it == kv.end()) {
    if (required) throw InputError(where + ": '" + key + "=' is required");
    return fallback;
  }
  return ParseNumber(it->second, where + " " + key);
}

int Integer(const std::map<std::string, std::string>& kv, const std::string& key, int fallback,
            int lo, int hi, const std::string& where) {
  const double v = Number(kv, key, fallback, where);
  if (v != std::floor(v) || v < lo || v > hi)
    throw InputError(where + " " + key + ": expected a whole number in " + std::to_string(lo) +
                     ".." + std::to_string(hi) + ", got " + FormatNumber(v));
  return int(v);
}

// A signal around `mean` (default 0) with its required scale (> 0).
InputSignal AroundMean(const std::map<std::string, std::string>& kv, InputSignal::Kind kind,
                       const std::string& scale_key, const std::string& where) {
  InputSignal s;
  s.kind = kind;
  s.scale = Number(kv, scale_key, 0.0, where, true);
  s.mean = Number(kv, "mean", 0.0, where);
  if (!(s.scale > 0)) throw InputError(where + " " + scale_key + ": must be > 0");
  return s;
}

InputSignal Multisine(const std::vector<std::string>& args, const std::string& where) {
  const auto kv = KeyValues(args, {"rms", "mean", "band", "sines", "seed"}, where);
  InputSignal s = AroundMean(kv, InputSignal::kMultisine, "rms", where);
  const int sines = Integer(kv, "sines", 10, 1, 10000, where);
  const int seed = Integer(kv, "seed", 1, 0, 2147483647, where);
  const auto band = kv.find("band");
  if (band == kv.end()) throw InputError(where + ": 'band=f1:f2' (Hz) is required");
  const size_t colon = band->second.find(':');
  if (colon == std::string::npos)
    throw InputError(where + " band: expected f1:f2 in Hz, got '" + band->second + "'");
  const double f1 = ParseNumber(band->second.substr(0, colon), where + " band");
  const double f2 = ParseNumber(band->second.substr(colon + 1), where + " band");
  if (!(f1 > 0 && (sines == 1 ? f2 >= f1 : f2 > f1)))
    throw InputError(where + " band: expected 0 < f1 " + (sines == 1 ? "<=" : "<") + " f2, got '" +
                     band->second + "'");
  Rng rng(DeriveSeed({uint64_t(seed), 0x6D756C7469ull}));  // "multi"
  for (int i = 0; i < sines; ++i) {
    s.freqs.push_back(sines == 1 ? f1 : f1 + (f2 - f1) * double(i) / double(sines - 1));
    s.phases.push_back(2 * kPi * rng.Uniform());
  }
  return s;
}

InputSignal Prbs(const std::vector<std::string>& args, const std::string& where) {
  const auto kv = KeyValues(args, {"amplitude", "mean", "period", "order", "seed"}, where);
  InputSignal s = AroundMean(kv, InputSignal::kPrbs, "amplitude", where);
  s.period = Number(kv, "period", 1.0, where);
  if (!(s.period > 0)) throw InputError(where + " period: must be > 0 s");
  const int order = Integer(kv, "order", 10, 2, 20, where);
  const int seed = Integer(kv, "seed", 1, 0, 2147483647, where);
  s.bits = MaximumLengthSequence(order, uint32_t(seed));
  return s;
}

InputSignal Steps(const std::vector<std::string>& args, const std::string& where) {
  if (args.empty()) throw InputError(where + ": steps(first value, t1:v1, ...) needs a value");
  InputSignal s;
  s.kind = InputSignal::kSteps;
  s.mean = ParseNumber(args[0], where + " first value");
  for (size_t i = 1; i < args.size(); ++i) {
    const size_t colon = args[i].find(':');
    if (colon == std::string::npos)
      throw InputError(where + ": expected time:value, got '" + args[i] + "'");
    const double t = ParseNumber(args[i].substr(0, colon), where + " step time");
    const double v = ParseNumber(args[i].substr(colon + 1), where + " step value");
    if (!s.steps.empty() && !(t > s.steps.back().first))
      throw InputError(where + ": step times must increase, got " + FormatNumber(t) + " after " +
                       FormatNumber(s.steps.back().first));
    s.steps.emplace_back(t, v);
  }
  return s;
}

// file(path[, column]): the rows of a recorded input.
InputSignal Recorded(const std::vector<std::string>& args, const std::string& where,
                     const std::string& base_dir) {
  if (args.empty() || args.size() > 2 || args[0].empty())
    throw InputError(where + ": expected file(path) or file(path, column)");
  InputSignal s;
  s.kind = InputSignal::kRecorded;
  const std::filesystem::path path(args[0]);
  s.path = path.is_absolute() || base_dir.empty()
               ? path.string()
               : (std::filesystem::path(base_dir) / path).string();
  const CsvTable table = ReadCsv(s.path);
  const std::string column = args.size() == 2 ? args[1] : "u";
  const int t_col = table.ColumnIndex("t"), u_col = table.ColumnIndex(column);
  if (t_col < 0 || u_col < 0)
    throw InputError(where + ": " + s.path + " has no '" + (t_col < 0 ? "t" : column) + "' column");
  for (size_t i = 0; i < table.rows.size(); ++i) {
    const double t = table.rows[i][size_t(t_col)], u = table.rows[i][size_t(u_col)];
    const std::string at = s.path + ":" + std::to_string(table.line_numbers[i]);
    if (!std::isfinite(t) || !std::isfinite(u))
      throw InputError(where + ": " + at + ": missing " + (std::isfinite(t) ? column : "t"));
    if (!s.steps.empty() && !(t > s.steps.back().first))
      throw InputError(where + ": " + at + ": t = " + FormatNumber(t) + " does not increase");
    s.steps.emplace_back(t, u);
  }
  if (s.steps.empty()) throw InputError(where + ": " + s.path + " has no rows");
  return s;
}

}  // namespace

std::vector<bool> MaximumLengthSequence(int order, uint32_t start) {
  const auto it = PrimitiveTaps().find(order);
  if (it == PrimitiveTaps().end())
    throw InputError("prbs order: expected 2..20, got " + std::to_string(order));
  uint32_t mask = 0;
  for (int t : it->second) mask |= 1u << (t - 1);
  const uint32_t length = (1u << order) - 1;
  uint32_t state = start % (length + 1);
  if (state == 0) state = 1;
  std::vector<bool> bits(length);
  for (uint32_t j = 0; j < length; ++j) {  // Galois register: out the low bit
    bits[j] = state & 1u;
    state = (state >> 1) ^ ((state & 1u) ? mask : 0u);
  }
  return bits;
}

double InputSignal::At(double t) const {
  if (!std::isfinite(t)) return std::nan("");
  switch (kind) {
    case kConstant:
      return mean;
    case kMultisine: {
      double sum = 0.0;
      for (size_t i = 0; i < freqs.size(); ++i) sum += std::cos(2 * kPi * freqs[i] * t + phases[i]);
      return mean + scale * std::sqrt(2.0 / double(freqs.size())) * sum;
    }
    case kPrbs: {
      const double j = std::floor(Reached(t) / period);
      const size_t index = size_t(std::fmod(std::max(j, 0.0), double(bits.size())));
      return mean + (bits[index] ? scale : -scale);
    }
    case kSteps:
    case kRecorded: {  // the last (time, value) at or before t
      const auto after = std::upper_bound(
          steps.begin(), steps.end(), Reached(t),
          [](double time, const std::pair<double, double>& step) { return time < step.first; });
      if (after == steps.begin()) return kind == kSteps ? mean : steps.front().second;
      return std::prev(after)->second;
    }
  }
  return mean;
}

std::string InputSignal::Covers(double t_first, double t_last) const {
  if (kind != kRecorded) return "";
  if (Reached(t_first) < steps.front().first || t_last > Reached(steps.back().first))
    return "the input of " + path + " covers t = " + FormatDouble(steps.front().first) + " .. " +
           FormatDouble(steps.back().first) + ", not " + FormatDouble(t_first) + " .. " +
           FormatDouble(t_last);
  return "";
}

InputSignal ParseInputSignal(const std::string& text, const std::string& what,
                             const std::string& base_dir) {
  const std::string s = Trim(text);
  std::string name;
  std::vector<std::string> args;
  if (!SplitCall(s, &name, &args)) {
    InputSignal c;
    c.mean = ParseNumber(s, what);
    return c;
  }
  const std::string where = what + " " + name + "(...)";
  if (name == "multisine") return Multisine(args, where);
  if (name == "prbs") return Prbs(args, where);
  if (name == "steps") return Steps(args, where);
  if (name == "file") return Recorded(args, where, base_dir);
  throw InputError(what + ": unknown signal '" + name +
                   "' (expected a number, multisine(...), prbs(...), steps(...) or file(...))");
}

std::vector<InputSignal> ParseInputSignals(const std::string& text, const std::string& what,
                                           const std::vector<std::string>& names,
                                           const std::string& base_dir) {
  std::vector<std::string> items(1);
  int depth = 0;
  for (char c : text) {
    depth += c == '(' ? 1 : c == ')' ? -1 : 0;
    if (c == ',' && depth == 0)
      items.emplace_back();
    else
      items.back() += c;
  }
  if (items.size() != names.size()) {
    std::string order;
    for (const std::string& n : names) {
      if (!order.empty()) order += ", ";
      order += n;
    }
    throw InputError(what + ": " + std::to_string(items.size()) + " item(s) for " +
                     std::to_string(names.size()) +
                     " inputs (one constant or signal per input, comma-separated, in the order " +
                     order + ")");
  }
  std::vector<InputSignal> signals;
  for (size_t i = 0; i < items.size(); ++i) {
    const std::string where = names.size() > 1 ? what + " (input " + names[i] + ")" : what;
    if (Trim(items[i]).empty()) throw InputError(where + ": empty item");
    signals.push_back(ParseInputSignal(items[i], where, base_dir));
  }
  return signals;
}

}  // namespace estlab
