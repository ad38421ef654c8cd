// Pieces shared by the study runner (study_runner.cpp) and the tuning of its
// `tuned` noise settings (study_tuning.cpp). Internal to studies/run/.
#ifndef ESTLAB_STUDIES_RUN_STUDY_RUNNER_PARTS_H_
#define ESTLAB_STUDIES_RUN_STUDY_RUNNER_PARTS_H_

#include <cstdint>
#include <string>
#include <vector>

#include "src/run/filter_spec.h"
#include "src/sim/simulation.h"
#include "studies/config/study_config.h"

namespace estlab::study_runner {

// The time now as 2026-12-03T14:19:43Z.
std::string NowUtc();

// "%.10g"; "" for NaN.
std::string Sig10(double v);

// A run's initial state drawn from the scenario's prior (x0 = sample):
// truth x0 + L w, L L^T = prior P0, w ~ N(0, I) from DeriveSeed({seed, "x0"}).
std::vector<double> SampleX0(const ScenarioConfig& sc, uint64_t run_seed);

// The measurements (and truth) of a simulated trajectory, as a filter reads
// them, with the scenario's input signal when it has one (the sample held
// from each row on). With meas-noise = poisson the simulator drew no measurement noise and
// the counts are added here from their own stream DeriveSeed({seed, "pois"}).
FilterData DataFromTruth(const ScenarioConfig& sc, const SimulationResult& truth,
                         const std::string& label, uint64_t seed);

}  // namespace estlab::study_runner

#endif  // ESTLAB_STUDIES_RUN_STUDY_RUNNER_PARTS_H_
