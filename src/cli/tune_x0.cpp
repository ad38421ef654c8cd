#include "src/cli/tune_x0.h"

#include <algorithm>
#include <iomanip>
#include <iostream>

#include "src/io/output_file.h"

namespace estlab::cli {
namespace {

// The estimated components of one row (values or SEs), in r.names' order.
std::vector<double> Estimated(const X0Report& r, const std::vector<double>& row) {
  std::vector<double> out;
  for (const std::string& name : r.names) {
    const auto it = std::find(r.states.begin(), r.states.end(), name);
    out.push_back(row[size_t(it - r.states.begin())]);
  }
  return out;
}

}  // namespace

X0Report MakeX0Report(const std::vector<std::string>& states, const std::vector<std::string>& names,
                      const std::vector<std::vector<double>>& initial,
                      const std::vector<std::vector<double>>& x0,
                      const std::vector<std::vector<double>>& std_errors,
                      const std::vector<FilterData>& runs) {
  X0Report out{.states = states,
               .names = names,
               .initial = initial,
               .x0 = x0,
               .std_errors = std_errors,
               .paths = {}};
  for (const FilterData& d : runs) out.paths.push_back(d.path);
  return out;
}

void PrintX0(const X0Report& r) {
  for (size_t row = 0; row < r.x0.size(); ++row) {
    std::cout << "\n  initial state" << (r.x0.size() > 1 ? " of " + r.paths[row] : "") << "\n";
    const std::vector<double> v0 = Estimated(r, r.initial[row]);
    const std::vector<double> v = Estimated(r, r.x0[row]);
    const std::vector<double> se = Estimated(r, r.std_errors[row]);
    for (size_t i = 0; i < v.size(); ++i)
      std::cout << "  " << std::left << std::setw(26) << r.names[i] << std::right << std::setw(12)
                << v0[i] << " " << std::setw(12) << v[i] << " " << std::setw(10) << se[i] << "\n";
  }
}

void WriteTunedX0Json(JsonWriter* j, const X0Report& r) {
  if (r.x0.size() == 1) j->Key("x0").Object(r.names, Estimated(r, r.x0[0]));
}

void WriteX0DetailJson(JsonWriter* j, const X0Report& r) {
  if (r.x0.size() == 1) {
    j->Key("x0_std_errors").Object(r.names, Estimated(r, r.std_errors[0]));
    j->Key("x0_initial").Object(r.names, Estimated(r, r.initial[0]));
  }
  if (r.x0.size() <= 1) return;
  j->Key("x0_per_file").BeginArray();
  for (size_t row = 0; row < r.x0.size(); ++row) {
    j->BeginObject().Key("data").Value(r.paths[row]);
    j->Key("x0").Object(r.names, Estimated(r, r.x0[row]));
    j->Key("std_errors").Object(r.names, Estimated(r, r.std_errors[row]));
    j->Key("initial").Object(r.names, Estimated(r, r.initial[row]));
    j->EndObject();
  }
  j->EndArray();
}

std::string X0IniLines(const X0Report& r) {
  std::string out;
  for (size_t row = 0; row < r.x0.size(); ++row) {
    std::string line;
    for (size_t i = 0; i < r.states.size(); ++i)
      line += (i ? "," : "") + r.states[i] + "=" + FormatDouble(r.x0[row][i]);
    out += (r.x0.size() == 1 ? "" : "# " + r.paths[row] + ": ") + "x0 = " + line + "\n";
  }
  return out;
}

}  // namespace estlab::cli
