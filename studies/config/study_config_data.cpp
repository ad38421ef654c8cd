// Recorded-data scenarios (`data =`): the files, the column maps and whether
// state-named columns are truth (study_config_parts.h).
#include <glob.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "src/core/parse.h"
#include "src/options/filter_flags.h"
#include "studies/config/study_config_parts.h"

namespace estlab::study_config {

namespace fs = std::filesystem;

namespace {

// Whether `file` lies in a study's results folder (its own study.state, or
// that of a folder up to three levels above: timeseries/SCENARIO/run.csv):
// a study's outputs are never its data, even when a glob reaches them
// (`data = dd/*/*.csv` with --out dd/res once matched dd/res/runs.csv on
// the second run).
bool InResultsFolder(const fs::path& file) {
  std::error_code ec;
  fs::path dir = file.parent_path();
  for (int level = 0; level < 4 && !dir.empty(); ++level, dir = dir.parent_path())
    if (fs::exists(dir / "study.state", ec)) return true;
  return false;
}

// The files of a `data` / `tune-data` value: comma-separated globs relative to
// the config file's folder, each expanded in sorted order, files in a study's
// results folder left out; one that matches nothing is an error naming it.
std::vector<std::string> ExpandFiles(const SectionValues& v, const std::string& key) {
  const fs::path base = fs::path(v.errors().path()).parent_path();
  std::vector<std::string> files;
  for (const std::string& item : Split(v.Get(key)->text, ',')) {
    if (item.empty()) v.Fail(key, "empty file name in '" + v.Get(key)->text + "'");
    const fs::path pattern = fs::path(item).is_absolute() ? fs::path(item) : base / item;
    glob_t g{};
    const int rc = ::glob(pattern.string().c_str(), 0, nullptr, &g);
    size_t kept = 0;
    for (size_t i = 0; rc == 0 && i < g.gl_pathc; ++i) {
      if (InResultsFolder(g.gl_pathv[i])) continue;
      files.push_back(fs::path(g.gl_pathv[i]).lexically_normal().string());
      ++kept;
    }
    ::globfree(&g);
    if (rc == 0 && kept == 0)
      v.Fail(key, "'" + item + "' matches only files of a study's results folder (" +
                      pattern.lexically_normal().string() + ")");
    if (rc != 0)
      v.Fail(key, "no file matches '" + item + "' (looked for " +
                      pattern.lexically_normal().string() + ")");
  }
  return files;
}

std::vector<FilterData> LoadFiles(const SectionValues& v, const std::string& key,
                                  const ScenarioConfig& sc) {
  const MeasurementDesc& meas = sc.model->FindMeasurement(sc.truth.measurement);
  std::vector<FilterData> runs;
  std::vector<std::string> seen;  // canonical paths: a file is one run
  for (const std::string& file : ExpandFiles(v, key)) {
    std::error_code ec;
    const std::string canonical = fs::weakly_canonical(file, ec).string();
    if (std::find(seen.begin(), seen.end(), canonical) != seen.end())
      v.Fail(key, "'" + file + "' is listed twice; each file is one run (a second copy would " +
                      "count it twice and narrow every interval)");
    seen.push_back(canonical);
    runs.push_back(Checked(*v.Get(key), v.errors(), [&](const std::string&) {
      return cli::LoadFilterData(file, *sc.model, meas, sc.columns, sc.has_truth);
    }));
    if (std::none_of(runs.back().z.begin(), runs.back().z.end(),
                     [](double z) { return std::isfinite(z); }))
      v.Fail(key, "'" + file + "' has no finite measurement (every z cell is empty or NaN): " +
                      "a run of it would filter nothing");
    if (sc.has_truth && !runs.back().has_truth) {
      std::string states;
      for (const auto& s : sc.model->states) states += (states.empty() ? "" : ", ") + s;
      v.Fail("truth", "'columns', but " + file + " has no column for every state (" + states +
                          "; map them with column = STATE=NAME)");
    }
  }
  return runs;
}

double MedianStep(const std::vector<double>& t) {
  std::vector<double> d;
  for (size_t k = 1; k < t.size(); ++k) d.push_back(t[k] - t[k - 1]);
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + long(d.size() / 2), d.end());
  return d[d.size() / 2];
}

}  // namespace

void ReadRecordedData(const SectionValues& v, ScenarioConfig* sc) {
  sc->recorded = true;
  sc->has_truth = false;
  if (v.Has("truth")) {
    const std::string t = v.Get("truth")->text;
    if (t != "none" && t != "columns") v.Fail("truth", "expected none or columns, got '" + t + "'");
    sc->has_truth = t == "columns";
  }
  if (v.Has("column")) {
    sc->columns = Checked(*v.Get("column"), v.errors(), [](const std::string& text) {
      try {
        return ParseColumnMaps(Split(text, ','));
      } catch (const InputError& e) {  // "--column: ..." -> "column: ..."
        const std::string m = e.what();
        throw InputError(m.rfind("--", 0) == 0 ? m.substr(2) : m);
      }
    });
  }
  sc->data_runs = LoadFiles(v, "data", *sc);
  if (v.Has("tune-data")) sc->tune_runs = LoadFiles(v, "tune-data", *sc);
  // Tuning on an evaluated file reports an in-sample fit as a validation.
  for (const FilterData& t : sc->tune_runs)
    for (const FilterData& d : sc->data_runs) {
      std::error_code ec;
      if (fs::equivalent(t.path, d.path, ec) && !ec)
        v.Fail("tune-data", "'" + t.path + "' is also in data: a file the noise is tuned on " +
                                "cannot validate it (list it in one of the two)");
    }
  if (v.Has("burn-in")) {
    sc->burn_in = Checked(*v.Get("burn-in"), v.errors(), [](const std::string& t) {
      return ParseCount(t, "burn-in", 0, kMaxSteps);
    });
    size_t shortest = sc->data_runs.front().t.size();
    for (const FilterData& d : sc->data_runs) shortest = std::min(shortest, d.t.size());
    if (size_t(sc->burn_in) >= shortest)
      v.Fail("burn-in", "must be less than the rows of every data file (the shortest has " +
                            std::to_string(shortest) + ")");
  }
  // For the report: the typical sampling interval and the longest run.
  sc->truth.dt = MedianStep(sc->data_runs.front().t);
  sc->steps = 0;
  for (const FilterData& d : sc->data_runs) sc->steps = std::max(sc->steps, int(d.t.size()));
  sc->truth_description = "recorded, " + std::to_string(sc->data_runs.size()) + " file(s)" +
                          (sc->has_truth ? ", truth from the state columns" : ", no truth");
}

}  // namespace estlab::study_config
