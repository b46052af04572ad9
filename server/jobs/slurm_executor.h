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
  // Jobs with the same limits handed to Slurm in one round go as one job
  // array (up to kSlurmArrayMax tasks each) when there are at least this
  // many, as Slurm users submit a sweep; 0: each its own Slurm job.
  int array_min = 10;
  // How often squeue is asked.
  std::chrono::milliseconds poll{2000};
  // Where sbatch, squeue and scancel are (empty: on PATH), and the
  // environment they get (e.g. SLURM_CONF=...).
  std::filesystem::path bin_dir;
  std::vector<std::string> env;
  // Time limit of each Slurm command.
  std::chrono::milliseconds command_timeout{60000};
};

// The most tasks in one job array (Slurm's default MaxArraySize allows
// task ids up to 1000).
inline constexpr int kSlurmArrayMax = 1000;

// A Slurm job as squeue shows it (a task of a job array: id
// "<array job id>_<task id>").
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
// name, limits and script; or of a job array of `array_tasks` tasks, each
// running in entry <task id> of `dir`, a link to its job's folder.
struct SlurmSubmission {
  std::string job_id;  // PBA's; of an array, its name in the jobs folder's arrays/
  std::filesystem::path dir, script;
  int array_tasks = 0;  // 0: one job
  int ranks = 1;
  int cpus_per_task = 1;
  int64_t time_limit_s = 0;  // 0: the partition's
  int64_t memory_bytes = 0;  // 0: the partition's default
};
std::vector<std::string> SbatchArguments(const SlurmOptions& options, const SlurmSubmission& s);

// The batch script: runs `command` (the program first; an argument
// "@PBA_RUN_RESULT@" becomes result-<run>) in the job's folder, under an
// address-space limit when `memory_bytes` > 0, and writes its exit code to
// exit_code-<run> (through a temporary file: the file is there whole or not
// at all), where <run> is $PBA_RUN_ID, or $SLURM_JOB_ID without it. Each
// argument single-quoted for the shell.
std::string SlurmBatchScript(const std::vector<std::string>& command, int64_t memory_bytes);

// A job array's script: task N goes into the array folder's entry N (its
// job's folder) and runs that job's batch script (`job_script`, its name)
// with PBA_RUN_ID=<array job id>_<N>.
std::string SlurmArrayScript(const std::string& job_script);

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
  struct Prepared;  // a job whose folder and script are ready, defined in the .cc

  // Hands QUEUED jobs to Slurm while there is room: those with the same
  // limits as one job array when there are array_min or more.
  void SubmitQueued();
  // The job's folder and batch script; false when the job failed instead.
  bool Prepare(const v1::Job& job, Prepared* prepared);
  // sbatch for one job, or for an array of them; false (the jobs back in
  // the queue, submissions paused) when Slurm may take them later.
  bool SubmitOne(Prepared& p);
  bool SubmitArray(std::vector<Prepared>& members);
  // sbatch with p's limits; kLater also pauses submissions. `said`: what
  // sbatch said when it did not take the job.
  enum class Sbatched { kSubmitted, kLater, kRefused };
  Sbatched Sbatch(const Prepared& p, SlurmSubmission submission, std::string* slurm_id,
                  std::string* said);
  // Puts a claimed job back in PBA's queue.
  void Release(const std::string& id);
  // Records the Slurm job of a submitted job and follows it.
  void Track(Prepared& p, const std::string& slurm_id, const std::string& message);
  // The task of a job array that a job claimed before a crash became, if
  // the array's list names it (nullptr: none).
  const SlurmJobState* FindInArrays(const std::vector<SlurmJobState>& queue, const std::string& id);
  // Array folders none of whose jobs is followed any more.
  void ExpireArrays();
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
