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
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "jobs/command.h"
#include "jobs/job_executor.h"
#include "jobs/slurm_commands.h"

namespace pba {

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
  // Whether submits are still coming (SlurmOptions::gather), and for how
  // much longer; false ends the gathering. Under mutex_.
  bool Gathering(std::chrono::steady_clock::time_point now,
                 std::chrono::steady_clock::duration* left);
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
  // Whether a job that ended may be judged now: false while Slurm says it
  // completed but its exit code or a file its SHA256SUMS names is not
  // here yet, for up to SlurmOptions::settle.
  bool Settled(Tracked& t, const SlurmJobState* seen, std::optional<int> code,
               const std::filesystem::path& run_result);
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
  // The first and the last Wake() since the last round (under mutex_;
  // zero: none).
  std::chrono::steady_clock::time_point first_wake_{}, last_wake_{};
  // squeue at once (a job was cancelled), under mutex_.
  bool poll_now_ = false;
  // PBA job id -> its Slurm job; only the loop's thread adds and removes,
  // Cancel marks under mutex_.
  std::map<std::string, std::unique_ptr<Tracked>> tracked_;
  std::thread loop_;
  // No submission before this (the loop's thread only): a pause after an
  // sbatch refusal that may pass later.
  std::chrono::steady_clock::time_point submit_after_{};
};

}  // namespace pba
