// The files of a study results folder: what each holds, its columns, the
// study.state file and the canonical order of the run files.
//
//   DIR/config.ini        the study file as given
//   DIR/study.state       config hash, runs, shard, status (for resume and merge)
//   DIR/manifest.json     config, seeds, versions, host, times
//   DIR/runs.csv          one row per scenario x run x filter x noise
//   DIR/steps.csv         per-step errors, NEES, NIS (every k-th step) of every run
//   DIR/timing.csv        wall-clock cost per run and filter
//   DIR/summary.csv       per scenario x filter x noise and metric: mean, spread, intervals
//   DIR/time_metrics.csv  per group and time: RMSE over runs, mean NEES/NIS with bounds
//   DIR/timeseries/       full time series of the kept runs
//   DIR/report.md         tables and the paper's numbers beside ours
//
// runs.csv, steps.csv, summary.csv and time_metrics.csv depend only on the
// configuration and the runs done: they are byte-identical whatever --jobs,
// however the study was sharded, and however often it was interrupted. Wall
// times (timing.csv, manifest.json, report.md) are not.
//
// This layer (studies/results/) knows the folder: its files, their columns,
// study.state and the canonical row order. What is computed from it lives
// above: summary.csv, time_metrics.csv and report.md in studies/report/
// (FinalizeStudy, study_finalize.h), runs and merges in studies/run/.
//
// Usage:
//   StudyState state;
//   if (ReadStudyState("results/paper002", &state)) ...
//   const RowFile runs = ReadRowFile("results/paper002/runs.csv", RunsColumns(config));
#ifndef ESTLAB_STUDIES_RESULTS_STUDY_RESULTS_H_
#define ESTLAB_STUDIES_RESULTS_STUDY_RESULTS_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "studies/config/study_config.h"

namespace estlab {

// Column headers of the per-run files.
std::vector<std::string> RunsColumns(const StudyConfig& config);
std::vector<std::string> StepsColumns(const StudyConfig& config);
std::vector<std::string> TimingColumns(const StudyConfig& config);
// With tune-per-run noise settings (config.identification), the columns of
// runs.csv (before steps) that say how well each run identified Q and R:
//   id_q_err, id_r_err  relative Frobenius error ||Q^ - Q||_F / ||Q||_F of the
//                       tuned per-step covariance against the truth's (R alike);
//                       empty for a fixed Q (R) and for settings not tuned per run
//   id_iterations       optimiser / EM iterations
//   id_converged        1 when the tuner converged, 0 when it stopped at its limit
//   id_at_bound         1 when an estimate ended at (or near) its search bound
//   id_q_STATE          per element: Q^_ii / Q_ii, the identified over the true
//                       variance of each state (state_columns)
//   id_r_OUTPUT         R^_jj / R_jj of each output (identification_outputs)
// A run whose tuning failed has status tune_failed. timing.csv gets
// identify_wall_s, the tuner's wall time in that run.
std::vector<std::string> IdentificationColumns(const StudyConfig& config);
// The first five of them (the per-element ones follow).
std::vector<std::string> IdentificationFitColumns();

// A CSV row file written run by run: the header and the rows, with a partial
// last line (an interrupted write) dropped. Throws InputError when the
// header differs from `columns`. A missing file reads as empty.
struct RowFile {
  std::vector<std::vector<std::string>> rows;
  bool existed = false;
  bool dropped_partial = false;
};
RowFile ReadRowFile(const std::string& path, const std::vector<std::string>& columns);
// The same, one row at a time (memory does not grow with the file);
// *dropped as RowFile::dropped_partial.
void ForEachRow(const std::string& path, const std::vector<std::string>& columns, bool* dropped,
                const std::function<void(const std::vector<std::string>&)>& visit);
std::string FormatCsvRow(const std::vector<std::string>& fields);
// A number as the result files write it: %.10g, "" for NaN, inf / -inf.
std::string FormatResultNumber(double v);
// A file's bytes; "" when it cannot be read.
std::string ReadWholeFile(const std::string& path);

// Any CSV with a header row, as text (summary.csv, time_metrics.csv).
struct CsvText {
  std::vector<std::string> columns;
  std::vector<std::vector<std::string>> rows;
  int Column(const std::string& name) const;  // -1 when absent
};
CsvText ReadCsvText(const std::string& path);  // throws InputError when unreadable

// A result file's checksum (study_integrity.h): its path in the folder,
// byte size and 64-bit FNV-1a.
struct FileDigest {
  std::string path;
  uint64_t bytes = 0;
  uint64_t fnv = 0;
  bool operator==(const FileDigest& o) const {
    return path == o.path && bytes == o.bytes && fnv == o.fnv;
  }
};

// The study.state file.
struct StudyState {
  uint64_t config_hash = 0;
  int runs = 0;
  int shard = 1, shards = 1;
  std::string status;  // running | interrupted | complete
  std::string started, finished;
  double wall_s = 0.0;
  int jobs = 1;
  // The absolute path of the config file the study was started from: the
  // folder that relative paths in it (model files, data) are relative to.
  std::string config_path;
  // When complete: the checksum of every result file ("file = PATH BYTES
  // FNV" lines), for `estlab merge` to check the folder against.
  std::vector<FileDigest> files;
};
void WriteStudyState(const std::string& dir, const StudyState& state);
// Returns false when DIR has no study.state.
bool ReadStudyState(const std::string& dir, StudyState* state);

// The configuration of a results folder: DIR/config.ini, read as if it were
// the original config file (state.config_path, when that folder still
// exists) so that its relative model and data paths resolve as they did.
StudyConfig LoadResultsConfig(const std::string& dir, const StudyState& state);

// Sorts the run files of DIR (runs.csv, steps.csv, timing.csv) into
// canonical order (scenario, run, filter, noise), rows of equal keys in the
// order found; a missing file is written with its header only. A file
// already in order and complete is left alone. Throws InputError for a row
// of a scenario, filter or noise the study does not have.
void CanonicalizeRunFiles(const StudyConfig& config, const std::string& dir);

}  // namespace estlab

#endif  // ESTLAB_STUDIES_RESULTS_STUDY_RESULTS_H_
