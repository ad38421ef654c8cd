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
//   StudyTunings tunings(config, o);   // then, as tasks: tunings.Tune(i, &config)
#ifndef ESTLAB_STUDIES_RUN_STUDY_TUNING_H_
#define ESTLAB_STUDIES_RUN_STUDY_TUNING_H_

#include <cstdint>
#include <memory>
#include <string>

#include "studies/config/study_config.h"

namespace estlab {

struct StudyTuningOptions {
  std::string dir;  // the results folder; "" = nothing saved or reused
  // Progress on stderr: one line per finished tuning, or a line rewritten
  // in place (with the running tuner's iteration) on a terminal.
  bool progress = false;
  // Threads of a tuning's gradient passes (TunerOptions::jobs; the study's
  // jobs): a tuning on the critical path spreads over the cores the runs
  // leave. The numbers do not depend on it (adaptive/tuner_objective.h).
  int jobs = 1;
};

struct StudyTuningSummary {
  std::string csv;  // tuned.csv text; "" when no noise setting is tuned
  int total = 0;    // scenario x filter x noise combinations to tune
  int reused = 0;   // found in DIR/tuning/
  int tuned = 0;    // tuned now
  bool interrupted = false;
};

// The `tuned` combos of a study (tune = true, not per run), as tasks of the
// study's task pool (src/core/task_pool.h): each pending one is a task, and
// the runs of its scenario wait for it.
//   StudyTunings tunings(config, options);  // finds them; loads DIR/tuning/
//   tunings.ApplyReused(&config);           // before any run
//   tunings.Tune(i, &config);               // pending i: tune, save, apply
//   StudyTuningSummary t = tunings.Summary();
// Tune(i) for distinct i may run at once: each writes only its own combo
// (config->scenarios[s].combos[c]) and its own result. Deterministic
// whatever the order, the jobs and however often the study resumed.
class StudyTunings {
 public:
  StudyTunings(const StudyConfig& config, const StudyTuningOptions& options);
  ~StudyTunings();
  size_t Pending() const;          // tunings still to run
  int ScenarioOf(size_t i) const;  // the scenario of pending tuning i
  int ComboOf(size_t i) const;     // its combo in that scenario
  void ApplyReused(StudyConfig* config) const;
  // Tunes pending combo i, saves it in DIR/tuning/, and puts the tuned Q/R
  // and parameters into its spec (or its failure into tune_failure).
  void Tune(size_t i, StudyConfig* config);
  // tuned.csv and the counts; interrupted (no csv) when a pending one did
  // not run.
  StudyTuningSummary Summary() const;

 private:
  struct State;
  StudyTuningOptions options_;
  uint64_t hash_;
  std::unique_ptr<State> state_;
};

// The folder of the saved results, DIR/tuning.
std::string TuningFolder(const std::string& dir);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RUN_STUDY_TUNING_H_
