// Instantiates the likelihood tuner (adaptive/tuner_impl.h) for
// models::Pendulum in its own translation unit, so that the Jet-heavy templates
// of one model compile in parallel with, and independently of, the others.
#include "adaptive/tuner_impl.h"
#include "models/pendulum.h"

template estlab::TuneResult estlab::TuneModel<estlab::models::Pendulum>(
    const estlab::FilterSpec&, const estlab::TunerOptions&, const std::vector<estlab::FilterData>&);
