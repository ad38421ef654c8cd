// How the Python module runs a command: one call at a time (the commands
// share process state: the in-memory files, stdout), with the GIL released,
// the command's stdout and stderr kept, and Ctrl-C held back until it
// returns.
//
// Usage (the GIL held):
//   std::string out, err;
//   int status = CallGuard::Call(&out, &err, [&] { return RunTune(args); });
// Call raises KeyboardInterrupt after a Ctrl-C, also when the command
// failed because of it (a model's compiler stopped by the same Ctrl-C).
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

  // f() under a guard; KeyboardInterrupt when Ctrl-C came during it, whether
  // it returned or threw. Call with the GIL held.
  template <typename F>
  static auto Call(std::string* out, std::string* err, F&& f) {
    try {
      auto result = [&] {
        CallGuard guard(out, err);
        return f();
      }();
      RaiseIfInterrupted();
      return result;
    } catch (const pybind11::error_already_set&) {
      throw;
    } catch (...) {
      RaiseIfInterrupted();
      throw;
    }
  }

 private:
  // Raises KeyboardInterrupt when Ctrl-C came during the last call (the GIL
  // held).
  static void RaiseIfInterrupted();

  pybind11::gil_scoped_release release_;
  std::unique_lock<std::mutex> lock_;
  std::string *out_, *err_;
  std::ostringstream out_buf_, err_buf_;
  std::streambuf *old_out_ = nullptr, *old_err_ = nullptr;
  struct sigaction old_int_ {};
};

}  // namespace estlab::python

#endif  // ESTLAB_PYTHON_CALL_GUARD_H_
