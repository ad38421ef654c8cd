// The sampling of simulated sensor groups: `--sensor-rate position=1`
// (Hz) and `--sensor-every position=100` (every k-th row) of `estlab
// simulate`, and the same keys of a study's scenario. A group not named is
// sampled every row; a row where a group is not sampled has its outputs
// missing (empty cells), and the filters update with what was measured
// (docs/multirate.md).
//
// Usage:
//   std::vector<int> every = OutputEvery(meas, "position=1", "", 0.01, "--sensor-rate",
//                                        "--sensor-every");  // {100, 1}
//   spec.output_every = every;  // SimulationSpec (src/sim/simulation.h)
#ifndef ESTLAB_OPTIONS_SENSOR_RATES_H_
#define ESTLAB_OPTIONS_SENSOR_RATES_H_

#include <string>
#include <vector>

#include "src/registry/registry.h"

namespace estlab {

// Each output's period in rows, from "GROUP=HZ,..." (rate_text) and
// "GROUP=K,..." (every_text), either may be empty; a measurement without
// groups is one group of its own name. dt: the rows' spacing (0 when not
// uniform: a rate is then refused). Throws InputError naming the option and
// the group: unknown, named twice, a rate that is not a whole number of
// rows, K < 1.
std::vector<int> OutputEvery(const MeasurementDesc& meas, const std::string& rate_text,
                             const std::string& every_text, double dt, const std::string& rate_key,
                             const std::string& every_key);

}  // namespace estlab

#endif  // ESTLAB_OPTIONS_SENSOR_RATES_H_
