// `estlab study --slurm N` and `--status` without a cluster: the scripts it
// writes, the sbatch calls it makes (a stand-in sbatch on PATH records them
// and answers job ids), which shards a resubmission picks, and the status of
// a partial submission. A real Slurm runs the same in `make test-slurm`
// (tests/slurm/test_slurm.sh).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "../cli/cli_test_util.h"
#include "study_test_util.h"

namespace estlab::testing {
namespace {

namespace fs = std::filesystem;

class StudySlurm : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!FiltersAvailable()) GTEST_SKIP() << "no filter runner in this build yet";
    // sbatch: appends its arguments to sbatch.log, answers 100, 101, ...
    fs::create_directories(dir_.File("bin"));
    WriteText(dir_.File("bin/sbatch"),
              "#!/bin/sh\n"
              "n=$(cat \"$(dirname \"$0\")/next\" 2>/dev/null || echo 100)\n"
              "echo \"$n $*\" >> \"$(dirname \"$0\")/sbatch.log\"\n"
              "echo $((n + 1)) > \"$(dirname \"$0\")/next\"\n"
              "echo \"$n;cluster\"\n");
    fs::permissions(dir_.File("bin/sbatch"), fs::perms::owner_all);
    WriteText(dir_.File("s.ini"), TinyStudy(6));
  }
  // estlab ARGS with the stand-in sbatch first on PATH.
  RunResult Estlab(const std::string& args) {
    // Beside the folder (its own name), not in a shared one: ctest -j runs
    // these tests at once, and one fixed /tmp/slurm.out mixed their output.
    const std::string out = dir_.path() + ".out", err = dir_.path() + ".err";
    const std::string cmd = "cd '" + dir_.path() + "' && PATH='" + dir_.File("bin") +
                            "':\"$PATH\" '" + ESTLAB_BINARY + "' " + args + " >'" + out + "' 2>'" +
                            err + "'";
    const int status = std::system(cmd.c_str());
    RunResult r;
    if (status != -1 && WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
    r.out = ReadFile(out);
    r.err = ReadFile(err);
    fs::remove(out);
    fs::remove(err);
    return r;
  }
  TempDir dir_;
};

TEST_F(StudySlurm, SubmitsAnArrayAndAMergeThatDependsOnIt) {
  const auto r = Estlab("study s.ini --out res --slurm 3 --jobs 2 --slurm-opts '--time=5'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string log = ReadFile(dir_.File("bin/sbatch.log"));
  const auto calls = SplitLines(log);
  ASSERT_EQ(calls.size(), 2u) << log;
  const std::string slurm = fs::canonical(dir_.path()).string() + "/res.slurm";
  EXPECT_EQ(calls[0], "100 --parsable --array=1,2,3 --output=" + slurm +
                          "/logs/shard-%a.out --time=5 " + slurm + "/array.sh");
  EXPECT_EQ(calls[1],
            "101 --parsable --dependency=afterok:100 --kill-on-invalid-dep=yes --output=" + slurm +
                "/logs/merge.out --time=5 " + slurm + "/merge.sh");
  EXPECT_NE(r.out.find("submitted shard(s) 1,2,3 of 3 as array job 100"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("squeue -j 100,101"), std::string::npos) << r.out;
  const std::string array = ReadFile(dir_.File("res.slurm/array.sh"));
  EXPECT_NE(array.find("#SBATCH --cpus-per-task=2\n"), std::string::npos) << array;
  EXPECT_NE(array.find("study '" + fs::canonical(dir_.File("s.ini")).string() + "' --out '" +
                       slurm + "/shard-'\"$K\" --shard \"$K/3\""),
            std::string::npos)
      << array;
  const std::string merge = ReadFile(dir_.File("res.slurm/merge.sh"));
  EXPECT_NE(merge.find(" merge '" + fs::canonical(dir_.path()).string() + "/res' '" + slurm +
                       "/shard-1' '" + slurm + "/shard-2' '" + slurm + "/shard-3'\n"),
            std::string::npos)
      << merge;
  EXPECT_NE(ReadFile(dir_.File("res.slurm/jobs.txt")).find(" array 100 shards 1,2,3 merge 101\n"),
            std::string::npos);
}

// What the array tasks would have done, done here: shards 1 and 3 complete,
// shard 2 not started. The resubmission picks shard 2; --status says so;
// once the merge exists nothing is submitted.
TEST_F(StudySlurm, ResubmissionRunsOnlyUnfinishedShards) {
  ASSERT_EQ(Estlab("study s.ini --out res --slurm 3 --slurm-dry-run").exit_code, 0);
  EXPECT_FALSE(dir_.Exists("bin/sbatch.log"));  // dry run: nothing submitted
  for (int k : {1, 3})
    ASSERT_EQ(Estlab("study s.ini --quiet --out res.slurm/shard-" + std::to_string(k) +
                     " --shard " + std::to_string(k) + "/3")
                  .exit_code,
              0);
  const auto status = Estlab("study --status res");
  ASSERT_EQ(status.exit_code, 0) << status.err;
  EXPECT_NE(status.out.find("res: not merged"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("2 of 3 shards complete"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("  2      not started   0/2"), std::string::npos) << status.out;
  EXPECT_NE(status.out.find("  3      complete      2/2"), std::string::npos) << status.out;

  const auto again = Estlab("study s.ini --out res --slurm 3 --json");
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("\"pending_shards\": [2]"), std::string::npos) << again.out;
  EXPECT_NE(ReadFile(dir_.File("bin/sbatch.log")).find("--array=2 "), std::string::npos);

  // The merge job's work, done here; then there is nothing to submit.
  ASSERT_EQ(Estlab("study s.ini --quiet --out res.slurm/shard-2 --shard 2/3").exit_code, 0);
  ASSERT_EQ(Estlab("merge res res.slurm/shard-1 res.slurm/shard-2 res.slurm/shard-3").exit_code, 0);
  const auto done = Estlab("study s.ini --out res --slurm 3");
  EXPECT_EQ(done.exit_code, 0) << done.err;
  EXPECT_NE(done.out.find("holds the merged study already; nothing to submit"), std::string::npos)
      << done.out;
  const auto complete = Estlab("study --status res --json");
  EXPECT_NE(complete.out.find("\"status\": \"complete\", \"finished_runs\": 6, \"total_runs\": 6"),
            std::string::npos)
      << complete.out;
  // Another study or shard count on the same OUT is refused.
  WriteText(dir_.File("other.ini"), TinyStudy(5));
  const auto other = Estlab("study other.ini --out res --slurm 3");
  EXPECT_EQ(other.exit_code, 2);
  EXPECT_NE(other.err.find("holds the submission of another study"), std::string::npos)
      << other.err;
}

TEST_F(StudySlurm, BadSlurmOptionsExitTwo) {
  const auto zero = Estlab("study s.ini --out res --slurm 0");
  EXPECT_EQ(zero.exit_code, 2);
  EXPECT_NE(zero.err.find("--slurm: the number of shards must be in 1..100000"), std::string::npos)
      << zero.err;
  const auto shard = Estlab("study s.ini --out res --slurm 3 --shard 1/3");
  EXPECT_EQ(shard.exit_code, 2);
  EXPECT_NE(shard.err.find("--slurm makes the shards itself"), std::string::npos) << shard.err;
  const auto alone = Estlab("study s.ini --out res --slurm-dry-run");
  EXPECT_EQ(alone.exit_code, 2);
  EXPECT_FALSE(dir_.Exists("res.slurm"));
  // sbatch refusing the job: its message, and an error exit.
  WriteText(dir_.File("bin/sbatch"),
            "#!/bin/sh\necho 'sbatch: error: invalid partition' >&2\n"
            "exit 1\n");
  const auto refused = Estlab("study s.ini --out res3 --slurm 2");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("sbatch failed (exit 1): sbatch: error: invalid partition"),
            std::string::npos)
      << refused.err;
  const auto missing = Estlab("study --status nowhere");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("'nowhere' is not a study results folder"), std::string::npos)
      << missing.err;
}

// 'text' for the shell of std::system.
std::string Quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// A results folder whose path holds a space, quotes, '$', a backquote and
// non-ASCII letters: sbatch gets each path as one word, and the scripts,
// run as Slurm would run them, write the merged study there.
TEST_F(StudySlurm, OddPathsAreQuotedAndTheScriptsRun) {
  // The stand-in sbatch logs one argument per line.
  WriteText(dir_.File("bin/sbatch"),
            "#!/bin/sh\n"
            "n=$(cat \"$(dirname \"$0\")/next\" 2>/dev/null || echo 100)\n"
            "for a in \"$@\"; do echo \"[$a]\"; done >> \"$(dirname \"$0\")/sbatch.log\"\n"
            "echo $((n + 1)) > \"$(dirname \"$0\")/next\"\n"
            "echo \"$n\"\n");
  const std::string odd = "we ird 'q' \"dq\" $HOME $ARRAY `id` \xc3\xa9";
  fs::create_directories(dir_.File(odd));
  const auto r = Estlab("study s.ini --out " + Quoted(odd + "/res") + " --slurm 3");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string slurm = fs::canonical(dir_.File(odd)).string() + "/res.slurm";
  const std::string log = ReadFile(dir_.File("bin/sbatch.log"));
  EXPECT_NE(log.find("[" + slurm + "/array.sh]\n"), std::string::npos) << log;
  EXPECT_NE(log.find("[--output=" + slurm + "/logs/shard-%a.out]\n"), std::string::npos) << log;
  EXPECT_NE(log.find("[" + slurm + "/merge.sh]\n"), std::string::npos) << log;
  EXPECT_NE(log.find("[--output=" + slurm + "/logs/merge.out]\n"), std::string::npos) << log;
  EXPECT_NE(log.find("[--dependency=afterok:100]\n"), std::string::npos) << log;
  // What Slurm would run: each task, then the merge.
  for (int k = 1; k <= 3; ++k) {
    const std::string cmd = "cd / && SLURM_ARRAY_TASK_ID=" + std::to_string(k) + " bash " +
                            Quoted(slurm + "/array.sh") + " > /dev/null 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  const std::string merge = "cd / && bash " + Quoted(slurm + "/merge.sh") + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(merge.c_str()), 0);
  EXPECT_TRUE(fs::is_regular_file(dir_.File(odd + "/res/summary.csv")));
  const auto status = Estlab("study --status " + Quoted(odd + "/res") + " --json");
  EXPECT_NE(status.out.find("\"status\": \"complete\", \"finished_runs\": 6, \"total_runs\": 6"),
            std::string::npos)
      << status.out;
}

// Shell code in --slurm-opts, a newline or '%' in --out: refused before
// anything is written or run.
TEST_F(StudySlurm, ShellSyntaxAndControlCharactersAreRefused) {
  const auto opts =
      Estlab("study s.ini --out res --slurm 2 --slurm-opts '--time=1 $(touch PWNED); echo x'");
  EXPECT_EQ(opts.exit_code, 2);
  EXPECT_NE(opts.err.find("--slurm-opts: shell syntax '$' at character 10"), std::string::npos)
      << opts.err;
  const auto newline = Estlab("study s.ini --out 'r\ntouch PWNED\n' --slurm 2 --slurm-dry-run");
  EXPECT_EQ(newline.exit_code, 2);
  EXPECT_NE(newline.err.find("holds a control character"), std::string::npos) << newline.err;
  const auto percent = Estlab("study s.ini --out 'r%j' --slurm 2 --slurm-dry-run");
  EXPECT_EQ(percent.exit_code, 2);
  EXPECT_NE(percent.err.find("holds '%'"), std::string::npos) << percent.err;
  for (const char* left :
       {"PWNED", "res.slurm", "r\ntouch PWNED\n.slurm", "r%j.slurm", "bin/sbatch.log"})
    EXPECT_FALSE(fs::exists(dir_.File(left))) << left;
}

}  // namespace
}  // namespace estlab::testing
