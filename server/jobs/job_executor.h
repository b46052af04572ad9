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
// SIGKILL when the child is still there after `kill_grace`.
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

#include "jobs/job_event_hub.h"
#include "pba/status.h"
#include "pba/v1/job.pb.h"
#include "store/job_store.h"

namespace pba {

struct ExecutorOptions {
  // Job folders are created in data_dir/jobs/<id>/.
  std::filesystem::path data_dir;
  // The pba-solve executable.
  std::filesystem::path solver;
  int max_running = 1;
  // --threads passed to each pba-solve; 0 passes nothing (pba-solve decides).
  int solver_threads = 0;
  // --atlas-cache passed to each pba-solve (built atlas meshes shared
  // between jobs) with --atlas-cache-size [GiB]; empty passes nothing.
  std::filesystem::path atlas_cache_dir;
  double atlas_cache_gib = 2.0;
  // Time between SIGTERM and SIGKILL.
  std::chrono::milliseconds kill_grace{10000};
  // How often idle workers look at the queue without being woken (covers
  // jobs queued by anything that does not call Wake()).
  std::chrono::milliseconds idle_poll{1000};
};

class JobExecutor {
 public:
  // Progress is stored when the phase changes or it grew by this much.
  static constexpr double kStoredProgressStep = 0.05;

  JobExecutor(JobStore& store, JobEventHub& hub, ExecutorOptions options);
  JobExecutor(const JobExecutor&) = delete;
  JobExecutor& operator=(const JobExecutor&) = delete;
  ~JobExecutor();  // Stop()

  void Start();
  // A job was queued: let an idle worker take it now.
  void Wake();

  // QUEUED -> CANCELLED at once; RUNNING -> its child is signalled and the job
  // ends CANCELLED shortly after; finished jobs are left alone. *job is the
  // job after the call (a running one still shows RUNNING).
  Status Cancel(const std::string& id, v1::Job* job, bool* found);

  // Stops taking jobs, stops running children (their jobs are re-queued) and
  // joins the workers. Idempotent.
  void Stop();

 private:
  struct Run;  // one running job, defined in the .cc

  void WorkerLoop();
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
};

}  // namespace pba
