#include "jobs/slurm_executor.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <system_error>

#include "core/atomic_write.h"
#include "core/checksum_file.h"
#include "jobs/job_run.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr char kSystem[] = "slurm";
constexpr char kSubmitting[] = "submitting";
constexpr char kCancelledByRequest[] = "cancelled by request";
// The batch script, in the job's folder. What each run writes there is
// named by its Slurm job id (a run Slurm lost track of on a failed node
// may still be writing its own while the next one runs): its progress
// lines, its exit code, and its result, renamed to result/ when it is the
// one that succeeded.
constexpr char kScript[] = "job.sh";
// Job arrays: one folder each under the jobs folder's arrays/, holding the
// array's script, the list of its jobs (task N the N-th line) and entry N,
// a link to task N's job folder.
constexpr char kArrays[] = "arrays";
constexpr char kArrayScript[] = "array.sh";
constexpr char kArrayJobs[] = "jobs";
// An array folder none of whose jobs is followed is removed after this.
constexpr std::chrono::minutes kArrayKeep{10};
// A line of an array's jobs file: a job id (PBA's are a dozen characters).
constexpr std::size_t kMaxIdLine = 256;
std::string ExitCodeFile(const std::string& slurm_id) { return "exit_code-" + slurm_id; }
std::string ResultDir(const std::string& slurm_id) { return "result-" + slurm_id; }
// The most of progress.jsonl read in one round.
constexpr std::uintmax_t kMaxProgressRead = std::uintmax_t{4} << 20;
// Rounds a job may be missing from squeue before it counts as gone (it is
// listed from the moment sbatch answers; one missing round can be a
// controller between states).
constexpr int kMissingRounds = 2;
// The pause after an sbatch refusal that may pass later.
constexpr std::chrono::seconds kSubmitPause{30};
// How long the start-up check waits for squeue.
constexpr std::chrono::milliseconds kCheckTimeout{15000};

// A job's wall-clock limit [s]: its own when smaller than the server's; 0:
// none.
int64_t TimeLimit(const ExecutorOptions& options, const v1::Job& job) {
  int64_t limit = options.max_job_time.count();
  if (job.timeout_s() > 0 && (limit == 0 || job.timeout_s() < limit)) limit = job.timeout_s();
  return limit;
}

// The exit code the batch script wrote, if it got that far.
std::optional<int> ReadExitCode(const fs::path& dir, const std::string& slurm_id) {
  std::ifstream in(dir / ExitCodeFile(slurm_id));
  int code = 0;
  if (in >> code) return code;
  return std::nullopt;
}

// "Slurm job 123" with what Slurm said of it: "(TIMEOUT, reason X, on n1)".
std::string SlurmSaid(const std::string& slurm_id, const SlurmJobState* seen) {
  std::string text = "Slurm job " + slurm_id;
  if (seen == nullptr) return text;
  text += " (" + seen->state;
  if (!seen->reason.empty() && seen->reason != "None") text += ", reason " + seen->reason;
  if (!seen->node.empty() && seen->node != "(null)") text += ", on " + seen->node;
  return text + ")";
}

// An sbatch refusal that may pass later: the controller out of reach or
// busy, or a limit on the jobs a user may have submitted at once (the
// site's MaxSubmitJobs: a job of PBA's queue waits for room there).
bool SbatchMayAnswerLater(const std::string& said) {
  for (const char* words : {"Unable to contact", "Socket timed out", "Resource temporarily",
                            "MaxSubmitJob", "Slurm temporarily unable"}) {
    if (said.find(words) != std::string::npos) return true;
  }
  return false;
}

// Whether the file says `words` past `offset` (at most its last 64 KiB).
bool LogSays(const fs::path& path, std::uintmax_t offset, const std::string& words) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff from = std::max<std::streamoff>(
      static_cast<std::streamoff>(offset), std::max<std::streamoff>(0, size - (64 << 10)));
  if (from >= size) return false;
  in.seekg(from);
  std::string tail(static_cast<std::size_t>(size - from), '\0');
  in.read(tail.data(), static_cast<std::streamsize>(tail.size()));
  return tail.find(words) != std::string::npos;
}

// What earlier runs wrote in the job's folder `dir` (their progress, exit
// codes, results and pba-solve's staging siblings of those).
void RemoveRunFiles(const fs::path& dir) {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    for (const char* prefix : {"progress-", "exit_code-", "result-", ".result-"}) {
      if (name.rfind(prefix, 0) == 0) {
        std::error_code remove_ec;
        fs::remove_all(entry.path(), remove_ec);
        break;
      }
    }
  }
}

}  // namespace

// One job in Slurm's hands. Only the loop's thread touches it, but for
// cancel_requested (under SlurmExecutor::mutex_).
struct SlurmExecutor::Tracked {
  v1::Job job;  // as claimed or re-attached (kFull)
  std::string slurm_id;
  fs::path dir;
  std::unique_ptr<ProgressLines> progress;
  std::uintmax_t offset = 0;  // of progress.jsonl read so far
  std::string partial;        // its incomplete last line
  SlurmJobState last;         // what Slurm said when last recorded
  bool running = false;       // the PBA job is RUNNING
  bool cancel_requested = false;
  int missing = 0;                // rounds in a row it was not in squeue
  int64_t limit_s = 0;            // the time limit it was submitted with
  std::uintmax_t log_offset = 0;  // solve.log's size when it was submitted
  // When Slurm's completion was first seen while its exit code or result
  // was not whole here (SlurmOptions::settle).
  std::optional<std::chrono::steady_clock::time_point> settling_since;
};

SlurmExecutor::SlurmExecutor(JobStore& store, JobEventHub& hub, ExecutorOptions options,
                             SlurmOptions slurm)
    : store_(store), hub_(hub), options_(std::move(options)), slurm_(std::move(slurm)) {}

SlurmExecutor::~SlurmExecutor() { Stop(); }

Status SlurmExecutor::Slurm(const std::string& program, const std::vector<std::string>& args,
                            CommandResult* result) {
  std::vector<std::string> argv = {slurm_.bin_dir.empty() ? program
                                                          : (slurm_.bin_dir / program).string()};
  argv.insert(argv.end(), args.begin(), args.end());
  CommandOptions command;
  command.timeout = slurm_.command_timeout;
  command.env = slurm_.env;
  return RunCommand(argv, command, result);
}

Status SlurmExecutor::Check() {
  // Slurm's commands retry a configuration they cannot read for a minute:
  // a SLURM_CONF naming nothing is said at once.
  std::string conf;
  if (const char* from_env = std::getenv("SLURM_CONF")) conf = from_env;
  for (const std::string& e : slurm_.env) {
    if (e.rfind("SLURM_CONF=", 0) == 0) conf = e.substr(11);
  }
  std::error_code ec;
  if (!conf.empty() && !fs::is_regular_file(conf, ec)) {
    return Status::FailedPrecondition("--executor slurm: SLURM_CONF names " + conf +
                                      ", which is not a file");
  }
  CommandResult r;
  std::vector<std::string> argv = {
      slurm_.bin_dir.empty() ? "squeue" : (slurm_.bin_dir / "squeue").string(), "--noheader",
      "--me", "--format=%i"};
  CommandOptions command;
  command.timeout = std::min(slurm_.command_timeout, kCheckTimeout);
  command.env = slurm_.env;
  const Status run = RunCommand(argv, command, &r);
  if (!run.ok()) {
    return Status::FailedPrecondition("--executor slurm: " + run.message() +
                                      " (is Slurm's client installed, and on PATH?)");
  }
  if (!r.ok()) {
    return Status::FailedPrecondition("--executor slurm: squeue failed, " + r.Describe() +
                                      " (is slurmctld running, and SLURM_CONF right?)");
  }
  return Status::Ok();
}

void SlurmExecutor::Start() {
  std::lock_guard lock(mutex_);
  if (started_ || stopping_) return;
  started_ = true;
  loop_ = std::thread([this] { Loop(); });
}

void SlurmExecutor::Wake() {
  std::lock_guard lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (first_wake_ == std::chrono::steady_clock::time_point{}) first_wake_ = now;
  last_wake_ = now;
  woken_ = true;
  wake_.notify_one();
}

bool SlurmExecutor::Gathering(std::chrono::steady_clock::time_point now,
                              std::chrono::steady_clock::duration* left) {
  *left = GatherLeft(first_wake_, last_wake_, now, slurm_.gather);
  if (*left > std::chrono::steady_clock::duration::zero()) return true;
  first_wake_ = last_wake_ = {};
  return false;
}

void SlurmExecutor::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (loop_.joinable()) loop_.join();
}

Status SlurmExecutor::Cancel(const std::string& id, v1::Job* job, bool* found) {
  std::string slurm_id;
  bool tracked = false;
  {
    std::lock_guard lock(mutex_);
    if (auto it = tracked_.find(id); it != tracked_.end()) {
      tracked = true;
      it->second->cancel_requested = true;
      slurm_id = it->second->slurm_id;
    }
  }
  if (tracked) {
    // Ended when Slurm says the job has ended (the loop records it).
    CommandResult r;
    const Status run = Slurm("scancel", {slurm_id}, &r);
    if (!run.ok() || !r.ok()) {
      spdlog::warn("job {}: scancel {} failed: {}", id, slurm_id,
                   run.ok() ? r.Describe() : run.ToString());
    } else {
      spdlog::info("job {} cancel requested: scancel {}", id, slurm_id);
    }
    std::lock_guard lock(mutex_);
    poll_now_ = woken_ = true;
    wake_.notify_one();
  } else {
    // Not in Slurm's hands (yet): a QUEUED job ends here. One being
    // submitted right now is cancelled in Slurm by Submit, which finds it
    // ended when it records its Slurm job.
    PBA_RETURN_IF_ERROR(
        EndQueuedJob(store_, hub_, id, v1::Job::CANCELLED, "cancelled before it started"));
  }
  return store_.GetJob(id, JobView::kFull, job, found);
}

void SlurmExecutor::Loop() {
  using Clock = std::chrono::steady_clock;
  bool reattached = false;
  Clock::time_point last_expiry{}, last_poll{};
  while (true) {
    bool poll_now = false;
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
      poll_now = poll_now_;
      poll_now_ = false;
    }
    // squeue every `poll` (sooner after a cancel), not at every submit.
    std::vector<SlurmJobState> queue;
    const bool due = poll_now || !reattached || Clock::now() - last_poll >= slurm_.poll;
    if (due) last_poll = Clock::now();
    if (due && Poll(&queue)) {
      if (!reattached) {
        Reattach(queue);
        reattached = true;
      }
      std::map<std::string, const SlurmJobState*> by_id;
      for (const SlurmJobState& s : queue) by_id[s.id] = &s;
      std::vector<std::string> ids;
      for (const auto& [id, t] : tracked_) ids.push_back(id);
      for (const std::string& id : ids) {
        Tracked& t = *tracked_.at(id);
        const auto seen = by_id.find(t.slurm_id);
        Follow(t, seen == by_id.end() ? nullptr : seen->second);
      }
    }
    // Nothing is submitted before the jobs Slurm already has are known: a
    // job claimed by a server that died before it named its Slurm job would
    // run twice. Nor while submits are still coming (SlurmOptions::gather).
    Clock::duration gather_left{};
    bool gathering = false;
    {
      std::lock_guard lock(mutex_);
      gathering = Gathering(Clock::now(), &gather_left);
    }
    if (reattached && !gathering) SubmitQueued();
    const auto now = Clock::now();
    if (now - last_expiry >= std::chrono::hours(1)) {
      last_expiry = now;
      ExpireResults(store_, JobsDir(options_), options_.keep_results);
      // (Only once the jobs in Slurm's hands are known: an array's tasks
      // still pending need its folder.)
      if (reattached) ExpireArrays();
    }
    Clock::time_point until = last_poll + slurm_.poll;
    if (gathering) until = std::min(until, now + gather_left);
    std::unique_lock lock(mutex_);
    wake_.wait_until(lock, until, [this] { return stopping_ || woken_; });
    woken_ = false;
  }
}

bool SlurmExecutor::Poll(std::vector<SlurmJobState>* queue) {
  CommandResult r;
  const Status run = Slurm(
      "squeue", {"--noheader", "--me", "--states=all", "--array", "--format=%i|%j|%T|%r|%N"}, &r);
  if (!run.ok() || !r.ok()) {
    // slurmctld down or restarting: nothing is concluded from silence.
    spdlog::warn("squeue failed ({}); trying again in {} ms",
                 run.ok() ? r.Describe() : run.ToString(), slurm_.poll.count());
    return false;
  }
  *queue = ParseSqueue(r.out);
  return true;
}

void SlurmExecutor::Reattach(const std::vector<SlurmJobState>& queue) {
  std::vector<v1::Job> jobs;
  if (const Status listed = store_.ListScheduled(&jobs); !listed.ok()) {
    spdlog::error("cannot list the jobs in Slurm's hands: {}", listed.ToString());
    return;
  }
  for (v1::Job& job : jobs) {
    const std::string& id = job.id();
    std::string slurm_id = job.scheduler().job_id();
    if (slurm_id == kSubmitting) {
      // Claimed by a server that stopped before it named the Slurm job: the
      // job's name finds it, if sbatch took it.
      const auto by_name = std::find_if(queue.begin(), queue.end(), [&](const SlurmJobState& s) {
        return s.name == SlurmJobName(id) && ClassifySlurmState(s.state) == SlurmEnd::kNotEnded;
      });
      const SlurmJobState* named = by_name != queue.end() ? &*by_name : FindInArrays(queue, id);
      if (named == nullptr) {
        Release(id);
        continue;
      }
      slurm_id = named->id;
      v1::SchedulerJob scheduler;
      scheduler.set_system(kSystem);
      scheduler.set_job_id(slurm_id);
      scheduler.set_state(named->state);
      v1::JobEvent event;
      if (store_.RecordSchedulerJob(id, scheduler, "found as Slurm job " + slurm_id, &event).ok()) {
        hub_.Publish(event);
      }
    }
    auto t = std::make_unique<Tracked>();
    t->slurm_id = slurm_id;
    t->dir = JobsDir(options_) / id;
    t->running = job.state() == v1::Job::RUNNING;
    t->limit_s = TimeLimit(options_, job);
    t->last.state = job.scheduler().state();
    t->last.reason = job.scheduler().reason();
    t->last.node = job.scheduler().node();
    std::vector<v1::JobEvent> events;
    int64_t sequence = 0;
    if (store_.ListEvents(id, 0, &events).ok() && !events.empty())
      sequence = events.back().sequence();
    t->progress = std::make_unique<ProgressLines>(store_, hub_, id, sequence);
    // What it wrote while nobody followed: only its error matters now.
    SkimProgress(*t);
    t->job = std::move(job);
    spdlog::info("job {}: following Slurm job {} again ({})", id, slurm_id,
                 v1::Job::State_Name(t->job.state()));
    std::lock_guard lock(mutex_);
    tracked_[id] = std::move(t);
  }
}

struct SlurmExecutor::Prepared {
  v1::Job job;
  fs::path dir;
  int ranks = 1;
  int64_t limit_s = 0, memory_bytes = 0;
  std::uintmax_t log_offset = 0;  // solve.log's size before the run
};

void SlurmExecutor::SubmitQueued() {
  if (std::chrono::steady_clock::now() < submit_after_) return;
  // What the queue holds now, while there is room, prepared.
  std::vector<Prepared> ready;
  while (true) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_ || static_cast<int>(tracked_.size() + ready.size()) >= slurm_.max_submitted)
        break;
    }
    v1::Job job;
    bool claimed = false;
    const Status status = store_.ClaimForScheduler(&job, &claimed);
    if (!status.ok()) {
      spdlog::error("cannot take a job from the queue: {}", status.ToString());
      break;
    }
    if (!claimed) break;
    Prepared p;
    if (Prepare(job, &p)) ready.push_back(std::move(p));
  }
  // Jobs with the same limits, in the order they were queued: one array
  // when there are enough of them.
  std::vector<std::vector<Prepared>> groups;
  for (Prepared& p : ready) {
    const auto same = std::find_if(groups.begin(), groups.end(), [&](const auto& g) {
      return g[0].ranks == p.ranks && g[0].limit_s == p.limit_s &&
             g[0].memory_bytes == p.memory_bytes;
    });
    if (same == groups.end()) {
      groups.emplace_back().push_back(std::move(p));
    } else {
      same->push_back(std::move(p));
    }
  }
  bool paused = false;
  for (std::vector<Prepared>& group : groups) {
    const bool array = slurm_.array_min > 0 && static_cast<int>(group.size()) >= slurm_.array_min;
    for (std::size_t first = 0; first < group.size();) {
      const std::size_t count =
          array ? std::min<std::size_t>(kSlurmArrayMax, group.size() - first) : 1;
      std::vector<Prepared> part(std::make_move_iterator(group.begin() + first),
                                 std::make_move_iterator(group.begin() + first + count));
      first += count;
      if (paused) {
        for (const Prepared& p : part) Release(p.job.id());
      } else if (array && part.size() > 1) {
        paused = !SubmitArray(part);
      } else {
        paused = !SubmitOne(part[0]);
      }
    }
  }
}

void SlurmExecutor::FailQueued(const std::string& id, const std::string& error) {
  (void)store_.ReleaseToQueue(id);  // it never reached Slurm
  if (const Status ended = EndQueuedJob(store_, hub_, id, v1::Job::FAILED, error); !ended.ok())
    spdlog::error("job {}: cannot record its end: {}", id, ended.ToString());
}

bool SlurmExecutor::Prepare(const v1::Job& job, Prepared* p) {
  const std::string& id = job.id();
  if (job.attempts() >= options_.max_attempts) {
    FailQueued(
        id, fmt::format("started {} times without finishing; not started again", job.attempts()));
    return false;
  }
  if (options_.may_run) {
    if (const Status allowed = options_.may_run(job); !allowed.ok()) {
      FailQueued(id, allowed.ToString());
      return false;
    }
  }
  if (job.ranks() > 1 && options_.mpirun.empty()) {
    FailQueued(id, fmt::format("the job asks for {} MPI ranks, but this server runs no MPI (no "
                               "mpirun)",
                               job.ranks()));
    return false;
  }
  if (job.ranks() > options_.max_ranks) {
    FailQueued(id, fmt::format("the job asks for {} MPI ranks; this server allows {} (--max-ranks)",
                               job.ranks(), options_.max_ranks));
    return false;
  }
  const fs::path dir = JobsDir(options_) / id;
  v1::Job attempt = job;
  attempt.set_attempts(job.attempts() + 1);  // the run this prepares
  std::vector<std::string> input;
  Status prepared = PrepareFolder(attempt, dir, options_.preparation, &input);
  RemoveRunFiles(dir);
  const int ranks = std::max(1, job.ranks());
  ExecutorOptions per_job = options_;
  per_job.solver_threads = slurm_.cpus_per_task * ranks;
  const std::vector<std::string> command = SolverCommandLine(per_job, job, input, kSlurmRunResult);
  if (prepared.ok()) {
    prepared = AtomicWriteText(dir / kScript,
                               SlurmBatchScript(command, SolverMemoryPerRank(options_, job)));
  }
  if (!prepared.ok()) {
    FailQueued(id,
               prepared.code() == Status::Code::kIo || prepared.code() == Status::Code::kInternal
                   ? "cannot prepare the job folder: " + prepared.ToString()
                   : prepared.ToString());
    return false;
  }
  std::error_code log_ec;
  p->log_offset = fs::file_size(dir / "solve.log", log_ec);
  if (log_ec) p->log_offset = 0;
  p->job = job;
  p->dir = dir;
  p->ranks = ranks;
  p->limit_s = TimeLimit(options_, job);
  p->memory_bytes = options_.max_solver_memory_bytes;
  return true;
}

SlurmExecutor::Sbatched SlurmExecutor::Sbatch(const Prepared& p, SlurmSubmission submission,
                                              std::string* slurm_id, std::string* said) {
  submission.ranks = p.ranks;
  submission.cpus_per_task = slurm_.cpus_per_task;
  submission.time_limit_s = p.limit_s;
  submission.memory_bytes = p.memory_bytes;
  CommandResult r;
  const Status run = Slurm("sbatch", SbatchArguments(slurm_, submission), &r);
  *slurm_id = SlurmTrim(r.out.substr(0, r.out.find(';')));
  if (run.ok() && r.ok() && IsSlurmJobId(*slurm_id)) return Sbatched::kSubmitted;
  *said = run.ok() ? r.Describe() : run.ToString();
  // A controller that does not answer now may later: the jobs wait in
  // PBA's queue, and are tried again after a pause, not at every poll.
  // Anything else is the jobs' (a partition, an account, limits Slurm
  // refuses).
  if (run.ok() && !r.timed_out && !SbatchMayAnswerLater(*said)) return Sbatched::kRefused;
  submit_after_ = std::chrono::steady_clock::now() + kSubmitPause;
  spdlog::warn("sbatch failed ({}); submitting again in {} s", *said, kSubmitPause.count());
  return Sbatched::kLater;
}

void SlurmExecutor::Release(const std::string& id) {
  if (const Status released = store_.ReleaseToQueue(id); !released.ok())
    spdlog::error("job {}: cannot put it back in the queue: {}", id, released.ToString());
}

bool SlurmExecutor::SubmitOne(Prepared& p) {
  const std::string& id = p.job.id();
  SlurmSubmission submission;
  submission.job_id = id;
  submission.dir = p.dir;
  submission.script = p.dir / kScript;
  std::string slurm_id, said;
  switch (Sbatch(p, submission, &slurm_id, &said)) {
    case Sbatched::kLater:
      Release(id);
      return false;
    case Sbatched::kRefused:
      FailQueued(id, "Slurm refused the job: sbatch " + said);
      return true;
    case Sbatched::kSubmitted:
      break;
  }
  Track(p, slurm_id, "submitted to Slurm as job " + slurm_id);
  return true;
}

bool SlurmExecutor::SubmitArray(std::vector<Prepared>& members) {
  const Prepared& first = members.front();
  // Named after its first job and the time: a job given back to the queue
  // before it started may lead another array, while the tasks of the first
  // one still wait in Slurm for their folder. An existing folder is never
  // reused.
  const std::string token = fmt::format("{}-{}", first.job.id(),
                                        std::chrono::duration_cast<std::chrono::microseconds>(
                                            std::chrono::system_clock::now().time_since_epoch())
                                            .count());
  const fs::path dir = JobsDir(options_) / kArrays / token;
  std::error_code ec;
  bool created = false;
  fs::create_directories(dir.parent_path(), ec);
  if (!ec) created = fs::create_directory(dir, ec);
  if (!ec && !created) ec = std::make_error_code(std::errc::file_exists);
  // Only a folder made here is removed when the array does not go.
  const auto remove_folder = [&] {
    std::error_code ignored;
    if (created) fs::remove_all(dir, ignored);
  };
  std::string list;
  for (std::size_t i = 0; i < members.size() && !ec; ++i) {
    fs::create_directory_symlink(fs::path("..") / ".." / members[i].job.id(),
                                 dir / std::to_string(i), ec);
    list += members[i].job.id() + "\n";
  }
  Status written = ec ? Status::Io(dir.string() + ": " + ec.message()) : Status::Ok();
  if (written.ok()) written = AtomicWriteText(dir / kArrayJobs, list);
  if (written.ok()) written = AtomicWriteText(dir / kArrayScript, SlurmArrayScript(kScript));
  const auto one_by_one = [&](const std::string& why) {
    spdlog::warn("a job array of {} jobs: {}; they go to Slurm one by one", members.size(), why);
    remove_folder();
    for (std::size_t i = 0; i < members.size(); ++i) {
      if (!SubmitOne(members[i])) {
        for (std::size_t j = i + 1; j < members.size(); ++j) Release(members[j].job.id());
        return false;
      }
    }
    return true;
  };
  if (!written.ok()) return one_by_one("cannot write its folder: " + written.ToString());
  SlurmSubmission submission;
  submission.job_id = token;
  submission.dir = dir;
  submission.script = dir / kArrayScript;
  submission.array_tasks = static_cast<int>(members.size());
  std::string array_id, said;
  switch (Sbatch(first, submission, &array_id, &said)) {
    case Sbatched::kLater:
      remove_folder();
      for (const Prepared& p : members) Release(p.job.id());
      return false;
    case Sbatched::kRefused:
      // (A site's MaxArraySize, say: each job on its own may still pass.)
      return one_by_one("Slurm refused it: sbatch " + said);
    case Sbatched::kSubmitted:
      break;
  }
  spdlog::info("{} jobs submitted to Slurm as job array {}", members.size(), array_id);
  for (std::size_t i = 0; i < members.size(); ++i) {
    Track(members[i], fmt::format("{}_{}", array_id, i),
          fmt::format("submitted to Slurm as task {} of job array {}", i, array_id));
  }
  return true;
}

void SlurmExecutor::Track(Prepared& p, const std::string& slurm_id, const std::string& message) {
  const std::string& id = p.job.id();
  v1::SchedulerJob scheduler;
  scheduler.set_system(kSystem);
  scheduler.set_job_id(slurm_id);
  scheduler.set_state("PENDING");
  v1::JobEvent event;
  const Status recorded = store_.RecordSchedulerJob(id, scheduler, message, &event);
  if (!recorded.ok()) {
    // Cancelled (or gone) while it was being submitted: Slurm must not run it.
    spdlog::info("job {} ended while it was submitted: scancel {}", id, slurm_id);
    CommandResult cancelled;
    (void)Slurm("scancel", {slurm_id}, &cancelled);
    return;
  }
  hub_.Publish(event);
  spdlog::info("job {}: {}", id, message);
  auto t = std::make_unique<Tracked>();
  t->job = std::move(p.job);
  t->slurm_id = slurm_id;
  t->dir = p.dir;
  t->limit_s = p.limit_s;
  t->log_offset = p.log_offset;
  t->last.state = "PENDING";
  t->progress = std::make_unique<ProgressLines>(store_, hub_, id, event.sequence());
  std::lock_guard lock(mutex_);
  tracked_[id] = std::move(t);
}

const SlurmJobState* SlurmExecutor::FindInArrays(const std::vector<SlurmJobState>& queue,
                                                 const std::string& id) {
  const std::string prefix = kSlurmArrayPrefix;
  for (const SlurmJobState& s : queue) {
    if (s.name.rfind(prefix, 0) != 0 || ClassifySlurmState(s.state) != SlurmEnd::kNotEnded)
      continue;
    const std::string token = s.name.substr(prefix.size());
    const std::size_t underscore = s.id.find('_');
    // Only a name PBA could have given (no path in it), and a task.
    if (token.empty() || underscore == std::string::npos ||
        !std::all_of(token.begin(), token.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) || c == '-';
        }))
      continue;
    std::ifstream in(JobsDir(options_) / kArrays / token / kArrayJobs);
    std::string line;
    for (int task = 0; task < kSlurmArrayMax && ReadBoundedLine(in, kMaxIdLine, &line); ++task) {
      if (line == id && s.id.substr(underscore + 1) == std::to_string(task)) return &s;
    }
  }
  return nullptr;
}

void SlurmExecutor::ExpireArrays() {
  const fs::path arrays = JobsDir(options_) / kArrays;
  std::error_code ec;
  if (!fs::is_directory(arrays, ec)) return;
  const auto now = fs::file_time_type::clock::now();
  for (const fs::directory_entry& entry : fs::directory_iterator(arrays, ec)) {
    std::error_code time_ec;
    const auto written = fs::last_write_time(entry.path() / kArrayJobs, time_ec);
    if (!time_ec && now - written < kArrayKeep) continue;
    bool followed = false;
    std::ifstream in(entry.path() / kArrayJobs);
    std::string line;
    {
      std::lock_guard lock(mutex_);
      for (int task = 0;
           task < kSlurmArrayMax && ReadBoundedLine(in, kMaxIdLine, &line) && !followed; ++task)
        followed = tracked_.count(line) > 0;
    }
    if (!followed) fs::remove_all(entry.path(), time_ec);
  }
}

void SlurmExecutor::Follow(Tracked& t, const SlurmJobState* seen) {
  if (seen == nullptr) {
    if (++t.missing >= kMissingRounds) Conclude(t, nullptr);
    return;
  }
  t.missing = 0;
  const SlurmEnd end = ClassifySlurmState(seen->state);
  if (seen->state != t.last.state || seen->reason != t.last.reason || seen->node != t.last.node) {
    v1::SchedulerJob scheduler;
    scheduler.set_system(kSystem);
    scheduler.set_job_id(t.slurm_id);
    scheduler.set_state(seen->state);
    scheduler.set_reason(seen->reason);
    scheduler.set_node(seen->node);
    // An event while it waits (a new reason shows why); a start and an end
    // make their own.
    const bool waiting = end == SlurmEnd::kNotEnded && !SlurmRunning(seen->state);
    v1::JobEvent event;
    const Status recorded = store_.RecordSchedulerJob(
        t.job.id(), scheduler, waiting ? "Slurm: " + SlurmSaid(t.slurm_id, seen) : "", &event);
    if (recorded.ok() && event.sequence() > 0) {
      hub_.Publish(event);
      t.progress->set_sequence(std::max(t.progress->sequence(), event.sequence()));
    }
    t.last = *seen;
  }
  if (SlurmRunning(seen->state) && !t.running) {
    StartRun(t, "Slurm job " + t.slurm_id + (seen->node.empty() ? "" : " on " + seen->node));
  }
  if (t.running) ReadProgress(t);
  if (end != SlurmEnd::kNotEnded) Conclude(t, seen);
}

bool SlurmExecutor::StartRun(Tracked& t, const std::string& message) {
  v1::JobEvent event;
  bool started = false;
  v1::Job job;
  const Status status = store_.StartScheduled(t.job.id(), message, &job, &event, &started);
  if (!status.ok() || !started) {
    if (!status.ok())
      spdlog::error("job {}: cannot record its start: {}", t.job.id(), status.ToString());
    return false;
  }
  t.job = std::move(job);
  t.running = true;
  t.progress->set_sequence(std::max(t.progress->sequence(), event.sequence()));
  hub_.Publish(event);
  LogStateChange(event);
  return true;
}

void SlurmExecutor::SkimProgress(Tracked& t) {
  const fs::path file = t.dir / SlurmProgressFile(t.slurm_id);
  std::ifstream in(file, std::ios::binary);
  if (!in) return;
  in.seekg(static_cast<std::streamoff>(t.offset));
  std::string line;
  while (std::getline(in, line)) t.progress->Skim(line);
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(file, ec);
  if (!ec) t.offset = size;
  t.partial.clear();
}

void SlurmExecutor::ReadProgress(Tracked& t) {
  std::ifstream in(t.dir / SlurmProgressFile(t.slurm_id), std::ios::binary);
  if (!in) return;
  in.seekg(static_cast<std::streamoff>(t.offset));
  std::string chunk(kMaxProgressRead, '\0');
  in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
  chunk.resize(static_cast<std::size_t>(in.gcount()));
  t.offset += chunk.size();
  t.partial += chunk;
  std::size_t start = 0;
  for (std::size_t end; (end = t.partial.find('\n', start)) != std::string::npos; start = end + 1)
    t.progress->Handle(t.partial.substr(start, end - start));
  t.partial.erase(0, start);
  // A line longer than anything pba-solve writes is not one of its events.
  if (t.partial.size() > kMaxProgressRead) t.partial.clear();
}

bool SlurmExecutor::Accounting(const std::string& slurm_id, SlurmJobState* state) {
  // With slurmdbd, sacct; without, the job completion file (sacct -c).
  for (const bool completion : {false, true}) {
    std::vector<std::string> args = {"--noheader", "--parsable2", "--allocations",
                                     "--jobs=" + slurm_id, "--format=JobID,State,ExitCode"};
    if (completion) args.insert(args.begin(), "--completion");
    CommandResult r;
    if (!Slurm("sacct", args, &r).ok() || !r.ok()) continue;
    // A job run more than once has a line for each end: the last one.
    const std::vector<SlurmJobState> lines = ParseSacct(r.out, slurm_id);
    if (lines.empty()) continue;
    *state = lines.back();
    return true;
  }
  return false;
}

bool SlurmExecutor::Settled(Tracked& t, const SlurmJobState* seen, std::optional<int> code,
                            const fs::path& run_result) {
  Status whole =
      code.has_value()
          ? Status::Ok()
          : Status::Io("its exit code file " + ExitCodeFile(t.slurm_id) + " is not there");
  if (whole.ok() && *code == 0) whole = ChecksumFileComplete(run_result);
  if (whole.ok()) return true;
  SlurmJobState recorded;
  if (seen == nullptr && Accounting(t.slurm_id, &recorded)) seen = &recorded;
  if (seen == nullptr || ClassifySlurmState(seen->state) != SlurmEnd::kCompleted) return true;
  const auto now = std::chrono::steady_clock::now();
  if (!t.settling_since) {
    t.settling_since = now;
    spdlog::info("job {}: Slurm job {} completed, but {}; looking again for up to {} s", t.job.id(),
                 t.slurm_id, whole.ToString(),
                 std::chrono::duration_cast<std::chrono::seconds>(slurm_.settle).count());
  }
  return now - *t.settling_since >= slurm_.settle;
}

void SlurmExecutor::Conclude(Tracked& t, const SlurmJobState* seen) {
  const std::string id = t.job.id();
  bool cancel_requested = false;
  {
    std::lock_guard lock(mutex_);
    cancel_requested = t.cancel_requested;
  }
  const std::optional<int> code = ReadExitCode(t.dir, t.slurm_id);
  const fs::path run_result = t.dir / ResultDir(t.slurm_id);
  if (!cancel_requested && !Settled(t, seen, code, run_result)) return;
  // Its last lines (pba-solve's error among them) before anything is
  // decided: published when it is seen running, else only read.
  if (t.running) {
    ReadProgress(t);
  } else {
    SkimProgress(t);
  }
  // A job Slurm started and ended between two rounds is started here.
  const auto run = [&] {
    return t.running ||
           StartRun(t, "Slurm job " + t.slurm_id + ", ended before it was seen running");
  };
  const auto end_run = [&](RunOutcome outcome) {
    std::error_code ec;
    fs::remove_all(run_result, ec);  // renamed to result/ when it succeeded
    for (const fs::directory_entry& entry : fs::directory_iterator(t.dir, ec)) {
      if (entry.path().filename().string().rfind("." + ResultDir(t.slurm_id) + ".", 0) == 0)
        fs::remove_all(entry.path(), ec);
    }
    if (run()) {
      ReadProgress(t);
      RecordRunEnd(store_, hub_, t.dir, id, t.progress->sequence(), std::move(outcome));
    }
  };
  const auto fail = [&](const std::string& error) {
    RunOutcome outcome;
    outcome.state = v1::Job::FAILED;
    outcome.error = error;
    end_run(std::move(outcome));
  };
  // Gone from squeue: the accounting, if the cluster keeps one, still
  // knows how it ended (without Slurm's reason).
  SlurmJobState recorded;
  if (seen == nullptr && Accounting(t.slurm_id, &recorded)) seen = &recorded;
  const std::string said = SlurmSaid(t.slurm_id, seen);
  const SlurmEnd end = seen != nullptr ? ClassifySlurmState(seen->state) : SlurmEnd::kFailed;
  // Slurm's own kill over the job's memory, told only in its stderr (a
  // cluster without cgroups has it FAILED, not OUT_OF_MEMORY).
  const bool over_memory = end == SlurmEnd::kOutOfMemory ||
                           (code.value_or(1) != 0 && LogSays(t.dir / "solve.log", t.log_offset,
                                                             "Exceeded job memory limit"));
  if (cancel_requested) {
    if (t.running) {
      RunOutcome outcome;
      outcome.state = v1::Job::CANCELLED;
      outcome.error = kCancelledByRequest;
      end_run(std::move(outcome));
    } else {
      (void)EndQueuedJob(store_, hub_, id, v1::Job::CANCELLED, "cancelled before it started");
    }
  } else if (code == 0 && end != SlurmEnd::kRequeue) {
    // pba-solve ran to its end and succeeded.
    // This run's result becomes the job's.
    RunOutcome outcome;
    std::error_code ec;
    fs::remove_all(t.dir / "result", ec);
    fs::rename(run_result, t.dir / "result", ec);
    const Status collected = ec ? Status::Io("its result " + run_result.string() +
                                             " cannot be moved into place: " + ec.message())
                                : CollectResult(t.dir / "result", &outcome.summary, &outcome.files);
    Status completed = collected;
    if (collected.ok() && options_.preparation != nullptr) {
      completed = options_.preparation->Complete(t.job, t.dir / "result", &outcome);
    }
    if (!collected.ok()) {
      fail(said + ": pba-solve succeeded but " + collected.ToString());
    } else if (!completed.ok()) {
      fail(completed.ToString());
    } else {
      outcome.state = v1::Job::SUCCEEDED;
      end_run(std::move(outcome));
    }
  } else if (end == SlurmEnd::kTimeout) {
    // (pba-solve, stopped by Slurm's SIGTERM, may have left an exit code.)
    fail(said + ": stopped by Slurm at its time limit" +
         (t.limit_s > 0 ? fmt::format(" of {} min", (t.limit_s + 59) / 60) : std::string()));
  } else if (over_memory) {
    fail(said + ": killed by Slurm over its memory limit" +
         (options_.max_solver_memory_bytes > 0
              ? fmt::format(" of {} MiB", (options_.max_solver_memory_bytes + (1 << 20) - 1) >> 20)
              : std::string()));
  } else if (end == SlurmEnd::kCancelled) {
    RunOutcome outcome;
    outcome.state = v1::Job::CANCELLED;
    outcome.error = said + ": cancelled in Slurm, not through PBA";
    if (t.running) {
      end_run(std::move(outcome));
    } else {
      (void)EndQueuedJob(store_, hub_, id, v1::Job::CANCELLED, outcome.error);
    }
  } else if (end == SlurmEnd::kRequeue) {
    const int attempts = t.job.attempts() + (t.running ? 0 : 1);
    if (attempts >= options_.max_attempts) {
      fail(said + fmt::format(": started {} times without finishing; not started again", attempts));
    } else if (t.running) {
      RecordRequeue(store_, hub_, id, t.progress->sequence(), "re-queued: " + said);
    } else if (store_.ReleaseToQueue(id).ok()) {
      spdlog::info("job {}: {} never started; queued again", id, said);
    }
  } else if (code.has_value()) {
    // pba-solve failed: its own words, or its exit code.
    ProcessExit exit;
    exit.code = *code;
    fail(FailureReason(t.progress->error(), exit));
  } else if (seen == nullptr) {
    fail("Slurm job " + t.slurm_id +
         " ended while no server followed it, longer ago than Slurm keeps finished jobs, and "
         "left no exit code: how it ended is not known");
  } else {
    fail(said + (end == SlurmEnd::kCompleted
                     ? ": the batch script ended without pba-solve's exit code"
                     : ": pba-solve did not finish"));
  }
  std::lock_guard lock(mutex_);
  tracked_.erase(id);
}

}  // namespace pba
