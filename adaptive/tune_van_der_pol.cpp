// Instantiates the likelihood tuner (adaptive/tuner_impl.h) for
// models::VanDerPol in its own translation unit, so that the Jet-heavy templates
// of one model compile in parallel with, and independently of, the others.
#include "adaptive/tuner_impl.h"
#include "models/van_der_pol.h"

template estlab::TuneResult estlab::TuneModel<estlab::models::VanDerPol>(
    const estlab::FilterSpec&, const estlab::TunerOptions&, const std::vector<estlab::FilterData>&);
