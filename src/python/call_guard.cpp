#include "src/python/call_guard.h"

#include <atomic>
#include <iostream>

#include "src/core/interrupt.h"

namespace estlab::python {

namespace {

std::mutex& CallMutex() {
  static std::mutex m;
  return m;
}

std::atomic<bool> g_interrupted{false};

// Noted for the call's end, and for the filter runs in it (interrupt.h).
extern "C" void NoteInterrupt(int) {
  g_interrupted = true;
  g_interrupt_requested = true;
}

}  // namespace

CallGuard::CallGuard(std::string* out, std::string* err)
    : lock_(CallMutex()), out_(out), err_(err) {
  g_interrupted = false;
  g_interrupt_requested = false;
  struct sigaction sa {};
  sa.sa_handler = NoteInterrupt;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, &old_int_);
  if (out_) old_out_ = std::cout.rdbuf(out_buf_.rdbuf());
  if (err_) old_err_ = std::cerr.rdbuf(err_buf_.rdbuf());
}

CallGuard::~CallGuard() {
  if (out_) {
    std::cout.rdbuf(old_out_);
    *out_ = out_buf_.str();
  }
  if (err_) {
    std::cerr.rdbuf(old_err_);
    *err_ = err_buf_.str();
  }
  ::sigaction(SIGINT, &old_int_, nullptr);
  g_interrupt_requested = false;
}

void CallGuard::RaiseIfInterrupted() {
  if (!g_interrupted.exchange(false)) return;
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw pybind11::error_already_set();
}

}  // namespace estlab::python
