// Every filter class, for the code that builds a filter from its options
// (MakeFilter, src/run/filter_run_impl.h). A filter kind's header is listed
// here as part of its registration (src/run/filter_kinds.h); each defines
// the MakeFilterFor overload for its options struct.
#ifndef ESTLAB_FILTERS_FILTERS_H_
#define ESTLAB_FILTERS_FILTERS_H_

#include "src/filters/ekf.h"          // EkfOptions
#include "src/filters/kalman.h"       // KfOptions
#include "src/filters/particle.h"     // ParticleOptions
#include "src/filters/sigma_point.h"  // SigmaPointOptions (ukf, ckf, ghkf)

#endif  // ESTLAB_FILTERS_FILTERS_H_
