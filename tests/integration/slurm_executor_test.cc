// pba-server --executor slurm against a real Slurm: a one-node cluster of
// Debian's slurmctld, slurmd and munge (scripts/slurm-local.sh), the real
// server and the real client. Jobs are submitted with sbatch, followed with
// squeue, cancelled with scancel and collected from their folders; and the
// faults of the cluster path: Slurm's time limit, the memory limit, a
// scancel from outside PBA, a drained node, slurmctld restarted, a node
// lost mid-job, the server killed and restarted while its jobs wait and
// run, a partition Slurm does not have, a result damaged after pba-solve
// wrote it. Label slurm; each test brings up its own cluster on ports
// of its own, and ctest's RESOURCE_LOCK runs them one at a time (each a node of the machine's cores
// and memory).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "common/subprocess.h"
#include "integration/block_scene.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::seconds;
using Clock = std::chrono::steady_clock;

// A viscoelastic hold of `end_s` model seconds in steps of 0.1 s: a job
// that runs for a while (about a quarter of a second per model second on
// one core of the 2-core machine, 120 MB) with progress all along.
std::string Hold(const std::string& name, double end_s) {
  std::string yaml = HoldSceneYaml(end_s, 1.5);
  const std::string end = "end_time_s: ";
  const std::size_t at = yaml.find('\n', yaml.find(end));
  yaml.insert(at + 1, "    initial_step_s: 0.1\n    max_step_s: 0.1\n");
  return "name: " + name + yaml.substr(yaml.find('\n'));
}

// A TCP port on 127.0.0.1 nothing listens on now (the kernel's pick).
int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof address;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    port = ntohs(address.sin_port);
  }
  ::close(fd);
  return port;
}

class SlurmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // munged wants every directory above its socket open to all (x).
    fs::permissions(dir_.path(), fs::perms::others_exec | fs::perms::group_exec,
                    fs::perm_options::add);
    slurm_dir_ = dir_.path() / "slurm";
    ::setenv("PBA_SLURM_DIR", slurm_dir_.c_str(), 1);
    // Ports of their own: a cluster some earlier run left behind cannot
    // stand in the way.
    ::setenv("PBA_SLURM_CTLD_PORT", std::to_string(FreePort()).c_str(), 1);
    ::setenv("PBA_SLURM_SLURMD_PORT", std::to_string(FreePort()).c_str(), 1);
    ::setenv("SLURM_CONF", (slurm_dir_ / "slurm.conf").c_str(), 1);
    const RunResult up = Cluster({"start"});
    ASSERT_EQ(up.exit_code, 0) << up.out << up.err;
    host_ = RunProcess({FindProgram("hostname"), "-s"}).out;
    host_ = host_.substr(0, host_.find('\n'));
  }

  void TearDown() override {
    if (HasFailure()) {
      if (server_ != nullptr) std::cerr << "server log:\n" << ReadFile(server_->log_path());
      std::cerr << "slurmctld log (end):\n" << Tail(slurm_dir_ / "log" / "slurmctld.log");
    }
    if (server_ != nullptr) server_->Stop();
    server_.reset();
    Cluster({"stop", "--clean"});
  }

  static std::string Tail(const fs::path& path) {
    const std::string text = ReadFile(path);
    return text.size() > 4000 ? text.substr(text.size() - 4000) : text;
  }

  RunResult Cluster(std::vector<std::string> args) {
    args.insert(args.begin(), {FindProgram("bash"), PBA_SOURCE_DIR "/scripts/slurm-local.sh"});
    return RunProcess(args, seconds(120));
  }

  // One of Slurm's commands (scontrol, scancel, squeue), its output.
  RunResult Slurm(std::vector<std::string> args) {
    args[0] = FindProgram(args[0]);
    return RunProcess(args, seconds(60));
  }

  bool StartServer(const std::vector<std::string>& extra = {}, std::string* log = nullptr) {
    std::string ignored;
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, dir_.path() / "data");
    std::vector<std::string> args = {"--executor", "slurm",          "--slurm-poll",
                                     "0.3",        "--max-attempts", "3"};
    args.insert(args.end(), extra.begin(), extra.end());
    if (!server_->Start(log != nullptr ? log : &ignored, args)) return false;
    std::ifstream token(dir_.path() / "data" / "admin.token");
    std::string admin;
    if (!(token >> admin)) return false;
    ::setenv("PBA_TOKEN", admin.c_str(), 1);
    return true;
  }

  RunResult Pba(std::vector<std::string> args, seconds timeout = seconds(300)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, timeout);
  }

  std::string Submit(const std::string& name, const std::string& yaml,
                     std::vector<std::string> extra = {}) {
    const fs::path scene = dir_.path() / (name + ".yaml");
    std::ofstream(scene) << yaml;
    std::vector<std::string> args = {"job", "submit", scene.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const RunResult submitted = Pba(args);
    EXPECT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err;
    std::smatch match;
    static const std::regex kId("Submitted job (\\S+)");
    return std::regex_search(submitted.out, match, kId) ? match[1].str() : "";
  }

  std::string Show(const std::string& id) { return Pba({"job", "show", id}).out; }  // = status

  // The Slurm job id `pba job show` names ("" before it has one).
  static std::string SlurmJobIn(const std::string& shown) {
    std::smatch match;
    static const std::regex kSlurm("Slurm job\\s+([0-9_]+)");  // a task: <array>_<task>
    return std::regex_search(shown, match, kSlurm) ? match[1].str() : "";
  }
  std::string SlurmJob(const std::string& id) { return SlurmJobIn(Show(id)); }

  // Polls `pba job show` until `pred` holds of its text.
  template <typename Pred>
  bool WaitForShow(const std::string& id, Pred pred, seconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (pred(Show(id))) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    return false;
  }
  bool WaitForState(const std::string& id, const std::string& state, seconds timeout) {
    return WaitForShow(
        id,
        [&](const std::string& shown) {
          return std::regex_search(shown, std::regex("State\\s+" + state + "\\b"));
        },
        timeout);
  }

  // Lines of Slurm's job completion file naming the PBA job (one per run).
  std::size_t SlurmRuns(const std::string& id) {
    return CountOf(ReadFile(slurm_dir_ / "jobcomp.txt"), "Name=pba-" + id + " ");
  }

  TempDir dir_;
  fs::path slurm_dir_;
  std::string host_;
  std::unique_ptr<ServerProcess> server_;
};

TEST_F(SlurmTest, AJobRunsAsASlurmJobWithItsProgressAndResult) {
  // pba-solve as the server runs it, but once it has ended a job named
  // "damaged" has its result.h5 cut short, and one named "late" has it
  // moved aside (the test puts it back), as a shared filesystem between
  // node and server might show them.
  const fs::path solver = dir_.path() / "pba-solve-then-damage";
  std::ofstream(solver) << "#!/bin/sh\n" PBA_SOLVE_BIN
                           " \"$@\"\ncode=$?\nprev=\n"
                           "for a in \"$@\"; do [ \"$prev\" = --out ] && out=$a; prev=$a; done\n"
                           "if [ $code -eq 0 ] && grep -q '\"name\": *\"damaged\"' \"$1\"; then\n"
                           "  truncate -s 100 \"$out/result.h5\"\nfi\n"
                           "if [ $code -eq 0 ] && grep -q '\"name\": *\"late\"' \"$1\"; then\n"
                           "  mv \"$out/result.h5\" \"$out/../late-result.h5\"\nfi\nexit $code\n";
  fs::permissions(solver, fs::perms::owner_all, fs::perm_options::add);
  ASSERT_TRUE(StartServer({"--solver", solver.string(), "--slurm-settle", "60"}));
  const fs::path scene = dir_.path() / "hold.yaml";
  std::ofstream(scene) << Hold("hold", 10);
  const RunResult run = Pba({"--json", "job", "submit", scene.string(), "--wait"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  // The events of --wait: Slurm's, then pba-solve's progress, then the end.
  EXPECT_NE(run.out.find("submitted to Slurm as job"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("\"progress\""), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("SUCCEEDED"), std::string::npos) << run.out;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(run.out, match, std::regex("\"job_?[iI]d\":\\s*\"(j[0-9a-f]+)\"")))
      << run.out;
  const std::string id = match[1].str();
  const std::string shown = Show(id);
  EXPECT_TRUE(std::regex_search(shown, std::regex("Slurm job\\s+\\d+ \\(COMPLETED"))) << shown;
  EXPECT_TRUE(std::regex_search(shown, std::regex("Attempts\\s+1\\b"))) << shown;
  // The result, checked against its digests by the client as it is fetched.
  const RunResult fetched = Pba({"job", "fetch", id, "-o", (dir_.path() / "out").string()});
  ASSERT_EQ(fetched.exit_code, 0) << fetched.out << fetched.err;
  EXPECT_TRUE(fs::exists(dir_.path() / "out" / "summary.json"));
  EXPECT_EQ(SlurmRuns(id), 1u);

  // A result Slurm ran to its end but that is not as pba-solve listed it
  // fails, naming the file; nothing of it is offered.
  const std::string damaged = Submit("damaged", Hold("damaged", 2));
  ASSERT_FALSE(damaged.empty());
  ASSERT_TRUE(WaitForState(damaged, "FAILED", seconds(120))) << Show(damaged);
  const std::string failed = Show(damaged);
  EXPECT_TRUE(std::regex_search(
      failed, std::regex("Slurm job \\d+ \\(COMPLETED[^)]*\\): pba-solve succeeded but .*"
                         "result.h5 is damaged: its SHA-256 is [0-9a-f]{64}, SHA256SUMS says "
                         "[0-9a-f]{64} \\(100 bytes now\\)")))
      << failed;
  EXPECT_NE(Pba({"job", "fetch", damaged, "-o", (dir_.path() / "damaged").string()}).exit_code, 0);
  EXPECT_FALSE(fs::exists(dir_.path() / "damaged" / "result.h5"));

  // A result that shows its last file late is waited for (--slurm-settle),
  // not failed: the file is put back only once the server has said it
  // waits.
  const std::string late = Submit("late", Hold("late", 2));
  ASSERT_FALSE(late.empty());
  const fs::path late_dir = dir_.path() / "data" / "jobs" / late;
  const std::string waits = "job " + late + ": Slurm job ";
  const std::string why = "lacks result.h5, which SHA256SUMS names; looking again for up to 60 s";
  const auto said = [&] {
    const std::string log = ReadFile(server_->log_path());
    const std::size_t at = log.find(waits);
    return at != std::string::npos && log.find(why, at) != std::string::npos;
  };
  const auto deadline = Clock::now() + seconds(120);
  while (Clock::now() < deadline && !said()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_TRUE(said()) << ReadFile(server_->log_path());
  ASSERT_TRUE(fs::exists(late_dir / "late-result.h5"));
  for (const fs::directory_entry& entry : fs::directory_iterator(late_dir)) {
    if (entry.path().filename().string().rfind("result-", 0) == 0) {
      fs::rename(late_dir / "late-result.h5", entry.path() / "result.h5");
    }
  }
  ASSERT_TRUE(WaitForState(late, "SUCCEEDED", seconds(60))) << Show(late);
  EXPECT_EQ(Pba({"job", "fetch", late, "-o", (dir_.path() / "late").string()}).exit_code, 0);
  EXPECT_TRUE(fs::exists(dir_.path() / "late" / "result.h5"));

  // A batch, unchanged: each member a Slurm job, all of them through, once
  // each.
  std::ofstream(dir_.path() / "base.yaml") << Hold("member", 2);
  std::ofstream(dir_.path() / "sweep.yaml") << "name: sweep\nscene: base.yaml\nparallel: 4\n"
                                               "sweep:\n  analysis.time.end_time_s: [1, 2, 3, 4]\n"
                                               "outputs:\n  - performance.wall_time_s\n";
  const RunResult batched =
      Pba({"batch", "run", (dir_.path() / "sweep.yaml").string(), "--no-plot"}, seconds(300));
  EXPECT_EQ(batched.exit_code, 0) << batched.out << batched.err;
  // The first job, the damaged and the late one (Slurm ran both to their
  // end) and the four.
  EXPECT_EQ(CountOf(ReadFile(slurm_dir_ / "jobcomp.txt"), "JobState=COMPLETED"), 7u);
}

// A sweep handed to Slurm together goes as one job array. The controller
// is out of reach while the members are queued (squeue and sbatch wait or
// fail: they wait in PBA's queue); once it is back, all of them go in one
// sbatch, the fewest an array takes being 4 here. Each
// member is a task of the array with a state of its own: one cancelled
// through PBA while it waits ends CANCELLED, the others succeed, each run
// once, though the server is killed and started again meanwhile.
TEST_F(SlurmTest, ASweepGoesAsOneJobArrayWithAStateForEachMember) {
  ASSERT_TRUE(StartServer({"--slurm-array-min", "4"}));
  ASSERT_EQ(Cluster({"stop-ctld"}).exit_code, 0);
  std::vector<std::string> ids;
  for (int i = 0; i < 5; ++i) {
    const std::string name = "member" + std::to_string(i);
    ids.push_back(Submit(name, Hold(name, 30)));
    ASSERT_FALSE(ids.back().empty());
  }
  const RunResult back = Cluster({"restart-ctld"});
  ASSERT_EQ(back.exit_code, 0) << back.out << back.err;
  // Two run at once on the two CPUs: the last waits for a while.
  std::string array;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    ASSERT_TRUE(WaitForShow(
        ids[i], [](const std::string& shown) { return !SlurmJobIn(shown).empty(); }, seconds(120)))
        << Show(ids[i]);
    const std::string slurm_id = SlurmJob(ids[i]);
    const std::size_t underscore = slurm_id.find('_');
    ASSERT_NE(underscore, std::string::npos) << slurm_id;
    if (array.empty()) array = slurm_id.substr(0, underscore);
    EXPECT_EQ(slurm_id, array + "_" + std::to_string(i));
  }
  const RunResult cancelled = Pba({"job", "cancel", ids[4]});
  EXPECT_EQ(cancelled.exit_code, 0) << cancelled.out << cancelled.err;
  ASSERT_TRUE(WaitForState(ids[4], "CANCELLED", seconds(60))) << Show(ids[4]);
  // The server killed while tasks run and wait, and started again: it
  // follows each task by its id.
  server_->Kill();
  std::string log;
  ASSERT_TRUE(StartServer({"--slurm-array-min", "4"}, &log)) << log;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(WaitForState(ids[i], "SUCCEEDED", seconds(180))) << Show(ids[i]);
    const std::string shown = Show(ids[i]);
    EXPECT_TRUE(std::regex_search(shown, std::regex("Attempts\\s+1\\b"))) << shown;
    // Its events, from the start: how it went to Slurm.
    const std::string events = Pba({"job", "watch", ids[i]}).out;
    EXPECT_NE(
        events.find("submitted to Slurm as task " + std::to_string(i) + " of job array " + array),
        std::string::npos)
        << events;
  }
  // One line per task in Slurm's job completion file: four completed, and
  // no member submitted on its own.
  const std::string completions = ReadFile(slurm_dir_ / "jobcomp.txt");
  EXPECT_EQ(CountOf(completions, "JobState=COMPLETED"), 4u) << completions;
  EXPECT_EQ(CountOf(completions, "Name=pba-j"), 0u) << completions;
}

// `pba batch run` of a sweep that does not say how many at a time, as a
// user writes it: against a Slurm-backed server the client hands every
// member over at once, the server gathers the submits into one round, and
// the ten members go to Slurm as one job array of ten tasks.
TEST_F(SlurmTest, ABatchRunGoesToSlurmAsOneJobArray) {
  ASSERT_TRUE(StartServer());
  const RunResult info = Pba({"server"});
  EXPECT_NE(
      info.out.find("executor: slurm (jobs handed over together go as one job array from 10)"),
      std::string::npos)
      << info.out;
  std::ofstream(dir_.path() / "base.yaml") << SmallBlockSceneYaml("block");
  std::ofstream(dir_.path() / "sweep.yaml") << R"(name: stiffness
scene: base.yaml
sweep:
  material.linear_elastic.youngs_modulus_pa: [1000, 2000, 3000, 4000, 5000]
  material.linear_elastic.poissons_ratio: [0.3, 0.45]
outputs:
  - results.reactions[1].force_n[2]
)";
  const RunResult run = Pba({"batch", "run", (dir_.path() / "sweep.yaml").string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("10 to submit, all at once"), std::string::npos) << run.out;
  const std::string csv = ReadFile(dir_.path() / "sweep.csv");
  EXPECT_EQ(CountOf(csv, "SUCCEEDED"), 10u) << csv;
  // Ten tasks of one array in Slurm's job completion file, none on its own.
  const std::string completions = ReadFile(slurm_dir_ / "jobcomp.txt");
  EXPECT_EQ(CountOf(completions, "JobState=COMPLETED"), 10u) << completions;
  EXPECT_EQ(CountOf(completions, "Name=pba-j"), 0u) << completions;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(csv, match, std::regex(",(j[0-9a-f]+),SUCCEEDED"))) << csv;
  const std::string slurm_id = SlurmJob(match[1].str());
  EXPECT_TRUE(std::regex_match(slurm_id, std::regex("[0-9]+_[0-9]"))) << slurm_id;
}

// A job on two MPI ranks: one Slurm job of two tasks, pba-solve started by
// mpirun inside the allocation, the job saying it ran on both.
TEST_F(SlurmTest, AJobOnTwoRanksRunsUnderMpirunInItsAllocation) {
  // Open MPI refuses to run as root unless told (CI runs as root); the
  // server's environment reaches the job through sbatch.
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  ASSERT_TRUE(StartServer({"--max-ranks", "2"}));
  const std::string id = Submit(
      "ranks", BlockSceneYaml("ranks", 10) + "analysis: {type: LINEAR_STATIC}\n", {"--ranks", "2"});
  ASSERT_FALSE(id.empty());
  ASSERT_TRUE(WaitForState(id, "SUCCEEDED", seconds(180)))
      << Show(id) << ReadFile(dir_.path() / "data" / "jobs" / id / "solve.log");
  const std::string shown = Show(id);
  EXPECT_NE(shown.find("on 2 MPI ranks"), std::string::npos) << shown;
  // Slurm gave it two tasks.
  const std::string completions = ReadFile(slurm_dir_ / "jobcomp.txt");
  const std::size_t line = completions.find("Name=pba-" + id + " ");
  ASSERT_NE(line, std::string::npos) << completions;
  const std::string record = completions.substr(line, completions.find('\n', line) - line);
  EXPECT_NE(record.find("ProcCnt=2"), std::string::npos) << record;
  EXPECT_EQ(SlurmRuns(id), 1u);
}

TEST_F(SlurmTest, CancelledThroughPbaOrWithScancelFromOutside) {
  ASSERT_TRUE(StartServer());
  const std::string ours = Submit("ours", Hold("ours", 4000));
  const std::string theirs = Submit("theirs", Hold("theirs", 4000));
  ASSERT_TRUE(WaitForState(ours, "RUNNING", seconds(60))) << Show(ours);
  ASSERT_TRUE(WaitForState(theirs, "RUNNING", seconds(60))) << Show(theirs);
  const RunResult cancelled = Pba({"job", "cancel", ours});
  EXPECT_EQ(cancelled.exit_code, 0) << cancelled.out << cancelled.err;
  ASSERT_TRUE(WaitForState(ours, "CANCELLED", seconds(60))) << Show(ours);
  EXPECT_NE(Show(ours).find("cancelled by request"), std::string::npos) << Show(ours);

  const std::string slurm_id = SlurmJob(theirs);
  ASSERT_FALSE(slurm_id.empty()) << Show(theirs);
  EXPECT_EQ(Slurm({"scancel", slurm_id}).exit_code, 0);
  ASSERT_TRUE(WaitForState(theirs, "CANCELLED", seconds(60))) << Show(theirs);
  const std::string shown = Show(theirs);
  EXPECT_NE(shown.find("cancelled in Slurm, not through PBA"), std::string::npos) << shown;
  // Nothing half-written is left as a result.
  EXPECT_FALSE(fs::exists(dir_.path() / "data" / "jobs" / theirs / "result"));
}

TEST_F(SlurmTest, SlurmsTimeLimitEndsTheJobSayingSo) {
  ASSERT_TRUE(StartServer());
  // A limit of 20 s is a minute in Slurm (it counts minutes), and Slurm
  // stops the job within about half a minute after it.
  const std::string id = Submit("slow", Hold("slow", 4000), {"--timeout", "20"});
  ASSERT_TRUE(WaitForState(id, "RUNNING", seconds(60))) << Show(id);
  ASSERT_TRUE(WaitForState(id, "FAILED", seconds(180))) << Show(id);
  const std::string shown = Show(id);
  EXPECT_NE(shown.find("TIMEOUT"), std::string::npos) << shown;
  EXPECT_NE(shown.find("stopped by Slurm at its time limit of 1 min"), std::string::npos) << shown;
}

TEST_F(SlurmTest, AJobOverItsMemoryFailsSayingSo) {
  // 400 MiB: pba-solve starts, and its 30 mm block (about 880 MB) does not
  // fit; the same limit is the Slurm job's --mem.
  ASSERT_TRUE(StartServer({"--solver-memory", "0.4"}));
  const std::string id = Submit("big", BlockSceneYaml("big", 30));
  ASSERT_TRUE(WaitForState(id, "FAILED", seconds(240))) << Show(id);
  const std::string shown = Show(id);
  // pba-solve's own limit comes first (Slurm's --mem is polled): its words.
  EXPECT_NE(shown.find("out of memory"), std::string::npos) << shown;
  EXPECT_NE(shown.find("address-space limit is 409 MiB"), std::string::npos) << shown;
}

TEST_F(SlurmTest, ADrainedNodeKeepsJobsWaitingWithSlurmsReason) {
  ASSERT_TRUE(StartServer());
  ASSERT_EQ(Slurm({"scontrol", "update", "nodename=" + host_, "state=drain", "reason=pba-test"})
                .exit_code,
            0);
  const std::string id = Submit("waits", Hold("waits", 2));
  // QUEUED in PBA, PENDING in Slurm, with Slurm's words for why.
  ASSERT_TRUE(WaitForShow(
      id,
      [](const std::string& shown) {
        return shown.find("PENDING") != std::string::npos &&
               (shown.find("ReqNodeNotAvail") != std::string::npos ||
                shown.find("DRAINED") != std::string::npos);
      },
      seconds(60)))
      << Show(id);
  EXPECT_TRUE(std::regex_search(Show(id), std::regex("State\\s+QUEUED\\b"))) << Show(id);
  ASSERT_EQ(Slurm({"scontrol", "update", "nodename=" + host_, "state=resume"}).exit_code, 0);
  ASSERT_TRUE(WaitForState(id, "SUCCEEDED", seconds(120))) << Show(id);
}

// The server killed (SIGKILL) while one job runs and one waits in Slurm's
// queue, and started again: it follows both by their Slurm ids, and each
// runs once.
TEST_F(SlurmTest, AServerKilledAndStartedAgainLosesAndRerunsNothing) {
  ASSERT_TRUE(StartServer());
  const std::string running = Submit("running", Hold("running", 120));
  ASSERT_TRUE(WaitForState(running, "RUNNING", seconds(60))) << Show(running);
  ASSERT_EQ(Slurm({"scontrol", "update", "nodename=" + host_, "state=drain", "reason=pba-test"})
                .exit_code,
            0);
  const std::string waiting = Submit("waiting", Hold("waiting", 2));
  ASSERT_TRUE(WaitForShow(
      waiting, [](const std::string& s) { return s.find("PENDING") != std::string::npos; },
      seconds(60)));
  const std::string running_slurm = SlurmJob(running), waiting_slurm = SlurmJob(waiting);
  ASSERT_FALSE(running_slurm.empty());
  ASSERT_FALSE(waiting_slurm.empty());
  server_->Kill();
  ASSERT_EQ(Slurm({"scontrol", "update", "nodename=" + host_, "state=resume"}).exit_code, 0);
  std::string log;
  ASSERT_TRUE(StartServer({}, &log)) << log;
  ASSERT_TRUE(WaitForState(running, "SUCCEEDED", seconds(180))) << Show(running);
  ASSERT_TRUE(WaitForState(waiting, "SUCCEEDED", seconds(180))) << Show(waiting);
  EXPECT_EQ(SlurmJob(running), running_slurm);
  EXPECT_EQ(SlurmJob(waiting), waiting_slurm);
  EXPECT_TRUE(std::regex_search(Show(running), std::regex("Attempts\\s+1\\b"))) << Show(running);
  EXPECT_TRUE(std::regex_search(Show(waiting), std::regex("Attempts\\s+1\\b"))) << Show(waiting);
  EXPECT_EQ(SlurmRuns(running), 1u);
  EXPECT_EQ(SlurmRuns(waiting), 1u);
}

// slurmd lost while a job runs: Slurm declares the node down and the job
// NODE_FAIL, and PBA runs it again as a new Slurm job once the node is
// back. The lost run's pba-solve may still be writing (its slurmstepd
// outlives slurmd): its files are its own, never taken for the new run's.
TEST_F(SlurmTest, ANodeLostMidJobRunsTheJobAgainAsANewSlurmJob) {
  // A node silent for 10 s is down (60 s otherwise); Slurm notices within
  // about 30 s, well inside the job's minute.
  ASSERT_EQ(Cluster({"stop", "--clean"}).exit_code, 0);
  ::setenv("PBA_SLURM_SLURMD_TIMEOUT", "10", 1);
  const RunResult up = Cluster({"start"});
  ::unsetenv("PBA_SLURM_SLURMD_TIMEOUT");
  ASSERT_EQ(up.exit_code, 0) << up.out << up.err;
  ASSERT_TRUE(StartServer());
  const std::string id = Submit("lost", Hold("lost", 240));
  ASSERT_TRUE(WaitForState(id, "RUNNING", seconds(60))) << Show(id);
  const std::string first = SlurmJob(id);
  ASSERT_FALSE(first.empty());
  const std::string pid = ReadFile(slurm_dir_ / "run" / "slurmd.pid");
  ASSERT_FALSE(pid.empty());
  ASSERT_EQ(::kill(std::stoi(pid), SIGKILL), 0);
  // Re-queued and handed to Slurm again, waiting for the node.
  ASSERT_TRUE(WaitForShow(
      id,
      [&](const std::string& shown) {
        const std::string now = SlurmJobIn(shown);
        return !now.empty() && now != first;
      },
      seconds(120)))
      << Show(id);
  const RunResult back = Cluster({"start"});
  ASSERT_EQ(back.exit_code, 0) << back.out << back.err;
  ASSERT_TRUE(WaitForState(id, "SUCCEEDED", seconds(180))) << Show(id);
  const std::string shown = Show(id);
  EXPECT_TRUE(std::regex_search(shown, std::regex("Attempts\\s+2\\b"))) << shown;
  EXPECT_NE(SlurmJob(id), first);
  EXPECT_NE(ReadFile(server_->log_path()).find("re-queued: Slurm job " + first + " (NODE_FAIL"),
            std::string::npos)
      << ReadFile(server_->log_path());
  EXPECT_TRUE(fs::exists(dir_.path() / "data" / "jobs" / id / "result" / "summary.json"));
}

TEST_F(SlurmTest, SlurmctldRestartedWhileAJobRuns) {
  ASSERT_TRUE(StartServer());
  const std::string id = Submit("through", Hold("through", 120));
  ASSERT_TRUE(WaitForState(id, "RUNNING", seconds(60))) << Show(id);
  const RunResult restarted = Cluster({"restart-ctld"});
  ASSERT_EQ(restarted.exit_code, 0) << restarted.out << restarted.err;
  ASSERT_TRUE(WaitForState(id, "SUCCEEDED", seconds(180))) << Show(id);
  EXPECT_TRUE(std::regex_search(Show(id), std::regex("Attempts\\s+1\\b"))) << Show(id);
  EXPECT_EQ(SlurmRuns(id), 1u);
}

TEST_F(SlurmTest, WhatSlurmRefusesFailsTheJobOrTheServerSayingWhy) {
  ASSERT_TRUE(StartServer({"--slurm-partition", "no-such-partition"}));
  const std::string id = Submit("nowhere", Hold("nowhere", 2));
  ASSERT_TRUE(WaitForState(id, "FAILED", seconds(60))) << Show(id);
  const std::string shown = Show(id);
  EXPECT_NE(shown.find("Slurm refused the job: sbatch"), std::string::npos) << shown;
  EXPECT_NE(shown.find("partition"), std::string::npos) << shown;
  server_->Stop();
  server_.reset();

  // A server that cannot reach Slurm does not start, and says why: a
  // configuration that is not there, a controller that does not answer.
  ::setenv("SLURM_CONF", (dir_.path() / "missing.conf").c_str(), 1);
  std::string log;
  EXPECT_FALSE(StartServer({}, &log));
  EXPECT_NE(log.find("SLURM_CONF names"), std::string::npos) << log;
  ::setenv("SLURM_CONF", (slurm_dir_ / "slurm.conf").c_str(), 1);
  ASSERT_EQ(Cluster({"stop"}).exit_code, 0);
  EXPECT_FALSE(StartServer({}, &log));
  EXPECT_NE(log.find("squeue failed"), std::string::npos) << log;
  ::setenv("SLURM_CONF", (slurm_dir_ / "slurm.conf").c_str(), 1);
  server_.reset();
}

}  // namespace
}  // namespace pba::testing
