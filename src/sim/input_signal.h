// Seeded input signals for simulated experiments: what a study scenario's
// `input = ...` may be besides a constant (docs/studies.md, "Inputs").
// Sampled at the measurement times; the simulation and every filter hold
// each sample until the next (zero-order hold) or follow the line between
// them (--input-hold linear, src/ode/input_path.h).
//
//   2.5                            a constant
//   multisine(rms=0.5, mean=0, band=0.001:0.05, sines=10, seed=1)
//       u(t) = mean + rms sqrt(2/N) sum_i cos(2 pi f_i t + phi_i),
//       N = sines frequencies f_i evenly spaced over the band (both ends
//       included; one sine: the band's low end), phases phi_i uniform on
//       [0, 2 pi) from the seed; the deviation's mean square over a whole
//       common period is rms^2.
//   prbs(amplitude=1, mean=0, period=2, order=10, seed=1)
//       u(t) = mean +- amplitude by the bits b_j of the maximum-length
//       sequence of a `order`-bit linear feedback shift register (length
//       2^order - 1, then it repeats), each held `period` seconds:
//       j = floor(t / period); the register starts from `seed` mod 2^order
//       (0 is taken as 1).
//   steps(2.5, 200:3, 500:2)
//       the first value until the first time, then each value from its time
//       on (times strictly increasing).
//   file(pump.csv)  or  file(pump.csv, volts)
//       a recorded input: the file's `t` column and its `u` column (or the
//       one named), each value held until the next row's time; a relative
//       path is relative to `base_dir`. Times must increase and values be
//       finite (errors name file and line); sampling outside [first, last]
//       row time is refused by Covers().
//
// multisine needs rms and band (f1 < f2 for two sines or more), prbs needs
// amplitude; the other keys have the defaults shown. A time within 1e-9
// (relative, at least 1e-9 s) of a step, a bit boundary or a row counts as
// reached, so that k dt rounding (3 x 0.3 = 0.8999999999999999) does not
// move a switch by a sample. Errors name the key and the signal as written.
//
// Usage:
//   const InputSignal s = ParseInputSignal("prbs(amplitude=0.5, period=4)", "input");
//   if (const std::string why = s.Covers(0, 100); !why.empty()) ...
//   double u = s.At(12.0);
#ifndef ESTLAB_SIM_INPUT_SIGNAL_H_
#define ESTLAB_SIM_INPUT_SIGNAL_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace estlab {

struct InputSignal {
  enum Kind { kConstant, kMultisine, kPrbs, kSteps, kRecorded };
  Kind kind = kConstant;
  double mean = 0.0;                             // constant: the value
  double scale = 0.0;                            // multisine: rms; prbs: amplitude
  std::vector<double> freqs, phases;             // multisine
  double period = 1.0;                           // prbs
  std::vector<bool> bits;                        // prbs: one period of the sequence
  std::vector<std::pair<double, double>> steps;  // (time, value) after the first value;
                                                 // recorded: every row (time, value)
  std::string path;                              // recorded: the file read

  double At(double t) const;  // NaN for a non-finite t
  // "" when every time in [t_first, t_last] can be sampled, else why not
  // (a recorded input that starts later or ends earlier, beyond the 1e-9
  // slack).
  std::string Covers(double t_first, double t_last) const;
};

// Throws InputError("<what>: ...") naming the key or argument at fault;
// file(...) paths are relative to base_dir (the working folder when empty).
InputSignal ParseInputSignal(const std::string& text, const std::string& what,
                             const std::string& base_dir = "");

// One signal per input of a model with inputs `names`: `text` is a list
// split at its top-level commas (a comma inside a signal's parentheses
// belongs to the signal), item i for input i. "1.5, 0" is two constants;
// "multisine(rms=1, band=0.01:0.1, seed=1), prbs(amplitude=2, seed=2)" two
// signals (give each its own seed: two multisines with the same seed have
// the same phases). Throws InputError naming the count, or the input whose
// item is wrong ("<what> (input F): ...").
std::vector<InputSignal> ParseInputSignals(const std::string& text, const std::string& what,
                                           const std::vector<std::string>& names,
                                           const std::string& base_dir = "");

// One period of the maximum-length sequence of an order-bit Galois LFSR
// (2 <= order <= 20) from the start state mod 2^order (0 taken as 1).
std::vector<bool> MaximumLengthSequence(int order, uint32_t start);

}  // namespace estlab

#endif  // ESTLAB_SIM_INPUT_SIGNAL_H_
