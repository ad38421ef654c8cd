// The `tuned` noise settings of a study: Q/R (and the model parameters a
// noise setting fits) tuned once per scenario x filter x noise before the
// runs, on their own trajectories DeriveSeed({seed, s, "tune", k}) or the
// scenario's tuning files.
//
// Each result is saved in DIR/tuning/ the moment it is found, exactly
// (%.17g), so that a study interrupted or killed while tuning keeps what it
// tuned, and a resume reuses it instead of tuning again: the folder belongs
// to one configuration (its study.state hash), and each saved result names
// that hash and its scenario, filter and noise, so a file from elsewhere is
// never taken.
//
// Usage:
//   StudyTuningOptions o;
//   o.dir = "results/paper002";   // "" = nothing saved or reused
//   o.jobs = 2;
//   StudyTuningSummary t = TuneStudyNoise(&config, o);   // config's combos now tuned
//   if (t.interrupted) ...;        // options.stop was set: some combos not tuned
#ifndef ESTLAB_STUDIES_STUDY_TUNING_H_
#define ESTLAB_STUDIES_STUDY_TUNING_H_

#include <atomic>
#include <string>

#include "studies/study_config.h"

namespace estlab {

struct StudyTuningOptions {
  std::string dir;  // the results folder; "" = nothing saved or reused
  int jobs = 1;     // tunings run in parallel (each single-threaded)
  // Progress on stderr: one line per finished tuning, or a line rewritten
  // in place (with the running tuner's iteration) on a terminal.
  bool progress = false;
  // When non-null and nonzero: start no new tuning; the running ones finish
  // and are saved.
  const std::atomic<int>* stop = nullptr;
};

struct StudyTuningSummary {
  std::string csv;  // tuned.csv text; "" when no noise setting is tuned
  int total = 0;    // scenario x filter x noise combinations to tune
  int reused = 0;   // found in DIR/tuning/
  int tuned = 0;    // tuned now
  bool interrupted = false;
};

// Tunes every combo of `config` with tune = true (reusing DIR/tuning/), puts
// the tuned Q/R and parameters into its spec, or its failure into
// tune_failure. Deterministic whatever jobs is and however often it resumed.
StudyTuningSummary TuneStudyNoise(StudyConfig* config, const StudyTuningOptions& options);

// The folder of the saved results, DIR/tuning.
std::string TuningFolder(const std::string& dir);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_STUDY_TUNING_H_
