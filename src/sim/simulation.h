// What `estlab simulate` (and the studies' truth) asks a model's simulator
// to do, and what it returns, in plain runtime types.
#ifndef ESTLAB_SIM_SIMULATION_H_
#define ESTLAB_SIM_SIMULATION_H_

#include <cstdint>
#include <string>
#include <vector>

#include "src/ode/transition.h"

namespace estlab {

// What to simulate. Vectors are already resolved to full length by the
// registry (ResolveParams, ResolveState).
struct SimulationSpec {
  std::vector<double> params;  // in the model's parameter order
  std::vector<double> x0;
  double t_end = 10.0;
  double dt = 0.01;
  TransitionOptions transition;
  // The constant input, one value per model input (empty = 0 for each), when
  // `inputs` is empty.
  std::vector<double> input;
  // A recorded schedule (`estlab simulate --data`, output error, free
  // simulation): when not empty, rows are written at these times (the first
  // is x0's time) instead of k dt, and t_end and dt are not used. `inputs`
  // (empty, or one row of nu values per time, row-major) is held over
  // [times[k], times[k+1]) (transition.input_hold = zoh: piecewise constant
  // between samples), or follows the line between the samples (linear);
  // CVODES restarts at every sample where the input changes or bends.
  std::vector<double> times;
  std::vector<double> inputs;
  // When not empty, columns of these names (one per model input) after the
  // states: the input held from each row on.
  std::vector<std::string> input_columns;
  // Adds the noise-free outputs y_<output> after the z_ columns.
  bool noise_free_outputs = false;
  std::vector<double> process_noise_var;  // empty = none, else one per state
  // Full process-noise covariance per output step (n x n, row-major, PSD);
  // used instead of process_noise_var when not empty.
  std::vector<double> process_noise_cov;
  std::string measurement;             // empty = none
  std::vector<double> meas_noise_var;  // empty = none, else one per output
  // Sensor rates (src/options/sensor_rates.h): empty = every output in every
  // row; else one period per output, z_j measured in rows k = 0, e, 2e, ...
  // and missing (NaN, an empty cell) in the others. The noise is drawn in
  // every row, so the data equal the full-rate data with cells emptied.
  std::vector<int> output_every;
  uint64_t seed = 1;
};

struct SimulationResult {
  std::vector<std::string> columns;       // t, states[, u], z_<outputs>[, y_<outputs>]
  std::vector<std::vector<double>> rows;  // one per output time computed
  bool ok = true;
  std::string error;  // CVODES' reason when !ok
  long steps = 0;
  TransitionStats stats;
  double wall_s = 0.0;
  // Invariants (energy, momentum) at t0 and their largest relative drift
  // max_k |I_k - I_0| / |I_0| (absolute when I_0 = 0); empty when the model
  // has none or they do not hold (damping, input, process noise).
  std::vector<std::string> invariant_names;
  std::vector<double> invariant_initial;
  std::vector<double> invariant_drift;
};

}  // namespace estlab

#endif  // ESTLAB_SIM_SIMULATION_H_
