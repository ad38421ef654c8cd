// estlab study | merge | figures: Monte Carlo studies from a config file.
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <boost/program_options.hpp>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "src/cli/commands.h"
#include "src/core/parse.h"
#include "src/core/types.h"
#include "src/io/csv_reader.h"
#include "src/io/json.h"
#include "src/io/output_file.h"
#include "src/io/shell.h"
#include "studies/config/study_config.h"
#include "studies/report/run_figures.h"
#include "studies/report/study_figures.h"
#include "studies/results/study_results.h"
#include "studies/run/study_merge.h"
#include "studies/run/study_runner.h"
#include "studies/run/study_slurm.h"

namespace po = boost::program_options;

namespace estlab::cli {

namespace {

constexpr const char* kStudyHelp = R"(
Runs every scenario of CONFIG (a studies/*.ini file, format in docs/studies.md)
N times: each run simulates the truth once and runs every filter x noise
setting on the same measurements. A scenario with `data = FILES` runs on
recorded files instead, one run per file (docs/studies.md, "Recorded data").

Examples:
  estlab study studies/paper002_pendulum_mc.ini --out results/paper002 --jobs 2
  estlab study studies/paper000_noise_grid.ini --out results/p000 --runs 10
  # Three machines, then join:
  estlab study S.ini --out r1 --shard 1/3   (and 2/3, 3/3 into r2, r3)
  estlab merge results/all r1 r2 r3
  estlab figures results/paper002
  estlab study studies/multiarm_hand_vs_auto.ini --out results/multiarm --jobs 2
  # On a Slurm cluster: 10 array tasks and a merge job, then follow them:
  estlab study studies/paper003_double_pendulum_sweep.ini --out results/p003 --slurm 10 \
      --jobs 4 --slurm-opts "--partition=short --time=01:00:00"
  estlab study --status results/p003
  # Every Q/R estimator, identified in each run (tune-per-run), 100 runs per scenario:
  estlab study studies/noise_identification.ini --out results/ni --runs 100 --jobs 2

Output folder: runs.csv (a row per scenario, run, filter and noise setting),
summary.csv, time_metrics.csv, steps.csv, timing.csv, timeseries/ (kept runs),
report.md, manifest.json; identification.csv with tune-per-run noise settings.
runs.csv and summary.csv do not depend on --jobs or
--shard. Ctrl-C (or SIGTERM) stops taking new runs, writes the finished ones
and exits 130 (143); the same command again resumes.
Exit status: 0 done (filter runs that failed numerically are results: their
status is in runs.csv), 1 done but a noise tuning failed (tuned.csv says
why), 2 bad config or options, or an output that cannot be written (a
read-only or full folder), 130/143 interrupted (resumable).
)";

std::atomic<int> g_stop_signal{0};

extern "C" void OnStopSignal(int sig) {
  g_stop_signal = sig;
  ::signal(sig, SIG_DFL);  // a second signal ends the process at once
}

class StopSignals {
 public:
  StopSignals() {
    g_stop_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = OnStopSignal;
    sigemptyset(&sa.sa_mask);
    ::sigaction(SIGINT, &sa, &old_int_);
    ::sigaction(SIGTERM, &sa, &old_term_);
  }
  ~StopSignals() {
    ::sigaction(SIGINT, &old_int_, nullptr);
    ::sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  struct sigaction old_int_ {
  }, old_term_{};
};

void ParseShard(const std::string& text, int* k, int* n) {
  const auto slash = text.find('/');
  try {
    if (slash == std::string::npos) throw InputError("");
    const double a = ParseNumber(text.substr(0, slash), "--shard");
    const double b = ParseNumber(text.substr(slash + 1), "--shard");
    if (a != std::floor(a) || b != std::floor(b) || b < 1 || a < 1 || a > b || b > 100000)
      throw InputError("");
    *k = int(a);
    *n = int(b);
  } catch (const InputError&) {
    throw InputError("--shard: expected k/N with 1 <= k <= N, got '" + text + "'");
  }
}

// A short table of summary.csv: per group the mean RMSE per state, NEES and
// NIS (on recorded data, NIS, NLL per step and prediction RMSE: the metrics
// that need no truth); metrics without a value are left out.
void PrintSummaryTable(const std::string& dir) {
  const CsvText s = ReadCsvText(dir + "/summary.csv");
  const int metric = s.Column("metric"), mean = s.Column("mean"), n = s.Column("n");
  const int runs = s.Column("runs"), lo = s.Column("ci95_lo"), hi = s.Column("ci95_hi");
  auto group_of = [](const std::vector<std::string>& r) { return r[0] + "  " + r[1] + "/" + r[2]; };
  std::string group;
  for (size_t i = 0; i < s.rows.size(); ++i) {
    const auto& r = s.rows[i];
    const std::string g = group_of(r);
    if (g != group) {
      long ok = 0;  // the ok runs: the most values any metric of the group has
      for (size_t j = i; j < s.rows.size() && group_of(s.rows[j]) == g; ++j)
        ok = std::max(ok, std::stol(s.rows[j][n]));
      std::cout << (group.empty() ? "" : "\n") << g << "  (" << ok << "/" << r[runs]
                << " runs ok)\n";
      group = g;
    }
    const std::string& m = r[metric];
    // The numbers of summary.csv, formatted (6 significant digits), never cut.
    const auto number = CellForDisplay;
    const bool shown = m.rfind("rmse_", 0) == 0 || m.rfind("pred_rmse_", 0) == 0 ||
                       m == "mean_nees" || m == "mean_nis" || m == "nll_per_step";
    if (shown && r[n] != "0")
      std::cout << "  " << std::left << std::setw(16) << m << std::right << std::setw(12)
                << number(r[mean]) << "   95% CI [" << number(r[lo]) << ", " << number(r[hi])
                << "]\n";
  }
}

std::string SummaryJson(const std::string& dir, const StudyConfig& config,
                        const StudyRunSummary& sum) {
  JsonWriter j;
  j.BeginObject().Key("study").Value(config.study.name).Key("out").Value(dir);
  j.Key("status").Value(sum.interrupted ? "interrupted" : "complete");
  j.Key("total_runs").Value(sum.total_runs).Key("finished_runs").Value(sum.finished_runs);
  j.Key("resumed_runs").Value(sum.resumed_runs);
  j.Key("failed_filter_runs").Value(sum.failed_filter_runs);
  j.Key("failed_tunings").Value(long(sum.failed_tunings)).Key("wall_s").Value(sum.wall_s);
  j.Key("task_work_s").Value(sum.task_work_s).Key("critical_path_s").Value(sum.critical_path_s);
  j.Key("summary").BeginArray();
  if (!sum.interrupted) {
    const CsvText s = ReadCsvText(dir + "/summary.csv");
    for (const auto& r : s.rows) {
      j.BeginObject();
      for (size_t c = 0; c < s.columns.size(); ++c) {
        if (c < 4) {
          j.Key(s.columns[c]).Value(r[c]);
        } else if (r[c].empty()) {
          j.Key(s.columns[c]).Null();
        } else {
          j.Key(s.columns[c]).Value(std::strtod(r[c].c_str(), nullptr));
        }
      }
      j.EndObject();
    }
  }
  j.EndArray().EndObject();
  return j.str();
}

// `--slurm N`: the scripts, the submission (unless --slurm-dry-run), and how
// to follow it.
// An sbatch command as a shell line to paste: each word quoted, but the
// merge's "$ARRAY" (our own text) left for the shell to expand.
std::string ShownCommand(const std::vector<std::string>& words) {
  std::string line;
  for (const std::string& w : words) {
    const bool ours = w == kArrayDependency;
    line += (line.empty() ? "" : " ") + (ours ? w : ShellJoin({w}));
  }
  return line;
}

int SubmitToSlurm(const po::variables_map& vm, const StudyConfig& config,
                  const StudyRunOptions& run, bool json) {
  if (vm.count("shard")) throw InputError("--slurm makes the shards itself; leave out --shard");
  SlurmOptions o;
  o.shards = vm["slurm"].as<int>();
  o.cpus_per_task = run.jobs;
  o.sbatch_opts = vm["slurm-opts"].as<std::string>();
  o.estlab = std::filesystem::canonical("/proc/self/exe").string();
  o.config_path = std::filesystem::absolute(config.path).lexically_normal().string();
  o.dry_run = vm.count("slurm-dry-run") > 0;
  SlurmPlan plan = PlanSlurm(config, run.out_dir, o);
  if (!o.dry_run) SubmitSlurm(&plan);
  const std::string shards = [&] {
    std::string s;
    for (int k : plan.pending_shards) {
      if (!s.empty()) s += ',';
      s += std::to_string(k);
    }
    return s;
  }();
  if (json) {
    JsonWriter j;
    j.BeginObject().Key("out").Value(plan.out).Key("folder").Value(plan.folder);
    j.Key("merged").Value(plan.merged).Key("dry_run").Value(o.dry_run);
    j.Key("pending_shards").BeginArray();
    for (int k : plan.pending_shards) j.Value(k);
    j.EndArray().Key("array_job").Value(plan.array_job).Key("merge_job").Value(plan.merge_job);
    j.Key("commands").BeginArray();
    for (const auto& c : plan.commands) j.Value(ShownCommand(c));
    j.EndArray().EndObject();
    std::cout << j.str() << "\n";
    return 0;
  }
  if (plan.merged) {
    std::cout << run.out_dir << " holds the merged study already; nothing to submit\n";
    return 0;
  }
  if (o.dry_run) {
    std::cout << "wrote " << plan.array_script << " and " << plan.merge_script
              << "; submit with:\n";
    for (const auto& c : plan.commands) {
      const std::string shown = ShownCommand(c);
      std::cout << "  "
                << (std::find(c.begin(), c.end(), kArrayDependency) == c.end() &&
                            !plan.pending_shards.empty()
                        ? "ARRAY=$(" + shown + ")"
                        : shown)
                << "\n";
    }
    return 0;
  }
  if (!plan.array_job.empty())
    std::cout << "submitted shard(s) " << shards << " of " << o.shards << " as array job "
              << plan.array_job << " (" << plan.array_script << ")\n";
  else
    std::cout << "every shard is complete; no array job\n";
  std::cout << "merge job " << plan.merge_job << " writes " << plan.out
            << (plan.array_job.empty() ? "" : " after it (afterok)") << "\n"
            << "follow with:\n  squeue -j " << (plan.array_job.empty() ? "" : plan.array_job + ",")
            << plan.merge_job << "\n  sacct -j "
            << (plan.array_job.empty() ? "" : plan.array_job + ",") << plan.merge_job
            << "    (where accounting is on)\n  estlab study --status " << run.out_dir
            << "\nlogs in " << plan.folder << "/logs/; the same command again "
            << "resubmits only unfinished shards\n";
  return 0;
}

// `--status DIR`.
int PrintStatus(const std::string& dir, bool json) {
  const StudyStatus st = ReadStudyStatus(dir);
  if (json) {
    JsonWriter j;
    j.BeginObject().Key("dir").Value(dir).Key("status").Value(st.status);
    j.Key("finished_runs").Value(st.finished_runs).Key("total_runs").Value(st.total_runs);
    j.Key("complete_shards").Value(st.complete_shards).Key("shards").BeginArray();
    for (const auto& s : st.shards) {
      j.BeginObject().Key("shard").Value(s.shard).Key("status").Value(s.status);
      j.Key("finished_runs").Value(s.finished_runs).Key("total_runs").Value(s.total_runs);
      j.EndObject();
    }
    j.EndArray().Key("last_submission").Value(st.last_jobs).EndObject();
    std::cout << j.str() << "\n";
    return 0;
  }
  std::cout << dir << ": " << st.status;
  if (st.status != "not started")
    std::cout << ", " << st.finished_runs << "/" << st.total_runs << " runs";
  std::cout << "\n";
  if (!st.shards.empty()) {
    std::cout << st.complete_shards << " of " << st.shards.size() << " shards complete\n"
              << "  shard  status        runs\n";
    for (const auto& s : st.shards)
      std::cout << "  " << std::left << std::setw(5) << s.shard << "  " << std::setw(12) << s.status
                << "  " << s.finished_runs << "/" << s.total_runs << "\n"
                << std::right;
    if (!st.last_jobs.empty()) std::cout << "last submission: " << st.last_jobs << "\n";
  }
  return 0;
}

}  // namespace

int RunStudyCommand(const std::vector<std::string>& args) {
  po::options_description desc("estlab study CONFIG --out DIR: run a Monte Carlo study");
  desc.add_options()("help,h", "this text")("config", po::value<std::string>(),
                                            "study file (studies/*.ini)")(
      "out", po::value<std::string>(),
      "results folder (created; an existing one of the same study is resumed)")(
      "runs", po::value<int>(),
      "Monte Carlo runs per scenario (overrides [study] runs; not for recorded data)")(
      "jobs", po::value<int>(), "worker threads (overrides [study] jobs)")(
      "shard", po::value<std::string>(), "k/N: only runs i with i % N == k-1")(
      "quiet", "no progress output")("json", "print a JSON summary on stdout")(
      "force", "resume with fewer --runs than the folder holds (the others are dropped)")(
      "slurm", po::value<int>(),
      "N: submit the study as a Slurm job array of N shards plus a merge job into --out "
      "(scripts, shard folders and logs in OUT.slurm/); again: only unfinished shards")(
      "slurm-opts", po::value<std::string>()->default_value(""),
      "extra sbatch options for both jobs, plain words (no quotes or shell syntax), e.g. "
      "\"--partition=short --time=01:00:00\"")(
      "slurm-dry-run", "with --slurm: write the scripts and print the sbatch commands")(
      "status", po::value<std::string>(),
      "DIR: how far the study in DIR (or its --slurm shards) is; no CONFIG needed");
  po::positional_options_description pos;
  pos.add("config", 1);
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).positional(pos).run(), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << desc << kStudyHelp;
    return 0;
  }
  if (vm.count("status")) return PrintStatus(vm["status"].as<std::string>(), vm.count("json") > 0);
  if (!vm.count("config"))
    throw InputError("a study file is required: estlab study CONFIG --out DIR");
  if (!vm.count("out")) throw InputError("--out is required");
  StudyRunOptions options;
  options.out_dir = vm["out"].as<std::string>();
  if (vm.count("runs")) {
    options.runs = vm["runs"].as<int>();
    if (options.runs < 1) throw InputError("--runs must be >= 1");
  }
  if (vm.count("jobs")) {
    options.jobs = vm["jobs"].as<int>();
    if (options.jobs < 1) throw InputError("--jobs must be >= 1");
  }
  if (vm.count("shard")) ParseShard(vm["shard"].as<std::string>(), &options.shard, &options.shards);
  options.progress = !vm.count("quiet");
  options.force = vm.count("force") > 0;
  const bool json = vm.count("json") > 0;

  const StudyConfig config = LoadStudyConfig(vm["config"].as<std::string>());
  if (vm.count("slurm")) return SubmitToSlurm(vm, config, options, json);
  if (vm.count("slurm-dry-run") || !vm["slurm-opts"].defaulted())
    throw InputError("--slurm-dry-run and --slurm-opts go with --slurm N");
  StopSignals signals;
  options.stop = &g_stop_signal;
  const StudyRunSummary sum = RunStudy(config, options);
  const int sig = g_stop_signal.load();

  if (json) std::cout << SummaryJson(options.out_dir, config, sum) << "\n";
  if (sum.interrupted) {
    std::cerr << "estlab: " << (sig == SIGTERM ? "terminated" : "interrupted") << ": "
              << sum.finished_runs << " of " << sum.total_runs << " runs are finished in "
              << options.out_dir << "/runs.csv; run the same command again to resume\n";
    return sig == SIGTERM ? 143 : 130;
  }
  if (!json) {
    PrintSummaryTable(options.out_dir);
    std::cout << "\n" << sum.finished_runs << " runs";
    if (sum.resumed_runs) std::cout << " (" << sum.resumed_runs << " from before)";
    std::cout << " in " << std::setprecision(3) << sum.wall_s << " s";
    if (sum.critical_path_s > 0)
      std::cout << " (tasks: " << sum.task_work_s << " s of work, critical path "
                << sum.critical_path_s << " s)";
    if (sum.failed_filter_runs)
      std::cout << "; " << sum.failed_filter_runs << " filter runs failed (status in runs.csv)";
    const bool identification = std::filesystem::exists(options.out_dir + "/identification.csv");
    std::cout << "\nwrote " << options.out_dir << "/{runs,summary,time_metrics"
              << (identification ? ",identification" : "") << "}.csv, report.md, manifest.json\n";
  }
  if (sum.failed_tunings > 0) {  // results, but not the ones asked for
    std::cerr << "estlab: " << sum.failed_tunings << " noise tuning(s) failed (" << options.out_dir
              << "/tuned.csv says why; their runs are marked failed)\n";
    return 1;
  }
  return 0;
}

int RunMerge(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::cout << "estlab merge OUT SHARD_DIR...: join the folders of 'estlab study --shard k/N'\n"
                 "into OUT (new or empty). The result equals one unsharded run.\n"
                 "Every shard is checked first: complete, of the same study, its files\n"
                 "unchanged since it finished (size and checksum in its study.state), its\n"
                 "runs exactly its shard's and whole; a refusal names the shard and the\n"
                 "problem (exit 2). OUT is built in a temporary folder beside it and\n"
                 "renamed into place: it is complete or absent.\n\n"
                 "Example:\n  estlab merge results/all r1 r2 r3\n";
    return args.empty() ? 2 : 0;
  }
  if (args.size() < 2) throw InputError("merge: give OUT and at least one shard folder");
  MergeStudies(args[0], std::vector<std::string>(args.begin() + 1, args.end()));
  std::cout << "merged " << args.size() - 1 << " shard folder(s) into " << args[0] << "\n";
  return 0;
}

namespace {

// "N figures in FOLDER (png via T, svg)"; exit status 1 with the reason when
// they could not be rendered (the scripts and data are written).
int ReportFigures(const FiguresSummary& f) {
  std::cout << f.scripts.size() << " figures in " << f.folder;
  if (f.rendered) std::cout << " (png via " << f.terminal << ", svg)";
  std::cout << "\n";
  if (f.message.empty()) return 0;
  std::cerr << "estlab: error: " << f.message << "\n";
  return 1;
}

// `estlab figures est.csv`: the figures of `estlab filter --plot` from the
// file it wrote, with the measurements of --data (its z_<output> columns).
int RunFileFigures(const po::variables_map& vm, const FiguresOptions& options) {
  const std::string path = vm["dir"].as<std::string>();
  const CsvTable est = ReadCsv(path);
  RunFigureInput in;
  in.title = std::filesystem::path(path).filename().string();
  in.columns = est.columns;
  in.rows = est.rows;
  if (vm.count("data")) {
    const CsvTable data = ReadCsv(vm["data"].as<std::string>());
    std::vector<int> zc;
    for (const auto& c : est.columns)  // the outputs the filter had
      if (c.rfind("nu_", 0) == 0 && data.ColumnIndex("z_" + c.substr(3)) >= 0) {
        in.outputs.push_back(c.substr(3));
        zc.push_back(data.ColumnIndex("z_" + c.substr(3)));
      }
    if (in.outputs.empty())  // a smoother's file: every z_ column
      for (size_t j = 0; j < data.columns.size(); ++j)
        if (data.columns[j].rfind("z_", 0) == 0) {
          in.outputs.push_back(data.columns[j].substr(2));
          zc.push_back(int(j));
        }
    const int tc = data.ColumnIndex("t");
    if (tc < 0) throw InputError(vm["data"].as<std::string>() + ": no 't' (time) column");
    for (const auto& row : data.rows) {
      in.meas_t.push_back(row[tc]);
      for (int c : zc) in.meas_z.push_back(row[c]);
    }
  }
  std::string dir = vm.count("out") ? vm["out"].as<std::string>() : "";
  if (dir.empty()) dir = std::filesystem::path(path).replace_extension().string() + "_figures";
  const FiguresSummary f = DrawRunFigures(in, dir, options);
  return ReportFigures(f);
}

}  // namespace

int RunFigures(const std::vector<std::string>& args) {
  po::options_description desc(
      "estlab figures DIR | FILE.csv: draw a finished study's figures, or those of one filter "
      "run's output file, with gnuplot");
  desc.add_options()("help,h", "this text")("dir", po::value<std::string>(),
                                            "results folder, or est.csv of estlab filter/smooth")(
      "data", po::value<std::string>(), "FILE.csv: the data file, for its measurements")(
      "out", po::value<std::string>(), "FILE.csv: the figures' folder (default FILE_figures)")(
      "no-render", "write the .dat and .gp files only")(
      "gnuplot", po::value<std::string>()->default_value("gnuplot"), "gnuplot program");
  po::positional_options_description pos;
  pos.add("dir", 1);
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).positional(pos).run(), vm);
  po::notify(vm);
  if (vm.count("help")) {
    std::cout << desc
              << "\nA study folder: DIR/figures/NAME.{dat,gp,png,svg}: estimate vs truth with "
                 "+-2 sd and the\nmeasurements (a kept run), RMSE over time, NEES/NIS with 95 % "
                 "bounds, mean RMSE per\nfilter with 95 % CI.\n"
                 "A file: the figures of 'estlab filter --plot' (estimates, innovations, NIS, "
                 "autocorrelation)\nin FILE_figures/ (or --out DIR).\n\n"
                 "Examples:\n  estlab figures results/paper002\n"
                 "  estlab figures est.csv --data d.csv --out est_plots\n";
    return 0;
  }
  if (!vm.count("dir"))
    throw InputError("a results folder or a filter output file is required: estlab figures DIR");
  FiguresOptions options;
  options.render = !vm.count("no-render");
  options.gnuplot = vm["gnuplot"].as<std::string>();
  if (std::filesystem::is_regular_file(vm["dir"].as<std::string>()))
    return RunFileFigures(vm, options);
  if (vm.count("data") || vm.count("out"))
    throw InputError("--data and --out apply to 'estlab figures FILE.csv', not to a study folder");
  const FiguresSummary f = DrawStudyFigures(vm["dir"].as<std::string>(), options);
  return ReportFigures(f);
}

}  // namespace estlab::cli
