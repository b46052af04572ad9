#include "jobs/job_executor.h"

#include <signal.h>
#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <system_error>

#include "jobs/job_run.h"
#include "jobs/solver_process.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

// How long a worker waits for output before it looks at cancel/kill deadlines.
constexpr std::chrono::milliseconds kPollInterval{100};

constexpr char kRequeueShutdown[] = "re-queued: server shut down";
constexpr char kCancelledByRequest[] = "cancelled by request";

}  // namespace

fs::path JobsDir(const ExecutorOptions& options) {
  return options.jobs_dir.empty() ? options.data_dir / "jobs" : options.jobs_dir;
}

int64_t DefaultSolverMemoryBytes(int max_running) {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page_size <= 0) return 0;
  const int64_t physical = static_cast<int64_t>(pages) * page_size;
  return physical / 4 * 3 / std::max(1, max_running);
}

// Shared between the worker that runs a job and Cancel()/Stop(); every field
// is guarded by JobExecutor::mutex_.
struct JobExecutor::Run {
  SolverProcess* process = nullptr;  // while the child runs
  bool cancel_requested = false;
  bool stop_requested = false;
  bool term_sent = false;
  bool kill_sent = false;
  std::chrono::steady_clock::time_point kill_at;

  // SIGTERM now (if the child runs), SIGKILL later from the worker's loop.
  void Terminate(std::chrono::milliseconds grace) {
    if (process == nullptr || term_sent) return;
    process->Signal(SIGTERM);
    term_sent = true;
    kill_at = std::chrono::steady_clock::now() + grace;
  }
};

JobExecutor::JobExecutor(JobStore& store, JobEventHub& hub, ExecutorOptions options)
    : store_(store), hub_(hub), options_(std::move(options)) {}

JobExecutor::~JobExecutor() { Stop(); }

void JobExecutor::Start() {
  std::lock_guard lock(mutex_);
  if (started_ || stopping_) return;
  started_ = true;
  for (int i = 0; i < std::max(1, options_.max_running); ++i) {
    workers_.emplace_back([this] { WorkerLoop(); });
  }
}

void JobExecutor::Wake() {
  // Under the lock so a worker between "nothing queued" and waiting cannot
  // miss the notification.
  std::lock_guard lock(mutex_);
  wake_.notify_one();
}

Status JobExecutor::Cancel(const std::string& id, v1::Job* job, bool* found) {
  std::unique_lock lock(mutex_);
  // Workers claim jobs under mutex_, so a job is either in running_ or (if
  // RUNNING in the store) finishing right now; QUEUED ones cannot be claimed
  // while we cancel.
  if (auto it = running_.find(id); it != running_.end()) {
    Run& run = *it->second;
    if (!run.cancel_requested) spdlog::info("job {} cancel requested: stopping pba-solve", id);
    run.cancel_requested = true;
    run.Terminate(options_.kill_grace);
  } else {
    PBA_RETURN_IF_ERROR(
        EndQueuedJob(store_, hub_, id, v1::Job::CANCELLED, "cancelled before it started"));
  }
  lock.unlock();
  return store_.GetJob(id, JobView::kFull, job, found);
}

void JobExecutor::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    for (auto& [id, run] : running_) {
      run->stop_requested = true;
      run->Terminate(options_.kill_grace);
    }
  }
  wake_.notify_all();
  for (std::thread& worker : workers_) {
    if (worker.joinable()) worker.join();
  }
  workers_.clear();
}

void JobExecutor::MaybeExpireResults() {
  if (options_.keep_results.count() <= 0) return;
  {
    std::lock_guard lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    if (expired_once_ && now - last_expiry_ < std::chrono::hours(1)) return;
    expired_once_ = true;
    last_expiry_ = now;
  }
  ExpireResults(store_, JobsDir(options_), options_.keep_results);
}

void JobExecutor::WorkerLoop() {
  while (true) {
    MaybeExpireResults();
    v1::Job job;
    v1::JobEvent started;
    std::shared_ptr<Run> run;
    {
      std::unique_lock lock(mutex_);
      if (stopping_) return;
      bool claimed = false;
      const Status status = store_.ClaimNextQueued(&job, &started, &claimed);
      if (!status.ok()) spdlog::error("cannot take a job from the queue: {}", status.ToString());
      if (!claimed) {
        wake_.wait_for(lock, options_.idle_poll);
        continue;
      }
      run = std::make_shared<Run>();
      running_[job.id()] = run;
    }
    hub_.Publish(started);
    LogStateChange(started);
    Execute(job, started, *run);
    std::lock_guard lock(mutex_);
    running_.erase(job.id());
  }
}

// One attempt at a job, run by a worker: the steps of Execute() and what they
// share. Lives on the worker's stack for the length of the run.
class JobExecutor::Attempt {
 public:
  Attempt(JobExecutor& executor, const v1::Job& job, const v1::JobEvent& started, Run& run)
      : executor_(executor),
        options_(executor.options_),
        job_(job),
        run_(run),
        id_(job.id()),
        dir_(JobsDir(options_) / id_),
        result_dir_(dir_ / "result"),
        progress_(executor.store_, executor.hub_, job.id(), started.sequence()) {}

  // Prepare the folder, start pba-solve, follow it, then collect and record
  // the outcome. Every step that ends the job records how it ended.
  void Execute() {
    std::vector<std::string> input;
    if (!Prepare(&input)) return;
    SolverProcess process;
    if (!Start(input, process)) return;
    Follow(process);
    Conclude();
  }

 private:
  // Refuses a job started too often or refused by may_run, then prepares its
  // folder; false when the job was failed instead. *input: pba-solve's input
  // arguments.
  bool Prepare(std::vector<std::string>* input) {
    if (job_.attempts() > options_.max_attempts) {
      Fail("started " + std::to_string(job_.attempts() - 1) +
           " times without finishing (the server stopped during each run); not started "
           "again");
      return false;
    }
    if (options_.may_run) {
      if (const Status allowed = options_.may_run(job_); !allowed.ok()) {
        Fail(allowed.ToString());
        return false;
      }
    }
    const Status prepared = PrepareFolder(job_, dir_, options_.preparation, input);
    if (!prepared.ok()) {
      Fail(prepared.code() == Status::Code::kIo || prepared.code() == Status::Code::kInternal
               ? "cannot prepare the job folder: " + prepared.ToString()
               : prepared.ToString());
      return false;
    }
    return true;
  }

  // pba-solve's command line (SolverCommandLine), its stderr to solve.log.
  SolverCommand Command(const std::vector<std::string>& input) const {
    std::vector<std::string> line = SolverCommandLine(options_, job_, input, result_dir_);
    SolverCommand command;
    command.program = line.front();
    command.args.assign(line.begin() + 1, line.end());
    command.max_address_space_bytes = SolverMemoryPerRank(options_, job_);
    command.stderr_log = dir_ / "solve.log";
    return command;
  }

  // Starts pba-solve unless the job was cancelled or the server is stopping;
  // false when the job ended (or was re-queued) instead.
  bool Start(const std::vector<std::string>& input, SolverProcess& process) {
    if (job_.ranks() > 1 && options_.mpirun.empty()) {
      Fail(fmt::format("the job asks for {} MPI ranks, but this server runs no MPI (no mpirun)",
                       job_.ranks()));
      return false;
    }
    if (job_.ranks() > options_.max_ranks) {
      Fail(fmt::format("the job asks for {} MPI ranks; this server allows {} (--max-ranks)",
                       job_.ranks(), options_.max_ranks));
      return false;
    }
    const SolverCommand command = Command(input);
    {
      std::lock_guard lock(executor_.mutex_);
      if (run_.cancel_requested) {
        FinishCancelled();
        return false;
      }
      if (run_.stop_requested) {
        Requeue();
        return false;
      }
    }
    const Status spawned = process.Start(command);
    if (!spawned.ok()) {
      Fail(spawned.ToString());
      return false;
    }
    std::lock_guard lock(executor_.mutex_);
    run_.process = &process;
    if (run_.cancel_requested || run_.stop_requested) run_.Terminate(options_.kill_grace);
    return true;
  }

  // Turns pba-solve's stdout into job events until it has exited (exit_),
  // stopping it when it runs past its time limit or ignores SIGTERM.
  void Follow(SolverProcess& process) {
    // The job's time limit: its own when smaller than the server's.
    limit_ = options_.max_job_time;
    if (job_.timeout_s() > 0 && (limit_.count() == 0 || job_.timeout_s() < limit_.count())) {
      limit_ = std::chrono::seconds(job_.timeout_s());
    }
    started_at_ = std::chrono::steady_clock::now();
    bool exited = false;
    std::string line;
    while (true) {
      const SolverProcess::ReadResult read = process.ReadLine(&line, kPollInterval);
      if (read == SolverProcess::ReadResult::kLine) {
        progress_.Handle(line);
      } else if (read == SolverProcess::ReadResult::kEnd) {
        break;
      } else if (process.TryWait(&exit_)) {
        // Exited while something it started still holds stdout open: take what
        // is already there and stop reading.
        exited = true;
        while (process.ReadLine(&line, std::chrono::milliseconds(0)) ==
               SolverProcess::ReadResult::kLine) {
          progress_.Handle(line);
        }
        break;
      }
      Escalate(process);
    }
    while (!exited && !process.TryWait(&exit_)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      Escalate(process);
    }
  }

  // SIGTERM past the time limit, SIGKILL past the grace after a SIGTERM.
  void Escalate(SolverProcess& process) {
    std::lock_guard lock(executor_.mutex_);
    if (limit_.count() > 0 && !timed_out_ &&
        std::chrono::steady_clock::now() - started_at_ > limit_) {
      spdlog::warn("job {}: over its time limit of {} s; stopping pba-solve", id_, limit_.count());
      timed_out_ = true;
      run_.Terminate(options_.kill_grace);
    }
    if (run_.term_sent && !run_.kill_sent && std::chrono::steady_clock::now() >= run_.kill_at) {
      spdlog::warn("job {}: pba-solve ignored SIGTERM for {} ms; sending SIGKILL", id_,
                   options_.kill_grace.count());
      process.Signal(SIGKILL);
      run_.kill_sent = true;
    }
  }

  // pba-solve has exited: collects a success's result, or records why the
  // run ended otherwise (cancelled, timed out, server stopping, failed).
  void Conclude() {
    bool cancel_requested = false;
    bool stop_requested = false;
    {
      std::lock_guard lock(executor_.mutex_);
      run_.process = nullptr;
      cancel_requested = run_.cancel_requested;
      stop_requested = run_.stop_requested;
    }

    if (cancel_requested) return FinishCancelled();
    if (!exit_.signaled && exit_.code == 0) {
      RunOutcome outcome;
      const Status collected = CollectResult(result_dir_, &outcome.summary, &outcome.files);
      if (!collected.ok()) return Fail("pba-solve succeeded but " + collected.ToString());
      if (options_.preparation != nullptr) {
        const Status completed = options_.preparation->Complete(job_, result_dir_, &outcome);
        if (!completed.ok()) return Fail(completed.ToString());
      }
      outcome.state = v1::Job::SUCCEEDED;
      return Finish(std::move(outcome));
    }
    if (timed_out_) {
      std::error_code ec;
      fs::remove_all(result_dir_, ec);
      return Fail("stopped after its time limit of " + std::to_string(limit_.count()) + " s");
    }
    if (stop_requested) return Requeue();
    Fail(FailureReason(progress_.error(), exit_));
  }

  void Finish(RunOutcome outcome) {
    RecordRunEnd(executor_.store_, executor_.hub_, dir_, id_, progress_.sequence(),
                 std::move(outcome));
  }

  void Fail(const std::string& error) {
    RunOutcome outcome;
    outcome.state = v1::Job::FAILED;
    outcome.error = error;
    Finish(std::move(outcome));
  }

  void FinishCancelled() {
    std::error_code ec;
    fs::remove_all(result_dir_, ec);
    RunOutcome outcome;
    outcome.state = v1::Job::CANCELLED;
    outcome.error = kCancelledByRequest;
    Finish(std::move(outcome));
  }

  void Requeue() {
    RecordRequeue(executor_.store_, executor_.hub_, id_, progress_.sequence(), kRequeueShutdown);
  }

  JobExecutor& executor_;
  const ExecutorOptions& options_;
  const v1::Job& job_;
  Run& run_;
  const std::string& id_;
  const fs::path dir_;
  const fs::path result_dir_;
  // This worker numbers the job's events while it runs (see job_event_hub.h).
  ProgressLines progress_;
  std::chrono::seconds limit_{0};
  std::chrono::steady_clock::time_point started_at_;
  bool timed_out_ = false;
  ProcessExit exit_;
};

void JobExecutor::Execute(const v1::Job& job, const v1::JobEvent& started, Run& run) {
  Attempt(*this, job, started, run).Execute();
}

}  // namespace pba
