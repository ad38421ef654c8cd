#include "src/core/interrupt.h"

namespace estlab {

std::atomic<bool> g_interrupt_requested{false};

}  // namespace estlab
