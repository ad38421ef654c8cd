// Ctrl-C for a caller that must not end the process: the Python module
// (src/python/call_guard.h) sets the flag from its SIGINT handler, and every
// filter run, likelihood evaluation, EM and ALS pass reads it once per row
// (src/run/step_loop.h) and stops; the caller then discards the result. The
// estlab command never sets it (its SIGINT ends the process, temp files
// removed).
//
// A variable, not an inline function's static: a model library compiled at
// run time must read the same flag as the program that loaded it.
#ifndef ESTLAB_CORE_INTERRUPT_H_
#define ESTLAB_CORE_INTERRUPT_H_

#include <atomic>

namespace estlab {

extern std::atomic<bool> g_interrupt_requested;  // src/core/interrupt.cpp

inline bool InterruptRequested() { return g_interrupt_requested.load(std::memory_order_relaxed); }

}  // namespace estlab

#endif  // ESTLAB_CORE_INTERRUPT_H_
