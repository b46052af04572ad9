// SlurmExecutor: runs queued jobs as Slurm jobs (pba-server --executor
// slurm), through Slurm's own commands: sbatch, squeue, scancel.
//
// One thread follows everything. Each round it
//   1. hands QUEUED jobs to Slurm, up to `max_submitted` in Slurm's hands
//      at once: the job's folder under `jobs_dir` (a directory every node
//      sees) is prepared as for a local run (job_run.h), and `sbatch`
//      submits a script that runs pba-solve there (under mpirun for a job
//      on several ranks), its stdout (the progress lines) to
//      progress-<Slurm id>.jsonl, its stderr to solve.log, its result to
//      result-<Slurm id> and its exit code, once it has one, to
//      exit_code-<Slurm id> (each run's own files: a run lost on a failed
//      node cannot be taken for the next). The PBA job stays QUEUED, its
//      Job.scheduler naming the Slurm job (PENDING, with Slurm's reason);
//   2. reads every Slurm job of the server's user in one `squeue --states=all`
//      and, for each of its own:
//      - PENDING: keeps Slurm's reason (a drained node shows here);
//      - RUNNING: the PBA job becomes RUNNING (an attempt; the node noted),
//        and the new lines of its progress file become its progress events;
//      - ended: the run's result is renamed to result/, collected and
//        checked (SUCCEEDED), or the
//        job FAILED with Slurm's state and reason (TIMEOUT: its time limit;
//        OUT_OF_MEMORY: its memory) or pba-solve's error; CANCELLED when
//        PBA cancelled it, or when someone did with scancel (said so);
//        NODE_FAIL, PREEMPTED and BOOT_FAIL put it back in the queue for a
//        new Slurm job until it has been started `max_attempts` times;
//      - gone from squeue (it ended while the server was down, longer than
//        Slurm keeps finished jobs): sacct (slurmdbd's accounting, or the
//        job completion file with --completion) and the exit code file
//        decide, or the job FAILED saying nothing is known of its end.
// A job killed over its --mem shows FAILED on a cluster without cgroups;
// Slurm's "Exceeded job memory limit" in its stderr (solve.log) tells it.
// Cancel asks scancel; the job ends CANCELLED when Slurm says it has
// ended. Stop leaves the Slurm jobs running: a server started again
// re-attaches to them by the ids the store keeps (a job claimed but not yet
// named is found by its Slurm job name, pba-<job id>), and neither loses nor
// runs any of them twice.
#pragma once

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "jobs/command.h"
#include "jobs/job_executor.h"

namespace pba {

// With ExecutorOptions::jobs_dir a directory every compute node sees at
// the same path (the job folders, and the atlas mesh cache).
struct SlurmOptions {
  std::string partition;  // empty: Slurm's default partition
  std::string account;    // empty: the user's default account
  // CPUs of each rank (--cpus-per-task), pba-solve's --threads.
  int cpus_per_task = 1;
  // The most jobs in Slurm's hands (pending or running) at once; the rest
  // wait in PBA's queue.
  int max_submitted = 1000;
  // How often squeue is asked.
  std::chrono::milliseconds poll{2000};
  // Where sbatch, squeue and scancel are (empty: on PATH), and the
  // environment they get (e.g. SLURM_CONF=...).
  std::filesystem::path bin_dir;
  std::vector<std::string> env;
  // Time limit of each Slurm command.
  std::chrono::milliseconds command_timeout{60000};
};

// A Slurm job as squeue shows it.
struct SlurmJobState {
  std::string id, name, state, reason, node;
};

// squeue -h -o '%i|%j|%T|%r|%N' lines, as jobs (a line that does not
// parse is skipped).
std::vector<SlurmJobState> ParseSqueue(const std::string& text);

// sacct --parsable2 lines "JobID|State|ExitCode" of `slurm_id`, in order
// (a job run again has one for each end).
std::vector<SlurmJobState> ParseSacct(const std::string& text, const std::string& slurm_id);

// How PBA takes each Slurm state.
enum class SlurmEnd {
  kNotEnded,  // PENDING, RUNNING, CONFIGURING, COMPLETING, SUSPENDED, ...
  kCompleted,
  kFailed,       // FAILED, DEADLINE, SPECIAL_EXIT, and states PBA does not know
  kTimeout,      // TIMEOUT
  kOutOfMemory,  // OUT_OF_MEMORY
  kCancelled,    // CANCELLED (by PBA or by someone with scancel)
  kRequeue,      // NODE_FAIL, PREEMPTED, BOOT_FAIL: the job is run again
};
SlurmEnd ClassifySlurmState(const std::string& state);
bool SlurmRunning(const std::string& state);  // RUNNING or COMPLETING

// The sbatch command line (without the program) of one job: its folder,
// name, limits and script.
struct SlurmSubmission {
  std::string job_id;  // PBA's
  std::filesystem::path dir, script;
  int ranks = 1;
  int cpus_per_task = 1;
  int64_t time_limit_s = 0;  // 0: the partition's
  int64_t memory_bytes = 0;  // 0: the partition's default
};
std::vector<std::string> SbatchArguments(const SlurmOptions& options, const SlurmSubmission& s);

// The batch script: runs `command` (the program first; an argument
// "@PBA_RUN_RESULT@" becomes result-$SLURM_JOB_ID) in the job's folder,
// under an address-space limit when `memory_bytes` > 0, and writes its exit
// code to exit_code-$SLURM_JOB_ID (through a temporary file: the file is there whole or
// not at all). Each argument single-quoted for the shell.
std::string SlurmBatchScript(const std::vector<std::string>& command, int64_t memory_bytes);

class SlurmExecutor : public Executor {
 public:
  SlurmExecutor(JobStore& store, JobEventHub& hub, ExecutorOptions options, SlurmOptions slurm);
  SlurmExecutor(const SlurmExecutor&) = delete;
  SlurmExecutor& operator=(const SlurmExecutor&) = delete;
  ~SlurmExecutor() override;  // Stop()

  // Checks that SLURM_CONF, when set, names a file and that squeue answers
  // within 15 s (FailedPrecondition naming what it said otherwise);
  // pba-server calls it before it listens.
  Status Check();

  void Start() override;
  void Wake() override;
  Status Cancel(const std::string& id, v1::Job* job, bool* found) override;
  void Stop() override;

 private:
  struct Tracked;  // one job in Slurm's hands, defined in the .cc

  void Loop();
  // Takes over the jobs in Slurm's hands that the store names.
  void Reattach(const std::vector<SlurmJobState>& queue);
  // Hands QUEUED jobs to Slurm while there is room.
  void SubmitQueued();
  bool Submit(const v1::Job& job);
  // One squeue: each tracked job's new state, progress, end.
  bool Poll(std::vector<SlurmJobState>* queue);
  void Follow(Tracked& t, const SlurmJobState* seen);
  void ReadProgress(Tracked& t);
  // The unread rest of the run's progress file, for pba-solve's error only.
  void SkimProgress(Tracked& t);
  void Conclude(Tracked& t, const SlurmJobState* seen);
  // How a job gone from squeue ended, from Slurm's accounting; false when
  // the cluster keeps none (or none of it).
  bool Accounting(const std::string& slurm_id, SlurmJobState* state);
  bool StartRun(Tracked& t, const std::string& message);
  void FailQueued(const std::string& id, const std::string& error);
  Status Slurm(const std::string& program, const std::vector<std::string>& args,
               CommandResult* result);

  JobStore& store_;
  JobEventHub& hub_;
  const ExecutorOptions options_;
  const SlurmOptions slurm_;

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool started_ = false;
  bool woken_ = false;
  // PBA job id -> its Slurm job; only the loop's thread adds and removes,
  // Cancel marks under mutex_.
  std::map<std::string, std::unique_ptr<Tracked>> tracked_;
  std::thread loop_;
  // No submission before this (the loop's thread only): a pause after an
  // sbatch refusal that may pass later.
  std::chrono::steady_clock::time_point submit_after_{};
};

}  // namespace pba
