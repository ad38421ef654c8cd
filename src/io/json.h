// A small JSON writer for summaries (`--json`) and sidecar files. Numbers are
// written with full double precision; non-finite numbers become null.
//
// Usage:
//   JsonWriter j;
//   j.BeginObject().Key("steps").Value(1000).Key("rmse").BeginObject()...EndObject().EndObject();
//   std::cout << j.str() << "\n";
#ifndef ESTLAB_IO_JSON_H_
#define ESTLAB_IO_JSON_H_

#include <string>
#include <vector>

namespace estlab {

class JsonWriter {
 public:
  JsonWriter& BeginObject();
  JsonWriter& EndObject();
  JsonWriter& BeginArray();
  JsonWriter& EndArray();
  JsonWriter& Key(const std::string& key);
  JsonWriter& Value(double v);
  JsonWriter& Value(long v);
  JsonWriter& Value(int v) { return Value(long(v)); }
  JsonWriter& Value(bool v);
  JsonWriter& Value(const std::string& v);
  JsonWriter& Value(const char* v) { return Value(std::string(v)); }
  JsonWriter& Value(const std::vector<double>& v);
  JsonWriter& Value(const std::vector<std::string>& v);
  // {"names[0]": values[0], ...} (the same number of each).
  JsonWriter& Object(const std::vector<std::string>& names, const std::vector<double>& values);
  JsonWriter& Null();
  const std::string& str() const { return out_; }

  static std::string Escape(const std::string& s);
  static std::string Number(double v);

 private:
  void Separate();
  std::string out_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

}  // namespace estlab

#endif  // ESTLAB_IO_JSON_H_
