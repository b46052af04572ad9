// JobStore: the jobs, their events and their result files in pba.db.
//
// Every logical change (a submit, a state transition with its event, a
// finished run with its files) is one transaction, so a reader never sees a
// state without the event that explains it. Thread-safe: one connection
// behind a mutex, which is plenty for a job queue.
//
// Event sequences: events of a job are numbered 1, 2, ... in the order they
// happen. Transitions made here (submit, start, cancel of a queued job,
// re-queue at start-up) take the next number after the highest stored one.
// While a job runs the executor owns its numbering (it also numbers live
// progress events that are not stored) and passes the number in; the store
// still never goes below "highest stored + 1".
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "pba/status.h"
#include "pba/v1/job.pb.h"
#include "store/database.h"

namespace pba {

// How much of a job to load: kFull adds the scene and the summary.
enum class JobView { kBasic, kFull };

// What a submit stores (validated and resolved by the caller).
struct NewJob {
  v1::Scene scene;
  std::string request_id;
  std::string owner;
  int priority = 0;
  int timeout_s = 0;
  int ranks = 0;                                  // MPI processes; 0 or 1: one
  v1::SnapshotRef snapshot;                       // resolved: the snapshot's id
  const v1::AtlasImport* atlas_import = nullptr;  // an import job
  // The most jobs `owner` may have QUEUED or RUNNING; a new job beyond is
  // kResourceExhausted (a repeated request_id still returns its job). 0:
  // no bound.
  int max_open = 0;
  // Runs inside the submit's transaction once the job has its id, before
  // it commits (an error rolls the submit back): what the job needs is in
  // place before any worker can see it.
  std::function<Status(const std::string& id)> before_commit;
};

// Who lists jobs (job.proto, "Who sees a job"): `user` sees the jobs on no
// project, their own, and those on projects they are a member of (by the
// atlas store's members, read from the same database); `all` (a server
// admin) sees every job.
struct JobReader {
  std::string user;
  bool all = false;
};

// How a run ended, for FinishRun().
struct RunOutcome {
  v1::Job::State state = v1::Job::FAILED;  // SUCCEEDED, FAILED or CANCELLED
  std::string error;                       // FAILED / CANCELLED: why
  std::string message;                     // the event's message
  v1::Summary summary;                     // SUCCEEDED only
  std::vector<v1::ResultFile> files;       // SUCCEEDED only
  v1::SnapshotRef snapshot;                // SUCCEEDED import: the snapshot it made
};

class JobStore {
 public:
  static constexpr int kDefaultPageSize = 50;
  static constexpr int kMaxPageSize = 500;

  // Opens or creates the database at `path` and migrates it.
  static Status Open(const std::filesystem::path& path, std::unique_ptr<JobStore>* out);

  Status SchemaVersion(int* version);

  // Stores a QUEUED job for `scene`, submitted by `owner`, with its first
  // event. With a non-empty `request_id` that `owner` used before, returns
  // the job created then and sets *created to false; another owner's
  // request_id is kAlreadyExists. The scene must already be validated.
  Status CreateJob(const NewJob& request, v1::Job* job, bool* created);
  Status CreateJob(const v1::Scene& scene, const std::string& request_id, const std::string& owner,
                   v1::Job* job, bool* created) {
    NewJob request;
    request.scene = scene;
    request.request_id = request_id;
    request.owner = owner;
    return CreateJob(request, job, created);
  }
  Status GetJob(const std::string& id, JobView view, v1::Job* job, bool* found);
  // The job `owner` submitted with `request_id` (kFull); another owner's is
  // kAlreadyExists, as in CreateJob.
  Status FindByRequestId(const std::string& request_id, const std::string& owner, v1::Job* job,
                         bool* found);

  // The jobs `reader` sees, newest first. `page_size` 0 means
  // kDefaultPageSize; larger than kMaxPageSize is capped. An unparsable
  // token is kInvalidArgument. A page holds page_size jobs the reader sees
  // (hidden ones are skipped in the query, not dropped from a page).
  Status ListJobs(const JobReader& reader, int page_size, const std::string& page_token,
                  std::vector<v1::Job>* jobs, std::string* next_page_token);
  // Every job (a reader with `all`).
  Status ListJobs(int page_size, const std::string& page_token, std::vector<v1::Job>* jobs,
                  std::string* next_page_token);

  // Stored events with sequence > `after_sequence`, in order.
  Status ListEvents(const std::string& id, int64_t after_sequence,
                    std::vector<v1::JobEvent>* events);

  Status GetResultFile(const std::string& id, const std::string& name, v1::ResultFile* file,
                       bool* found);

  // Moves the QUEUED job of highest priority, the oldest of those, to RUNNING (attempts + 1, start
  // time, event). *claimed is false when nothing is queued. `job` is loaded with kFull.
  Status ClaimNextQueued(v1::Job* job, v1::JobEvent* event, bool* claimed);

  // QUEUED -> CANCELLED with an event; *cancelled is false (and nothing
  // changes) when the job is not QUEUED.
  Status CancelQueued(const std::string& id, const std::string& message, v1::JobEvent* event,
                      bool* cancelled);
  // QUEUED -> `state` (CANCELLED or FAILED) with `message` as the error and
  // the event; *ended is false (and nothing changes) when it is not QUEUED.
  Status EndQueued(const std::string& id, v1::Job::State state, const std::string& message,
                   v1::JobEvent* event, bool* ended);

  // Stores a progress event of a RUNNING job and its phase/progress.
  // event->sequence may be raised to stay above the stored events.
  Status RecordProgress(v1::JobEvent* event);

  // RUNNING -> outcome.state, with end time, error, summary, result files and
  // the terminal event, all at once.
  Status FinishRun(const std::string& id, int64_t sequence, const RunOutcome& outcome,
                   v1::JobEvent* event);

  // RUNNING -> QUEUED (progress cleared) with an event saying why.
  Status RequeueRun(const std::string& id, int64_t sequence, const std::string& message,
                    v1::JobEvent* event);

  // Jobs that ended before `ended_before_us` and still have result files:
  // their file rows are removed and `note` is put in their error (after any
  // error they had); *ids lists them, for their folders to be removed.
  Status ExpireResults(int64_t ended_before_us, const std::string& note,
                       std::vector<std::string>* ids);

  // Every job left RUNNING by a server that stopped goes back to QUEUED with
  // an event carrying `message`, but for those in a cluster scheduler's
  // hands (Job.scheduler), which run on without the server. Call once at
  // start-up, before the executor.
  Status RequeueInterrupted(const std::string& message, std::vector<v1::JobEvent>* events);

  // Jobs handed to a cluster scheduler (jobs/slurm_executor.h). A QUEUED
  // job is claimed for the scheduler by marking it "submitting" (no event;
  // it stays QUEUED); RecordSchedulerJob then names its job there (or a new
  // state or reason, with an event when `message` is not empty: state,
  // phase and progress as they are); StartScheduled moves it to RUNNING
  // when the scheduler starts it (attempts + 1, start time, an event "started
  // (attempt N), <message>"); ReleaseToQueue gives a QUEUED job back
  // (nothing was submitted). FinishRun, RequeueRun (which forgets the
  // scheduler's job) and CancelQueued end them as any other.
  Status ClaimForScheduler(v1::Job* job, bool* claimed);
  Status RecordSchedulerJob(const std::string& id, const v1::SchedulerJob& scheduler,
                            const std::string& message, v1::JobEvent* event);
  Status StartScheduled(const std::string& id, const std::string& message, v1::Job* job,
                        v1::JobEvent* event, bool* started);
  Status ReleaseToQueue(const std::string& id);
  // The QUEUED and RUNNING jobs with a scheduler's job, oldest first (kFull).
  Status ListScheduled(std::vector<v1::Job>* jobs);

 private:
  explicit JobStore(std::unique_ptr<Database> db) : db_(std::move(db)) {}

  Status LoadJob(const std::string& id, JobView view, v1::Job* job, bool* found);
  // The QUEUED job of highest priority, the oldest of those, not in a
  // scheduler's hands; "" when there is none.
  Status NextQueued(std::string* id);
  Status LoadResultFiles(const std::string& id, v1::Job* job);
  Status NextSequence(const std::string& id, int64_t at_least, int64_t* sequence);
  Status InsertEvent(const v1::JobEvent& event);
  // Moves a job from `from` to `to` state; *changed says whether it was in `from`.
  Status Transition(const std::string& id, v1::Job::State from, v1::Job::State to, bool* changed);

  std::mutex mutex_;
  std::unique_ptr<Database> db_;
};

}  // namespace pba
