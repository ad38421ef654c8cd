// Keyword arguments as the command line's texts: the one rule by which
// `estlab.filter(..., q_diag=[1e-6, 1e-4], x0={'theta': 0.5})` becomes
// `--q-diag 1e-06,0.0001 --x0 theta=0.5` (the package's other commands call
// it through `values`). A float is written as Python's repr writes it (the
// shortest text that reads back to the same double), so the CLI and the
// module parse the same numbers.
//
//   value                          text
//   'ukf'                          ukf
//   0.01, 3                        0.01, 3
//   [1e-6, 1e-4], np.array(...)    1e-06,0.0001
//   ['imu', 'gps']                 imu,gps
//   {'theta': 0.5}                 theta=0.5
//   [[1, 0], [0, 1]]               1,0;0,1
#ifndef ESTLAB_PYTHON_KEYWORDS_H_
#define ESTLAB_PYTHON_KEYWORDS_H_

#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace estlab::python {

// The text of `value`; InputError for a bool, a non-number or an array of
// more than two dimensions.
std::string Text(pybind11::handle value);

// The texts the command line gives keyword `name` of estlab.COMMAND (an
// option of kind "flag", "repeatable" or "value") for `value`: a flag
// gives {"true"} when set, {} when not; a repeatable key one text per item
// of a list of strings or of a mapping (NAME=VALUE each); the others one.
// InputError names the command and keyword.
std::vector<std::string> Values(const std::string& command, const std::string& name,
                                const std::string& kind, pybind11::handle value);

// Defines `text` and `values` in the module.
void RegisterKeywords(pybind11::module_& m);

}  // namespace estlab::python

#endif  // ESTLAB_PYTHON_KEYWORDS_H_
