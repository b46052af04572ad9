#include "jobs/job_executor.h"

#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/time_util.h>
#include <signal.h>
#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <system_error>

#include "core/atomic_write.h"
#include "core/exit_codes.h"
#include "core/sha256.h"
#include "jobs/solver_process.h"
#include "pba/v1/solve_event.pb.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

using google::protobuf::util::TimeUtil;

// How long a worker waits for output before it looks at cancel/kill deadlines.
constexpr std::chrono::milliseconds kPollInterval{100};

constexpr char kRequeueShutdown[] = "re-queued: server shut down";
constexpr char kCancelledByRequest[] = "cancelled by request";

// The wall clock to the microsecond, as the store stamps the events it makes.
// (TimeUtil::GetCurrentTime() of protobuf 3.21 has whole seconds only, which
// put progress events up to a second before the events stored ahead of them.)
google::protobuf::Timestamp Now() {
  return TimeUtil::MicrosecondsToTimestamp(std::chrono::duration_cast<std::chrono::microseconds>(
                                               std::chrono::system_clock::now().time_since_epoch())
                                               .count());
}

void LogStateChange(const v1::JobEvent& event) {
  spdlog::info("job {} {}: {}", event.job_id(), v1::Job::State_Name(event.state()),
               event.message());
}

// Removes what an earlier attempt left: a complete result of a run whose end
// was never recorded, and pba-solve's hidden staging siblings (.result.*).
// pba-solve's --out is then always new (it replaces an earlier result only
// with --force, which the server never passes).
Status ClearFolder(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::Io("cannot create " + dir.string() + ": " + ec.message());
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name == "result" || name.rfind(".result.", 0) == 0) {
      std::error_code remove_ec;
      fs::remove_all(entry.path(), remove_ec);
      if (remove_ec) {
        return Status::Io("cannot remove " + entry.path().string() + ": " + remove_ec.message());
      }
    }
  }
  if (ec) return Status::Io("cannot list " + dir.string() + ": " + ec.message());
  return Status::Ok();
}

// pba-solve's hidden staging siblings of result/ (.result.partial-PID,
// .result.old-PID), left when a solve ends without its own cleanup: its
// cancel watchdog exits at once, even while the result is being written
// (pba_solve_main.cc), and a SIGKILL (past the grace, the time limit) or
// the address-space limit leaves no chance either. Called once pba-solve
// has exited.
void RemoveStagingLeftovers(const fs::path& dir) {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (entry.path().filename().string().rfind(".result.", 0) != 0) continue;
    std::error_code remove_ec;
    fs::remove_all(entry.path(), remove_ec);
    if (remove_ec) {
      spdlog::warn("cannot remove {}: {}", entry.path().string(), remove_ec.message());
    }
  }
}

// The job's folder, ready for pba-solve: inputs staged (by `preparation`,
// when there is one), scene.json written, the attempt noted in solve.log.
// *input: pba-solve's input arguments.
Status PrepareFolder(const v1::Job& job, const fs::path& dir, JobPreparation* preparation,
                     std::vector<std::string>* input) {
  PBA_RETURN_IF_ERROR(ClearFolder(dir));
  v1::Scene scene = job.scene();
  input->clear();
  if (preparation != nullptr) PBA_RETURN_IF_ERROR(preparation->Stage(job, dir, &scene, input));
  if (input->empty()) {
    std::string json;
    google::protobuf::util::JsonPrintOptions options;
    options.preserve_proto_field_names = true;
    options.add_whitespace = true;
    if (!google::protobuf::util::MessageToJsonString(scene, &json, options).ok()) {
      return Status::Internal("cannot write the scene as JSON");
    }
    PBA_RETURN_IF_ERROR(AtomicWriteText(dir / "scene.json", json));
    input->push_back((dir / "scene.json").string());
  }

  std::ofstream log(dir / "solve.log", std::ios::app);
  log << "=== attempt " << job.attempts() << ", " << TimeUtil::ToString(Now()) << " ===\n";
  return Status::Ok();
}

// summary.json and every file of a finished result folder.
Status CollectResult(const fs::path& dir, v1::Summary* summary,
                     std::vector<v1::ResultFile>* files) {
  std::ifstream in(dir / "summary.json");
  if (!in) return Status::Io("the result has no summary.json");
  std::stringstream json;
  json << in.rdbuf();
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;  // a newer pba-solve may say more
  const auto parsed = google::protobuf::util::JsonStringToMessage(json.str(), summary, options);
  if (!parsed.ok()) {
    return Status::Io("summary.json is not a pba.v1.Summary: " + std::string(parsed.message()));
  }
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    v1::ResultFile file;
    file.set_name(entry.path().filename().string());
    std::string sha256;
    int64_t size = 0;
    PBA_RETURN_IF_ERROR(FileSha256Hex(entry.path(), &sha256, &size));
    file.set_sha256(sha256);
    file.set_size_bytes(size);
    files->push_back(std::move(file));
  }
  if (ec) return Status::Io("cannot list " + dir.string() + ": " + ec.message());
  std::sort(files->begin(), files->end(),
            [](const v1::ResultFile& a, const v1::ResultFile& b) { return a.name() < b.name(); });
  return Status::Ok();
}

std::string FailureReason(const v1::SolveEvent* error, const ProcessExit& exit) {
  if (error != nullptr && !error->message().empty()) {
    // pba-solve's message is the whole status, its field first already.
    const std::string prefix = error->field() + ": ";
    return error->field().empty() || error->message().rfind(prefix, 0) == 0
               ? error->message()
               : prefix + error->message();
  }
  if (exit.signaled) {
    return "pba-solve was killed by signal " + std::to_string(exit.signal) + " (" +
           SignalName(exit.signal) + ")";
  }
  // Without an ERROR line (a bad command line, the cancel watchdog, a
  // crash) the code is all there is: its meaning from the shared table.
  const ExitCodeInfo* known = FindExitCode(exit.code);
  return "pba-solve exited with code " + std::to_string(exit.code) +
         (known != nullptr ? std::string(" (") + known->meaning + ")" : std::string());
}

}  // namespace

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
    v1::JobEvent event;
    bool cancelled = false;
    PBA_RETURN_IF_ERROR(store_.CancelQueued(id, "cancelled before it started", &event, &cancelled));
    if (cancelled) {
      hub_.Publish(event);
      LogStateChange(event);
    }
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
  const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  const int64_t cutoff =
      now_us - std::chrono::duration_cast<std::chrono::microseconds>(options_.keep_results).count();
  const double days = options_.keep_results.count() / 86400.0;
  char note[128];
  std::snprintf(note, sizeof note, "result files removed %.3g days after the job ended", days);
  std::vector<std::string> ids;
  const Status status = store_.ExpireResults(cutoff, note, &ids);
  if (!status.ok()) {
    spdlog::error("cannot expire old results: {}", status.ToString());
    return;
  }
  for (const std::string& id : ids) {
    std::error_code ec;
    fs::remove_all(options_.data_dir / "jobs" / id, ec);
    if (ec) spdlog::warn("cannot remove the folder of job {}: {}", id, ec.message());
  }
  if (!ids.empty()) spdlog::info("removed the result files of {} old job(s)", ids.size());
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
        dir_(options_.data_dir / "jobs" / id_),
        result_dir_(dir_ / "result"),
        sequence_(started.sequence()) {
    parse_options_.ignore_unknown_fields = true;
  }

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

  // pba-solve's command line; a job on several ranks runs it under
  // mpirun, each rank with its share of the threads and of the memory
  // limit (every rank inherits the limit, so each gets limit / ranks).
  SolverCommand Command(const std::vector<std::string>& input) const {
    SolverCommand command;
    const int ranks = std::max(1, job_.ranks());
    command.program = options_.solver;
    if (ranks > 1) {
      command.program = options_.mpirun;
      // Not bound to cores: jobs running side by side would each bind
      // their ranks to the first cores. Root needs saying so to Open MPI.
      command.args = {"-np", std::to_string(ranks), "--bind-to", "none"};
      if (::geteuid() == 0) command.args.push_back("--allow-run-as-root");
      command.args.push_back(options_.solver.string());
    }
    command.args.insert(command.args.end(), input.begin(), input.end());
    command.args.insert(command.args.end(), {"--out", result_dir_.string(), "--progress=json"});
    command.max_address_space_bytes = options_.max_solver_memory_bytes / ranks;
    if (options_.solver_threads > 0) {
      command.args.push_back("--threads");
      command.args.push_back(std::to_string(std::max(1, options_.solver_threads / ranks)));
    }
    if (!options_.atlas_cache_dir.empty()) {
      command.args.insert(command.args.end(),
                          {"--atlas-cache", options_.atlas_cache_dir.string(), "--atlas-cache-size",
                           fmt::format("{}", options_.atlas_cache_gib)});
    }
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
        HandleLine(line);
      } else if (read == SolverProcess::ReadResult::kEnd) {
        break;
      } else if (process.TryWait(&exit_)) {
        // Exited while something it started still holds stdout open: take what
        // is already there and stop reading.
        exited = true;
        while (process.ReadLine(&line, std::chrono::milliseconds(0)) ==
               SolverProcess::ReadResult::kLine) {
          HandleLine(line);
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

  // One stdout line: an ERROR event is kept for the failure reason, a
  // PROGRESS event is published (and stored when it moved far enough).
  void HandleLine(const std::string& line) {
    if (line.empty()) return;
    v1::SolveEvent solve_event;
    if (!google::protobuf::util::JsonStringToMessage(line, &solve_event, parse_options_).ok()) {
      spdlog::debug("job {}: ignoring a stdout line that is not a SolveEvent: {}", id_,
                    line.substr(0, 200));
      return;
    }
    if (solve_event.kind() == v1::SolveEvent::ERROR) {
      have_error_ = true;
      error_event_ = solve_event;
      return;
    }
    if (solve_event.kind() != v1::SolveEvent::PROGRESS) return;
    v1::JobEvent event;
    event.set_job_id(id_);
    event.set_sequence(++sequence_);
    *event.mutable_time() = Now();
    event.set_state(v1::Job::RUNNING);
    event.set_phase(solve_event.phase());
    event.set_progress(std::clamp(solve_event.progress(), 0.0, 1.0));
    event.set_message(solve_event.message());
    if (event.phase() != stored_phase_ ||
        event.progress() >= stored_progress_ + kStoredProgressStep) {
      const Status status = executor_.store_.RecordProgress(&event);
      if (status.ok()) {
        sequence_ = event.sequence();
        stored_phase_ = event.phase();
        stored_progress_ = event.progress();
      } else {
        spdlog::warn("job {}: cannot store progress: {}", id_, status.ToString());
      }
    }
    executor_.hub_.Publish(event);
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
    Fail(FailureReason(have_error_ ? &error_event_ : nullptr, exit_));
  }

  void Finish(RunOutcome outcome) {
    // Inputs staged for the run (a snapshot's structures, an import's
    // source) are copies of what the store keeps: not kept after it.
    for (const char* staged : {"snapshot", "source"}) {
      std::error_code ec;
      fs::remove_all(dir_ / staged, ec);
    }
    RemoveStagingLeftovers(dir_);
    if (outcome.message.empty()) {
      outcome.message = outcome.state == v1::Job::SUCCEEDED ? "succeeded" : outcome.error;
    }
    v1::JobEvent event;
    const Status status = executor_.store_.FinishRun(id_, sequence_ + 1, outcome, &event);
    if (!status.ok()) {
      spdlog::error("job {}: cannot record its end: {}", id_, status.ToString());
      return;
    }
    executor_.hub_.Publish(event);
    LogStateChange(event);
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
    v1::JobEvent event;
    const Status status = executor_.store_.RequeueRun(id_, sequence_ + 1, kRequeueShutdown, &event);
    if (!status.ok()) {
      spdlog::error("job {}: cannot re-queue: {}", id_, status.ToString());
      return;
    }
    executor_.hub_.Publish(event);
    LogStateChange(event);
  }

  JobExecutor& executor_;
  const ExecutorOptions& options_;
  const v1::Job& job_;
  Run& run_;
  const std::string& id_;
  const fs::path dir_;
  const fs::path result_dir_;
  // This worker numbers the job's events while it runs (see job_event_hub.h).
  int64_t sequence_;
  std::chrono::seconds limit_{0};
  std::chrono::steady_clock::time_point started_at_;
  bool timed_out_ = false;
  google::protobuf::util::JsonParseOptions parse_options_;
  std::string stored_phase_;
  double stored_progress_ = 0;
  bool have_error_ = false;
  v1::SolveEvent error_event_;
  ProcessExit exit_;
};

void JobExecutor::Execute(const v1::Job& job, const v1::JobEvent& started, Run& run) {
  Attempt(*this, job, started, run).Execute();
}

}  // namespace pba
