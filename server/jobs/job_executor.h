// JobExecutor: runs queued jobs, each in its own pba-solve child process, on
// `max_running` worker threads.
//
// A worker claims the oldest QUEUED job (RUNNING, attempts + 1), writes
// jobs/<id>/scene.json, runs `pba-solve scene.json --out result
// --progress=json`, turns its stdout lines into job events, and records the
// outcome: SUCCEEDED with summary and result files, FAILED with the reason, or
// CANCELLED. A job interrupted by Stop() goes back to QUEUED, so the next
// server start runs it again.
//
// Cancel and stop send SIGTERM to the child's process group; the worker sends
// SIGKILL when the child is still there after `kill_grace`. A job over its
// time limit is stopped the same way and FAILED, saying so; a job started
// more than `max_attempts` times (re-queued by restarts) is FAILED without
// running again.
//
// Before a claimed job is staged, `may_run` (when set) may refuse it: the
// job is FAILED with its reason and never runs.
//
// Jobs on the atlas store (a scene against a snapshot, an atlas import)
// need more than their scene: a JobPreparation stages their inputs before
// pba-solve runs and completes them after (an import's structures are
// committed then).
#pragma once

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "jobs/job_event_hub.h"
#include "pba/status.h"
#include "pba/v1/job.pb.h"
#include "store/job_store.h"

namespace pba {

// What the server adds around a job's pba-solve run.
class JobPreparation {
 public:
  virtual ~JobPreparation() = default;
  // Before pba-solve: writes what the job reads into its folder `dir` and
  // returns pba-solve's input arguments in *input (by default the scene
  // file, dir/scene.json, written from *scene after this returns; a
  // preparation may rewrite *scene, e.g. point its atlas at a staged
  // snapshot). An error FAILS the job with it.
  virtual Status Stage(const v1::Job& job, const std::filesystem::path& dir, v1::Scene* scene,
                       std::vector<std::string>* input) = 0;
  // After pba-solve succeeded, before the job is recorded SUCCEEDED: may
  // add to the outcome (e.g. the snapshot an import made). An error FAILS
  // the job with it.
  virtual Status Complete(const v1::Job& job, const std::filesystem::path& result_dir,
                          RunOutcome* outcome) = 0;
};

// The queue's runner as the job service sees it: the local one below runs
// pba-solve children on this machine; one that hands jobs to a cluster
// scheduler would implement the same four calls.
class Executor {
 public:
  virtual ~Executor() = default;
  virtual void Start() = 0;
  // A job was queued: let an idle worker take it now.
  virtual void Wake() = 0;
  // QUEUED -> CANCELLED at once; RUNNING -> stopped, then CANCELLED;
  // finished jobs are left alone. *job is the job after the call.
  virtual Status Cancel(const std::string& id, v1::Job* job, bool* found) = 0;
  // Stops taking jobs; running ones go back to the queue. Idempotent.
  virtual void Stop() = 0;
};

// pba-server's default wall-clock limit of a job (--max-job-time): a day,
// longer than any solve the examples or the benchmarks run, short enough
// that a job stuck in a loop frees its runner.
inline constexpr std::chrono::seconds kDefaultMaxJobTime{24 * 3600};

// pba-server's default address-space limit of each pba-solve
// (--solver-memory): three quarters of the physical memory shared among
// the `max_running` solves that may run at once, so that together they
// leave the server and the system a quarter; a solve past it fails with
// an out-of-memory error instead of pushing the machine into swap or the
// OOM killer. 0 when the physical memory cannot be read (no limit).
int64_t DefaultSolverMemoryBytes(int max_running);

struct ExecutorOptions {
  // Job folders are created in jobs_dir/<id>/; an empty jobs_dir is
  // data_dir/jobs (JobsDir).
  std::filesystem::path data_dir;
  std::filesystem::path jobs_dir;
  // The pba-solve executable.
  std::filesystem::path solver;
  int max_running = 1;
  // --threads passed to each pba-solve; 0 passes nothing (pba-solve decides).
  // A job on several MPI ranks passes each rank its share.
  int solver_threads = 0;
  // The mpirun a job with ranks > 1 runs under (mpirun -np N pba-solve ...);
  // empty: such a job fails saying the server has no MPI.
  std::filesystem::path mpirun;
  // The most ranks a job may run on (pba-server --max-ranks): a job queued
  // under a higher limit, before a restart, fails saying so.
  int max_ranks = 1;
  // --atlas-cache passed to each pba-solve (built atlas meshes shared
  // between jobs) with --atlas-cache-size [GiB]; empty passes nothing.
  std::filesystem::path atlas_cache_dir;
  double atlas_cache_gib = 2.0;
  // Time between SIGTERM and SIGKILL.
  std::chrono::milliseconds kill_grace{10000};
  // How often idle workers look at the queue without being woken (covers
  // jobs queued by anything that does not call Wake()).
  std::chrono::milliseconds idle_poll{1000};
  // The wall-clock limit of a job: a job's own timeout_s when it is
  // smaller; 0: none. The default (kDefaultMaxJobTime) keeps a runaway job
  // from holding a runner forever.
  std::chrono::seconds max_job_time{kDefaultMaxJobTime};
  // A job is started at most this many times (a start is an attempt; a
  // restart of the server re-queues the jobs it was running).
  int max_attempts = 3;
  // The address-space limit of each pba-solve [bytes]; 0: none.
  // pba-server's default is DefaultSolverMemoryBytes(max_running).
  int64_t max_solver_memory_bytes = 0;
  // A finished job's folder (result files, log) is removed this long after
  // it ended, at start and then hourly; the job stays listed, its files
  // listed no more and its `error` saying so. 0: kept forever.
  std::chrono::seconds keep_results{0};
  // Stages and completes jobs on the atlas store; nullptr: scenes only.
  JobPreparation* preparation = nullptr;
  // Asked about each job a worker claims, before anything is staged for it:
  // an error FAILS the job with that message instead of running it
  // (pba-server refuses the jobs of a user disabled while they waited in
  // the queue). Empty: every job runs.
  std::function<Status(const v1::Job& job)> may_run;
};

std::filesystem::path JobsDir(const ExecutorOptions& options);

class JobExecutor : public Executor {
 public:
  JobExecutor(JobStore& store, JobEventHub& hub, ExecutorOptions options);
  JobExecutor(const JobExecutor&) = delete;
  JobExecutor& operator=(const JobExecutor&) = delete;
  ~JobExecutor() override;  // Stop()

  void Start() override;
  void Wake() override;

  // QUEUED -> CANCELLED at once; RUNNING -> its child is signalled and the job
  // ends CANCELLED shortly after; finished jobs are left alone. *job is the
  // job after the call (a running one still shows RUNNING).
  Status Cancel(const std::string& id, v1::Job* job, bool* found) override;

  // Stops taking jobs, stops running children (their jobs are re-queued) and
  // joins the workers. Idempotent.
  void Stop() override;

 private:
  struct Run;     // one running job, defined in the .cc
  class Attempt;  // the steps of Execute(), defined in the .cc

  void WorkerLoop();
  // ExpireResults when the last run was an hour ago or more (any worker).
  void MaybeExpireResults();
  void Execute(const v1::Job& job, const v1::JobEvent& started, Run& run);

  JobStore& store_;
  JobEventHub& hub_;
  const ExecutorOptions options_;

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  bool started_ = false;
  std::map<std::string, std::shared_ptr<Run>> running_;
  std::vector<std::thread> workers_;
  std::chrono::steady_clock::time_point last_expiry_{};
  bool expired_once_ = false;
};

}  // namespace pba
