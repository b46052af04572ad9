// The parts of the Slurm executor that need no Slurm: the command runner,
// squeue's lines, Slurm's states as PBA takes them, the sbatch command
// line and the batch script (run here with /bin/sh). The executor itself
// runs against a real slurmctld and slurmd in tests/integration
// (slurm_executor_test.cc, label slurm).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "jobs/command.h"
#include "jobs/slurm_executor.h"
#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream content;
  content << in.rdbuf();
  return content.str();
}

TEST(CommandTest, CapturesOutputAndExitCode) {
  CommandResult r;
  ASSERT_TRUE(RunCommand({"sh", "-c", "echo out; echo err >&2; exit 3"}, {}, &r).ok());
  EXPECT_EQ(r.out, "out\n");
  EXPECT_EQ(r.err, "err\n");
  EXPECT_EQ(r.code, 3);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.Describe(), "exit code 3: err");
  CommandOptions with_env;
  with_env.env = {"PBA_COMMAND_TEST=yes", "PATH=/usr/bin:/bin"};
  ASSERT_TRUE(RunCommand({"sh", "-c", "printf %s \"$PBA_COMMAND_TEST\""}, with_env, &r).ok());
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.out, "yes");
}

TEST(CommandTest, ArgumentsReachTheProgramAsTheyAre) {
  CommandResult r;
  ASSERT_TRUE(RunCommand({"printf", "%s|", "a b", "$HOME", "'q'", ";rm"}, {}, &r).ok());
  EXPECT_EQ(r.out, "a b|$HOME|'q'|;rm|");
}

TEST(CommandTest, ATimeLimitKillsAndAMissingProgramIsRefused) {
  CommandOptions quick;
  quick.timeout = std::chrono::milliseconds(300);
  CommandResult r;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(RunCommand({"sh", "-c", "sleep 30 & sleep 30"}, quick, &r).ok());
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  EXPECT_TRUE(r.timed_out);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.Describe().find("time limit"), std::string::npos);
  const Status missing = RunCommand({"pba-no-such-program"}, {}, &r);
  EXPECT_EQ(missing.code(), Status::Code::kFailedPrecondition);
  EXPECT_NE(missing.message().find("pba-no-such-program"), std::string::npos);
}

TEST(CommandTest, OutputPastTheBoundIsDropped) {
  CommandOptions small;
  small.max_output_bytes = 1000;
  CommandResult r;
  ASSERT_TRUE(RunCommand({"sh", "-c", "head -c 100000 /dev/zero"}, small, &r).ok());
  EXPECT_EQ(r.out.size(), 1000u);
  EXPECT_TRUE(r.truncated);
  EXPECT_TRUE(r.ok());
}

// An array's jobs file is the shared folder's: a line past the bound is
// skipped whole, not held, and the lines after it are read as they are.
TEST(SlurmPartsTest, ListLinesAreBounded) {
  std::istringstream in("j1\n" + std::string(100000, 'x') + "\nj2\nj3");
  std::string line;
  std::vector<std::string> lines;
  while (ReadBoundedLine(in, 16, &line)) {
    lines.push_back(line);
    EXPECT_LE(line.capacity(), 100000u);
  }
  EXPECT_EQ(lines, (std::vector<std::string>{"j1", "", "j2", "j3"}));
  std::istringstream empty("");
  EXPECT_FALSE(ReadBoundedLine(empty, 16, &line));
}

TEST(SlurmPartsTest, SqueueLinesAreReadAndOthersSkipped) {
  const std::vector<SlurmJobState> jobs = ParseSqueue(
      "12|pba-0001|PENDING|ReqNodeNotAvail, UnavailableNodes:n1|\n"
      "13_4|pba-0002|RUNNING|None|node1\n"
      "garbage\n"
      "x|pba-3|RUNNING|None|n\n"
      "14|pba-0003|TIMEOUT|TimeLimit|node1");
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].id, "12");
  EXPECT_EQ(jobs[0].reason, "ReqNodeNotAvail, UnavailableNodes:n1");
  EXPECT_EQ(jobs[0].node, "");
  EXPECT_EQ(jobs[1].id, "13_4");
  EXPECT_EQ(jobs[1].node, "node1");
  EXPECT_EQ(jobs[2].state, "TIMEOUT");
}

TEST(SlurmPartsTest, SacctLinesOfTheJobLastOneLast) {
  const std::vector<SlurmJobState> lines =
      ParseSacct("14|PENDING|0:0\n15|COMPLETED|0:0\n14|NODE_FAIL|0:0\n14|COMPLETED|0:0\n", "14");
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines.back().state, "COMPLETED");
  EXPECT_TRUE(ParseSacct("garbage\n", "14").empty());
}

TEST(SlurmPartsTest, SlurmStatesAsPbaTakesThem) {
  EXPECT_EQ(ClassifySlurmState("PENDING"), SlurmEnd::kNotEnded);
  EXPECT_EQ(ClassifySlurmState("RUNNING"), SlurmEnd::kNotEnded);
  EXPECT_EQ(ClassifySlurmState("COMPLETING"), SlurmEnd::kNotEnded);
  EXPECT_EQ(ClassifySlurmState("COMPLETED"), SlurmEnd::kCompleted);
  EXPECT_EQ(ClassifySlurmState("FAILED"), SlurmEnd::kFailed);
  EXPECT_EQ(ClassifySlurmState("TIMEOUT"), SlurmEnd::kTimeout);
  EXPECT_EQ(ClassifySlurmState("OUT_OF_MEMORY"), SlurmEnd::kOutOfMemory);
  EXPECT_EQ(ClassifySlurmState("CANCELLED"), SlurmEnd::kCancelled);
  EXPECT_EQ(ClassifySlurmState("CANCELLED by 0"), SlurmEnd::kCancelled);
  EXPECT_EQ(ClassifySlurmState("NODE_FAIL"), SlurmEnd::kRequeue);
  EXPECT_EQ(ClassifySlurmState("PREEMPTED"), SlurmEnd::kRequeue);
  EXPECT_EQ(ClassifySlurmState("BOOT_FAIL"), SlurmEnd::kRequeue);
  EXPECT_EQ(ClassifySlurmState("DEADLINE"), SlurmEnd::kFailed);
  EXPECT_TRUE(SlurmRunning("RUNNING"));
  EXPECT_TRUE(SlurmRunning("COMPLETING"));
  EXPECT_FALSE(SlurmRunning("PENDING"));
}

TEST(SlurmPartsTest, SbatchGetsTheFolderNameAndLimits) {
  SlurmOptions options;
  options.partition = "short";
  options.account = "lab";
  SlurmSubmission s;
  s.job_id = "0123abcd";
  s.dir = "/shared/jobs/0123abcd";
  s.script = s.dir / "job.sh";
  s.ranks = 4;
  s.cpus_per_task = 2;
  s.time_limit_s = 90;
  s.memory_bytes = (int64_t{3} << 30) + 1;  // rounded up to whole MiB
  const std::vector<std::string> args = SbatchArguments(options, s);
  const auto has = [&](const std::string& a) {
    return std::find(args.begin(), args.end(), a) != args.end();
  };
  EXPECT_TRUE(has("--parsable"));
  EXPECT_TRUE(has("--job-name=pba-0123abcd"));
  EXPECT_TRUE(has("--chdir=/shared/jobs/0123abcd"));
  EXPECT_TRUE(has("--output=/shared/jobs/0123abcd/progress-%j.jsonl"));  // Slurm's job id
  EXPECT_TRUE(has("--error=/shared/jobs/0123abcd/solve.log"));
  EXPECT_TRUE(has("--no-requeue"));
  EXPECT_TRUE(has("--ntasks=4"));
  EXPECT_TRUE(has("--cpus-per-task=2"));
  EXPECT_TRUE(has("--time=2"));  // whole minutes, rounded up
  EXPECT_TRUE(has("--mem=3073M"));
  EXPECT_TRUE(has("--partition=short"));
  EXPECT_TRUE(has("--account=lab"));
  EXPECT_EQ(args.back(), "/shared/jobs/0123abcd/job.sh");
  s.time_limit_s = 0;
  s.memory_bytes = 0;
  const std::vector<std::string> plain = SbatchArguments(SlurmOptions(), s);
  for (const std::string& a : plain) {
    EXPECT_NE(a.rfind("--time", 0), 0u) << a;
    EXPECT_NE(a.rfind("--mem", 0), 0u) << a;
    EXPECT_NE(a.rfind("--partition", 0), 0u) << a;
  }
}

// The script, run by /bin/sh as Slurm would: the arguments arrive as they
// are, and the exit code lands in exit_code-<Slurm job id>, whole.
TEST(SlurmPartsTest, TheBatchScriptRunsTheCommandAndKeepsItsExitCode) {
  TempDir dir;
  const std::filesystem::path out = dir.path() / "args";
  const std::string script =
      SlurmBatchScript({"sh", "-c", "printf '%s|' \"$@\" > " + out.string() + "; exit 5", "zero",
                        "it's", "$(touch " + (dir.path() / "pwned").string() + ")", "a b"},
                       int64_t{2} << 30);
  EXPECT_NE(script.find("ulimit -v 2097152"), std::string::npos) << script;
  std::ofstream(dir.path() / "job.sh") << script;
  CommandResult r;
  CommandOptions as_slurm;
  as_slurm.env = {"SLURM_JOB_ID=77"};
  ASSERT_TRUE(
      RunCommand({"sh", "-c", "cd \"$0\" && sh job.sh", dir.path().string()}, as_slurm, &r).ok());
  EXPECT_EQ(r.code, 5) << r.err;
  EXPECT_EQ(ReadFile(out), "it's|$(touch " + (dir.path() / "pwned").string() + ")|a b|");
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "pwned"));
  EXPECT_EQ(ReadFile(dir.path() / "exit_code-77"), "5\n");
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "exit_code-77.partial"));
  // pba-solve's --out: this run's own result folder.
  EXPECT_NE(
      SlurmBatchScript({"pba-solve", "@PBA_RUN_RESULT@"}, 0).find("'pba-solve' result-\"$run\""),
      std::string::npos);
}

// A job array: one sbatch whose task N writes through entry N of the
// array's folder (a link to its job's folder), named after the array.
TEST(SlurmPartsTest, AnArrayGoesInOneSbatch) {
  SlurmSubmission s;
  s.job_id = "j0123-1";
  s.dir = "/shared/jobs/arrays/j0123-1";
  s.script = s.dir / "array.sh";
  s.array_tasks = 12;
  const std::vector<std::string> args = SbatchArguments(SlurmOptions(), s);
  const auto has = [&](const std::string& a) {
    return std::find(args.begin(), args.end(), a) != args.end();
  };
  EXPECT_TRUE(has("--array=0-11"));
  EXPECT_TRUE(has("--job-name=pba-array-j0123-1"));
  EXPECT_TRUE(has("--chdir=/shared/jobs/arrays/j0123-1"));
  EXPECT_TRUE(has("--output=/shared/jobs/arrays/j0123-1/%a/progress-%A_%a.jsonl"));
  EXPECT_TRUE(has("--error=/shared/jobs/arrays/j0123-1/%a/solve.log"));
  EXPECT_TRUE(has("--no-requeue"));
  EXPECT_EQ(args.back(), "/shared/jobs/arrays/j0123-1/array.sh");
}

// The array's script, run by /bin/sh as Slurm runs task 1: it goes into
// that task's job folder and runs its job's script there, whose files are
// named <array job id>_<task id>.
TEST(SlurmPartsTest, AnArrayTaskRunsItsJobInItsFolder) {
  TempDir dir;
  const std::filesystem::path jobs = dir.path() / "jobs";
  for (const char* job : {"ja", "jb"}) {
    std::filesystem::create_directories(jobs / job);
    std::ofstream(jobs / job / "job.sh")
        << SlurmBatchScript({"sh", "-c", std::string("pwd > where; exit 3"), "zero"}, 0);
  }
  const std::filesystem::path array = jobs / "arrays" / "ja-1";
  std::filesystem::create_directories(array);
  std::filesystem::create_directory_symlink("../../ja", array / "0");
  std::filesystem::create_directory_symlink("../../jb", array / "1");
  std::ofstream(array / "array.sh") << SlurmArrayScript("job.sh");
  CommandResult r;
  CommandOptions as_slurm;
  as_slurm.env = {"SLURM_JOB_ID=91", "SLURM_ARRAY_JOB_ID=90", "SLURM_ARRAY_TASK_ID=1"};
  ASSERT_TRUE(
      RunCommand({"sh", "-c", "cd \"$0\" && sh array.sh", array.string()}, as_slurm, &r).ok());
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_EQ(ReadFile(jobs / "jb" / "exit_code-90_1"), "3\n");
  EXPECT_TRUE(std::filesystem::exists(jobs / "jb" / "where"));
  EXPECT_FALSE(std::filesystem::exists(jobs / "ja" / "where"));
  EXPECT_FALSE(std::filesystem::exists(jobs / "jb" / "exit_code-91"));
  // A task whose entry is missing ends at once, having run nothing.
  as_slurm.env = {"SLURM_JOB_ID=92", "SLURM_ARRAY_JOB_ID=90", "SLURM_ARRAY_TASK_ID=2"};
  ASSERT_TRUE(
      RunCommand({"sh", "-c", "cd \"$0\" && sh array.sh", array.string()}, as_slurm, &r).ok());
  EXPECT_NE(r.code, 0);
}

// A round of submits goes to Slurm once none has come for `gather`, or
// kSlurmGatherCap gathers after the first (a steady stream of submits does
// not hold the queue back for ever); none since the last round: at once.
TEST(SlurmPartsTest, SubmitsAreGatheredUntilTheyPause) {
  using Clock = std::chrono::steady_clock;
  const std::chrono::milliseconds gather{1000};
  const Clock::time_point t0 = Clock::now();
  EXPECT_EQ(GatherLeft({}, {}, t0, gather), Clock::duration::zero());
  EXPECT_EQ(GatherLeft(t0, t0, t0, gather), gather);
  EXPECT_EQ(GatherLeft(t0, t0, t0 + std::chrono::milliseconds(400), gather),
            std::chrono::milliseconds(600));
  EXPECT_EQ(GatherLeft(t0, t0, t0 + gather, gather), Clock::duration::zero());
  // A submit every half gather: each pushes the round back, up to the cap.
  const Clock::time_point late = t0 + std::chrono::milliseconds(9500);
  EXPECT_EQ(GatherLeft(t0, late, late, gather), std::chrono::milliseconds(500));
  EXPECT_EQ(GatherLeft(t0, late, t0 + gather * kSlurmGatherCap, gather), Clock::duration::zero());
  EXPECT_EQ(GatherLeft(t0, t0, t0, std::chrono::milliseconds(0)), Clock::duration::zero());
}

}  // namespace
}  // namespace pba
