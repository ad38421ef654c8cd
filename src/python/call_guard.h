// How the Python module runs a command: one call at a time (the commands
// share process state: the in-memory files, stdout), with the GIL released,
// the command's stdout and stderr kept, and Ctrl-C held back until it
// returns.
//
// Usage (the GIL held):
//   std::string out, err;
//   int status;
//   {
//     CallGuard guard(&out, &err);   // releases the GIL
//     status = RunTune(args);
//   }                                // GIL back
//   CallGuard::RaiseIfInterrupted(); // KeyboardInterrupt after a Ctrl-C
#ifndef ESTLAB_PYTHON_CALL_GUARD_H_
#define ESTLAB_PYTHON_CALL_GUARD_H_

#include <pybind11/pybind11.h>

#include <signal.h>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>

namespace estlab::python {

class CallGuard {
 public:
  // out, err: where the command's std::cout and std::cerr go (null: left).
  CallGuard(std::string* out, std::string* err);
  ~CallGuard();
  CallGuard(const CallGuard&) = delete;
  CallGuard& operator=(const CallGuard&) = delete;

  // Raises KeyboardInterrupt when Ctrl-C came during the last call (the GIL
  // held).
  static void RaiseIfInterrupted();

 private:
  pybind11::gil_scoped_release release_;
  std::unique_lock<std::mutex> lock_;
  std::string *out_, *err_;
  std::ostringstream out_buf_, err_buf_;
  std::streambuf *old_out_ = nullptr, *old_err_ = nullptr;
  struct sigaction old_int_ {};
};

}  // namespace estlab::python

#endif  // ESTLAB_PYTHON_CALL_GUARD_H_
