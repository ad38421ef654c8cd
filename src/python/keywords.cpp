#include "src/python/keywords.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "src/core/types.h"

namespace py = pybind11;

namespace estlab::python {

namespace {

// numpy's and collections.abc's types, looked up once (kept for the
// process: no destructor runs after the interpreter is gone).
struct PyTypes {
  py::object bool_, integer, mapping, ndim, asarray, float64;
};
const PyTypes& Types() {
  static const PyTypes* t = [] {
    py::module_ np = py::module_::import("numpy");
    return new PyTypes{np.attr("bool_"),
                       np.attr("integer"),
                       py::module_::import("collections.abc").attr("Mapping"),
                       np.attr("ndim"),
                       np.attr("asarray"),
                       np.attr("float64")};
  }();
  return *t;
}

bool IsBool(py::handle v) { return PyBool_Check(v.ptr()) || py::isinstance(v, Types().bool_); }
bool IsMapping(py::handle v) { return PyDict_Check(v.ptr()) || py::isinstance(v, Types().mapping); }
std::string Repr(py::handle v) { return py::repr(v).cast<std::string>(); }

// Python's repr of a float.
std::string FloatText(double x) {
  char* s = PyOS_double_to_string(x, 'r', 0, Py_DTSF_ADD_DOT_0, nullptr);
  if (s == nullptr) throw py::error_already_set();
  std::string out(s);
  PyMem_Free(s);
  return out;
}

// A number: an integer as itself, anything else as a float.
std::string Number(py::handle v) {
  if (IsBool(v)) throw InputError("a number was expected, got " + Repr(v));
  if (PyLong_Check(v.ptr()) || py::isinstance(v, Types().integer)) {  // str(int(v))
    py::object i = py::reinterpret_steal<py::object>(PyNumber_Long(v.ptr()));
    if (!i) throw py::error_already_set();
    return py::str(i).cast<std::string>();
  }
  return FloatText(py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>());
}

// [1e-6, 3], (0.5,): a list or tuple of Python floats and ints.
bool IsNumberList(py::handle v) {
  if (!PyList_CheckExact(v.ptr()) && !PyTuple_CheckExact(v.ptr())) return false;
  py::sequence s = py::reinterpret_borrow<py::sequence>(v);
  if (s.size() == 0) return false;
  for (py::handle x : s)
    if (!PyFloat_CheckExact(x.ptr()) && !PyLong_CheckExact(x.ptr())) return false;
  return true;
}
// ['imu', 'gps']: a non-empty list or tuple of strings (exact: only str
// itself, not a subclass such as numpy's str_).
bool IsStringList(py::handle v, bool exact) {
  if (!PyList_Check(v.ptr()) && !PyTuple_Check(v.ptr())) return false;
  py::sequence s = py::reinterpret_borrow<py::sequence>(v);
  if (s.size() == 0) return false;
  for (py::handle x : s)
    if (exact ? !PyUnicode_CheckExact(x.ptr()) : !PyUnicode_Check(x.ptr())) return false;
  return true;
}

// The rows of a 1-D (one row) or 2-D float64 array: "1,2;3,4".
std::string ArrayText(const py::array_t<double>& a) {
  const py::ssize_t rows = a.ndim() == 1 ? 1 : a.shape(0);
  const py::ssize_t cols = a.ndim() == 1 ? a.shape(0) : a.shape(1);
  std::string out;
  for (py::ssize_t i = 0; i < rows; ++i) {
    if (i) out += ';';
    for (py::ssize_t j = 0; j < cols; ++j) {
      if (j) out += ',';
      out += FloatText(a.data()[i * cols + j]);
    }
  }
  return out;
}

// Raised by Text for a value it cannot write (and numpy's own TypeError,
// ValueError, OverflowError): "cannot use" with the command and keyword.
[[noreturn]] void CannotUse(const std::string& command, const std::string& name, py::handle value) {
  throw InputError("estlab." + command + ": " + name + ": cannot use " + Repr(value) +
                   " (a number, a list of numbers, a matrix, a mapping or a string)");
}

std::string TextOf(const std::string& command, const std::string& name, py::handle value) {
  try {
    return Text(value);
  } catch (const InputError&) {
    CannotUse(command, name, value);
  } catch (py::error_already_set& e) {
    if (!e.matches(PyExc_TypeError) && !e.matches(PyExc_ValueError) &&
        !e.matches(PyExc_OverflowError))
      throw;
    CannotUse(command, name, value);
  }
}

}  // namespace

std::string Text(py::handle v) {
  PyObject* p = v.ptr();
  if (PyUnicode_CheckExact(p)) return v.cast<std::string>();
  if (PyFloat_CheckExact(p)) return FloatText(PyFloat_AS_DOUBLE(p));
  if (PyLong_CheckExact(p)) return py::str(v).cast<std::string>();
  std::string out;
  if (IsNumberList(v)) {
    for (py::handle x : v) {
      if (!out.empty()) out += ',';
      out += Text(x);  // a float or an int: the lines above
    }
    return out;
  }
  if (IsMapping(v)) {
    py::object items = v.attr("items")();
    for (py::handle kv : items) {
      if (!out.empty()) out += ',';
      out += py::str(kv[py::int_(0)]).cast<std::string>() + "=" + Text(kv[py::int_(1)]);
    }
    return out;
  }
  if (IsStringList(v, false)) {
    for (py::handle x : v) {
      if (!out.empty()) out += ',';
      out += x.cast<std::string>();
    }
    return out;
  }
  const PyTypes& t = Types();
  if (t.ndim(v).cast<int>() == 0) return Number(v);
  py::array_t<double> a = t.asarray(v, py::arg("dtype") = t.float64);
  if (a.ndim() > 2)
    throw InputError("a value of shape " + py::str(a.attr("shape")).cast<std::string>() +
                     " (give a number, a list, or a 2-D matrix)");
  return ArrayText(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a));
}

std::vector<std::string> Values(const std::string& command, const std::string& name,
                                const std::string& kind, py::handle value) {
  PyObject* p = value.ptr();
  if (kind == "flag") {
    if (!IsBool(value))
      throw InputError("estlab." + command + ": " + name + " is a flag: True or False, got " +
                       Repr(value));
    if (PyObject_IsTrue(p)) return {"true"};
    return {};
  }
  if (PyUnicode_CheckExact(p)) return {value.cast<std::string>()};
  if (PyFloat_CheckExact(p) || PyLong_CheckExact(p)) return {Text(value)};
  if (PyList_CheckExact(p) || PyTuple_CheckExact(p)) {
    if (kind == "repeatable" && IsStringList(value, true)) {
      std::vector<std::string> out;
      for (py::handle x : value) out.push_back(x.cast<std::string>());
      return out;
    }
    return {TextOf(command, name, value)};
  }
  if (kind == "repeatable" && IsMapping(value)) {
    std::vector<std::string> out;
    py::object items = value.attr("items")();
    for (py::handle kv : items)
      out.push_back(py::str(kv[py::int_(0)]).cast<std::string>() + "=" +
                    TextOf(command, name, kv[py::int_(1)]));
    return out;
  }
  if (IsBool(value))
    throw InputError("estlab." + command + ": " + name + " takes a value, not " + Repr(value));
  return {TextOf(command, name, value)};
}

void RegisterKeywords(py::module_& m) {
  m.def("text", [](py::handle v) { return Text(v); });
  m.def("values", &Values);
}

}  // namespace estlab::python
