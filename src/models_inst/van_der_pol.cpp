// Instantiates every template estlab needs for models::VanDerPol in this one
// translation unit (transitions, simulator, filters), so a change to one
// model rebuilds only this file.
#include "models/van_der_pol.h"
#include "src/registry/model_entry_impl.h"

ESTLAB_DEFINE_MODEL_ENTRY(estlab::models::VanDerPol, VanDerPolEntry)
