#include "src/io/json.h"

#include <cmath>
#include <cstdio>

namespace estlab {

void JsonWriter::Separate() {
  if (after_key_) {
    after_key_ = false;
    return;
  }
  if (!first_.empty()) {
    if (!first_.back()) out_ += ", ";
    first_.back() = false;
  }
}

JsonWriter& JsonWriter::BeginObject() {
  Separate();
  out_ += "{";
  first_.push_back(true);
  return *this;
}
JsonWriter& JsonWriter::EndObject() {
  out_ += "}";
  first_.pop_back();
  return *this;
}
JsonWriter& JsonWriter::BeginArray() {
  Separate();
  out_ += "[";
  first_.push_back(true);
  return *this;
}
JsonWriter& JsonWriter::EndArray() {
  out_ += "]";
  first_.pop_back();
  return *this;
}
JsonWriter& JsonWriter::Key(const std::string& key) {
  Separate();
  out_ += Escape(key) + ": ";
  after_key_ = true;
  return *this;
}
std::string JsonWriter::Number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}
JsonWriter& JsonWriter::Value(double v) {
  Separate();
  out_ += Number(v);
  return *this;
}
JsonWriter& JsonWriter::Value(long v) {
  Separate();
  out_ += std::to_string(v);
  return *this;
}
JsonWriter& JsonWriter::Value(bool v) {
  Separate();
  out_ += v ? "true" : "false";
  return *this;
}
JsonWriter& JsonWriter::Value(const std::string& v) {
  Separate();
  out_ += Escape(v);
  return *this;
}
JsonWriter& JsonWriter::Value(const std::vector<double>& v) {
  BeginArray();
  for (double x : v) Value(x);
  return EndArray();
}
JsonWriter& JsonWriter::Value(const std::vector<std::string>& v) {
  BeginArray();
  for (const auto& x : v) Value(x);
  return EndArray();
}
JsonWriter& JsonWriter::Object(const std::vector<std::string>& names,
                               const std::vector<double>& values) {
  BeginObject();
  for (size_t i = 0; i < names.size() && i < values.size(); ++i) Key(names[i]).Value(values[i]);
  return EndObject();
}
JsonWriter& JsonWriter::Null() {
  Separate();
  out_ += "null";
  return *this;
}

std::string JsonWriter::Escape(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += char(c);
        }
    }
  }
  return out + "\"";
}

}  // namespace estlab
