#include "store/job_store.h"

#include <google/protobuf/util/time_util.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>

#include "store/job_id.h"
#include "store/migrations.h"
#include "store/transaction.h"

namespace pba {
namespace {

using google::protobuf::util::TimeUtil;

// A new id colliding with an existing one is a 1-in-10^12 event per pair;
// a few retries make failure practically impossible.
constexpr int kIdAttempts = 8;
constexpr char kPageTokenPrefix[] = "jobs.v1:";
constexpr char kJobColumns[] =
    "id, name, state, create_time_us, start_time_us, end_time_us, phase, progress, error, "
    "attempts, scene, summary, owner, priority, timeout_s, snapshot_project, snapshot, "
    "atlas_import, ranks, scheduler_job, scheduler_state, scheduler_reason, scheduler_node";
constexpr int kJobColumnCount = 23;

// scheduler_job while a job is being handed to the scheduler.
constexpr char kSubmitting[] = "submitting";

int64_t NowMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

const std::string& StateName(v1::Job::State state) { return v1::Job::State_Name(state); }

v1::Job::State ParseState(const std::string& name) {
  v1::Job::State state = v1::Job::STATE_UNSPECIFIED;
  v1::Job::State_Parse(name, &state);
  return state;
}

// Page tokens are opaque to clients: the hex form of a prefixed job number.
std::string EncodePageToken(int64_t number) {
  const std::string plain = kPageTokenPrefix + std::to_string(number);
  std::string hex;
  char buffer[3];
  for (unsigned char c : plain) {
    std::snprintf(buffer, sizeof(buffer), "%02x", c);
    hex += buffer;
  }
  return hex;
}

std::optional<int64_t> DecodePageToken(const std::string& token) {
  if (token.size() % 2 != 0 || token.size() > 80) return std::nullopt;
  std::string plain;
  for (size_t i = 0; i < token.size(); i += 2) {
    int value = 0;
    for (int k = 0; k < 2; ++k) {
      const char c = token[i + k];
      int digit;
      if (c >= '0' && c <= '9') {
        digit = c - '0';
      } else if (c >= 'a' && c <= 'f') {
        digit = c - 'a' + 10;
      } else {
        return std::nullopt;
      }
      value = value * 16 + digit;
    }
    plain.push_back(static_cast<char>(value));
  }
  const std::string prefix = kPageTokenPrefix;
  if (plain.rfind(prefix, 0) != 0) return std::nullopt;
  const std::string digits = plain.substr(prefix.size());
  if (digits.empty() || digits.size() > 18 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return std::nullopt;
  }
  const int64_t number = std::stoll(digits);
  if (number <= 0) return std::nullopt;
  return number;
}

v1::JobEvent MakeEvent(const std::string& id, int64_t sequence, v1::Job::State state,
                       const std::string& phase, double progress, const std::string& message) {
  v1::JobEvent event;
  event.set_job_id(id);
  event.set_sequence(sequence);
  *event.mutable_time() = TimeUtil::MicrosecondsToTimestamp(NowMicros());
  event.set_state(state);
  event.set_phase(phase);
  event.set_progress(progress);
  event.set_message(message);
  return event;
}

// Reads a row selected with kJobColumns.
void ReadJobRow(const Statement& stmt, JobView view, v1::Job* job) {
  job->Clear();
  job->set_id(stmt.ColumnText(0));
  job->set_name(stmt.ColumnText(1));
  job->set_state(ParseState(stmt.ColumnText(2)));
  *job->mutable_create_time() = TimeUtil::MicrosecondsToTimestamp(stmt.ColumnInt(3));
  if (!stmt.ColumnIsNull(4)) {
    *job->mutable_start_time() = TimeUtil::MicrosecondsToTimestamp(stmt.ColumnInt(4));
  }
  if (!stmt.ColumnIsNull(5)) {
    *job->mutable_end_time() = TimeUtil::MicrosecondsToTimestamp(stmt.ColumnInt(5));
  }
  job->set_phase(stmt.ColumnText(6));
  job->set_progress(stmt.ColumnDouble(7));
  job->set_error(stmt.ColumnText(8));
  job->set_attempts(static_cast<int32_t>(stmt.ColumnInt(9)));
  if (view == JobView::kFull) {
    job->mutable_scene()->ParseFromString(stmt.ColumnBlob(10));
    if (!stmt.ColumnIsNull(11)) job->mutable_summary()->ParseFromString(stmt.ColumnBlob(11));
  }
  job->set_owner(stmt.ColumnText(12));
  job->set_priority(static_cast<int32_t>(stmt.ColumnInt(13)));
  job->set_timeout_s(static_cast<int32_t>(stmt.ColumnInt(14)));
  if (!stmt.ColumnText(15).empty()) {
    job->mutable_snapshot()->set_project(stmt.ColumnText(15));
    job->mutable_snapshot()->set_snapshot(stmt.ColumnText(16));
  }
  if (!stmt.ColumnIsNull(17)) job->mutable_atlas_import()->ParseFromString(stmt.ColumnBlob(17));
  job->set_ranks(static_cast<int32_t>(stmt.ColumnInt(18)));
  // A job that ended while it was being handed to a scheduler never had a
  // job there.
  const bool ended_unsubmitted =
      stmt.ColumnText(19) == kSubmitting && job->state() != v1::Job::QUEUED;
  if (!stmt.ColumnText(19).empty() && !ended_unsubmitted) {
    v1::SchedulerJob* scheduler = job->mutable_scheduler();
    scheduler->set_system("slurm");
    scheduler->set_job_id(stmt.ColumnText(19));
    scheduler->set_state(stmt.ColumnText(20));
    scheduler->set_reason(stmt.ColumnText(21));
    scheduler->set_node(stmt.ColumnText(22));
  }
}

}  // namespace

Status JobStore::Open(const std::filesystem::path& path, std::unique_ptr<JobStore>* out) {
  std::unique_ptr<Database> db;
  PBA_RETURN_IF_ERROR(Database::Open(path, &db));
  PBA_RETURN_IF_ERROR(ApplyMigrations(*db));
  out->reset(new JobStore(std::move(db)));
  return Status::Ok();
}

Status JobStore::SchemaVersion(int* version) {
  std::lock_guard lock(mutex_);
  return ReadSchemaVersion(*db_, version);
}

Status JobStore::CreateJob(const NewJob& request, v1::Job* job, bool* created) {
  const v1::Scene& scene = request.scene;
  const std::string& request_id = request.request_id;
  const std::string& owner = request.owner;
  std::lock_guard lock(mutex_);
  *created = false;
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Statement stmt;
  if (!request_id.empty()) {
    PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id, owner FROM jobs WHERE request_id = ?", &stmt));
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Bind(1, request_id).Step(&row));
    if (row) {
      const std::string id = stmt.ColumnText(0);
      const std::string earlier_owner = stmt.ColumnText(1);
      stmt = Statement();
      // A request id names one user's submit; another's is not theirs to see.
      if (earlier_owner != owner) {
        return Status::AlreadyExists(
            "request_id: another user's job was submitted with this request id");
      }
      bool found = false;
      return LoadJob(id, JobView::kFull, job, &found);
    }
  }
  if (request.max_open > 0) {
    PBA_RETURN_IF_ERROR(
        db_->Prepare("SELECT COUNT(*) FROM jobs WHERE state IN (?, ?) AND owner = ?", &stmt));
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Bind(1, StateName(v1::Job::QUEUED))
                            .Bind(2, StateName(v1::Job::RUNNING))
                            .Bind(3, owner)
                            .Step(&row));
    const int64_t open = row ? stmt.ColumnInt(0) : 0;
    stmt = Statement();
    if (open >= request.max_open) {
      return Status::ResourceExhausted(
          "", "user '" + owner + "' already has " + std::to_string(open) +
                  " jobs queued or running, the most this server takes from one user "
                  "(pba-server --max-open-jobs); submit more once some have ended");
    }
  }
  std::string id;
  for (int attempt = 0; attempt < kIdAttempts && id.empty(); ++attempt) {
    std::string candidate = NewJobId();
    PBA_RETURN_IF_ERROR(db_->Prepare("SELECT 1 FROM jobs WHERE id = ?", &stmt));
    bool taken = false;
    PBA_RETURN_IF_ERROR(stmt.Bind(1, candidate).Step(&taken));
    if (!taken) id = std::move(candidate);
  }
  if (id.empty()) return Status::Internal("could not find an unused job id");

  std::string name = scene.name().empty() ? "unnamed" : scene.name();
  if (request.atlas_import != nullptr) name = "import into " + request.atlas_import->project();
  // The project the job belongs to decides who sees it (JobReader).
  const std::string& project = request.atlas_import != nullptr ? request.atlas_import->project()
                                                               : request.snapshot.project();
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO jobs (id, request_id, name, state, scene, create_time_us, owner, "
                   "priority, timeout_s, snapshot_project, snapshot, atlas_import, project, ranks) "
                   "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                   &stmt));
  stmt.Bind(1, id);
  if (request_id.empty()) {
    stmt.BindNull(2);
  } else {
    stmt.Bind(2, request_id);
  }
  stmt.Bind(3, name)
      .Bind(4, StateName(v1::Job::QUEUED))
      .BindBlob(5, scene.SerializeAsString())
      .Bind(6, NowMicros())
      .Bind(7, owner)
      .Bind(8, int64_t{request.priority})
      .Bind(9, int64_t{request.timeout_s})
      .Bind(10, request.snapshot.project())
      .Bind(11, request.snapshot.snapshot());
  if (request.atlas_import != nullptr) {
    stmt.BindBlob(12, request.atlas_import->SerializeAsString());
  } else {
    stmt.BindNull(12);
  }
  stmt.Bind(13, project);
  stmt.Bind(14, int64_t{request.ranks});
  PBA_RETURN_IF_ERROR(stmt.Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(InsertEvent(MakeEvent(id, 1, v1::Job::QUEUED, "", 0, "queued")));
  if (request.before_commit) PBA_RETURN_IF_ERROR(request.before_commit(id));
  bool found = false;
  PBA_RETURN_IF_ERROR(LoadJob(id, JobView::kFull, job, &found));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  *created = true;
  return Status::Ok();
}

Status JobStore::FindByRequestId(const std::string& request_id, const std::string& owner,
                                 v1::Job* job, bool* found) {
  std::lock_guard lock(mutex_);
  *found = false;
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id, owner FROM jobs WHERE request_id = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, request_id).Step(&row));
  if (!row) return Status::Ok();
  const std::string id = stmt.ColumnText(0);
  if (stmt.ColumnText(1) != owner) {
    return Status::AlreadyExists(
        "request_id: another user's job was submitted with this request id");
  }
  stmt = Statement();
  return LoadJob(id, JobView::kFull, job, found);
}

Status JobStore::GetJob(const std::string& id, JobView view, v1::Job* job, bool* found) {
  std::lock_guard lock(mutex_);
  return LoadJob(id, view, job, found);
}

Status JobStore::LoadJob(const std::string& id, JobView view, v1::Job* job, bool* found) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare(std::string("SELECT ") + kJobColumns + " FROM jobs WHERE id = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Step(found));
  if (!*found) return Status::Ok();
  ReadJobRow(stmt, view, job);
  return LoadResultFiles(id, job);
}

Status JobStore::LoadResultFiles(const std::string& id, v1::Job* job) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT name, size, sha256 FROM result_files WHERE job_id = ? ORDER BY name", &stmt));
  stmt.Bind(1, id);
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    v1::ResultFile* file = job->add_result_files();
    file->set_name(stmt.ColumnText(0));
    file->set_size_bytes(stmt.ColumnInt(1));
    file->set_sha256(stmt.ColumnText(2));
  }
  return Status::Ok();
}

Status JobStore::ListJobs(int page_size, const std::string& page_token, std::vector<v1::Job>* jobs,
                          std::string* next_page_token) {
  JobReader everything;
  everything.all = true;
  return ListJobs(everything, page_size, page_token, jobs, next_page_token);
}

Status JobStore::ListJobs(const JobReader& reader, int page_size, const std::string& page_token,
                          std::vector<v1::Job>* jobs, std::string* next_page_token) {
  if (page_size < 0) return Status::InvalidArgument("page_size", "must not be negative");
  if (page_size == 0) page_size = kDefaultPageSize;
  page_size = std::min(page_size, kMaxPageSize);
  int64_t before = INT64_MAX;
  if (!page_token.empty()) {
    const std::optional<int64_t> number = DecodePageToken(page_token);
    if (!number) {
      return Status::InvalidArgument("page_token", "not a token from a previous ListJobs response");
    }
    before = *number;
  }
  jobs->clear();
  next_page_token->clear();

  std::lock_guard lock(mutex_);
  Statement stmt;
  // Filtered in the query, so that a page holds page_size jobs the reader
  // sees, however many hidden ones lie between them. Membership is read from
  // the atlas store's tables (the same database) in the same statement.
  PBA_RETURN_IF_ERROR(db_->Prepare(
      std::string("SELECT ") + kJobColumns +
          ", number FROM jobs WHERE number < ?1 AND (?3 OR project = '' OR owner = ?4 OR "
          "project IN (SELECT p.name FROM members m JOIN projects p ON p.id = m.project "
          "JOIN users u ON u.id = m.user WHERE u.name = ?4)) "
          "ORDER BY number DESC LIMIT ?2",
      &stmt));
  // One row more than asked tells whether another page follows.
  stmt.Bind(1, before)
      .Bind(2, int64_t{page_size} + 1)
      .Bind(3, int64_t{reader.all ? 1 : 0})
      .Bind(4, reader.user);
  std::vector<int64_t> numbers;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    v1::Job job;
    ReadJobRow(stmt, JobView::kBasic, &job);
    jobs->push_back(std::move(job));
    numbers.push_back(stmt.ColumnInt(kJobColumnCount));
  }
  stmt = Statement();
  if (static_cast<int>(jobs->size()) > page_size) {
    jobs->pop_back();
    *next_page_token = EncodePageToken(numbers[page_size - 1]);
  }
  for (v1::Job& job : *jobs) PBA_RETURN_IF_ERROR(LoadResultFiles(job.id(), &job));
  return Status::Ok();
}

Status JobStore::ListEvents(const std::string& id, int64_t after_sequence,
                            std::vector<v1::JobEvent>* events) {
  std::lock_guard lock(mutex_);
  events->clear();
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT sequence, time_us, state, phase, progress, message FROM job_events "
                   "WHERE job_id = ? AND sequence > ? ORDER BY sequence",
                   &stmt));
  stmt.Bind(1, id).Bind(2, after_sequence);
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    v1::JobEvent& event = events->emplace_back();
    event.set_job_id(id);
    event.set_sequence(stmt.ColumnInt(0));
    *event.mutable_time() = TimeUtil::MicrosecondsToTimestamp(stmt.ColumnInt(1));
    event.set_state(ParseState(stmt.ColumnText(2)));
    event.set_phase(stmt.ColumnText(3));
    event.set_progress(stmt.ColumnDouble(4));
    event.set_message(stmt.ColumnText(5));
  }
  return Status::Ok();
}

Status JobStore::GetResultFile(const std::string& id, const std::string& name, v1::ResultFile* file,
                               bool* found) {
  std::lock_guard lock(mutex_);
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT name, size, sha256 FROM result_files WHERE job_id = ? AND name = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Bind(2, name).Step(found));
  if (*found) {
    file->set_name(stmt.ColumnText(0));
    file->set_size_bytes(stmt.ColumnInt(1));
    file->set_sha256(stmt.ColumnText(2));
  }
  return Status::Ok();
}

Status JobStore::NextSequence(const std::string& id, int64_t at_least, int64_t* sequence) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT COALESCE(MAX(sequence), 0) + 1 FROM job_events WHERE job_id = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Step(&row));
  *sequence = std::max(at_least, stmt.ColumnInt(0));
  return Status::Ok();
}

Status JobStore::InsertEvent(const v1::JobEvent& event) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "INSERT INTO job_events (job_id, sequence, time_us, state, phase, progress, message) "
      "VALUES (?, ?, ?, ?, ?, ?, ?)",
      &stmt));
  return stmt.Bind(1, event.job_id())
      .Bind(2, event.sequence())
      .Bind(3, TimeUtil::TimestampToMicroseconds(event.time()))
      .Bind(4, StateName(event.state()))
      .Bind(5, event.phase())
      .Bind(6, event.progress())
      .Bind(7, event.message())
      .Run();
}

Status JobStore::Transition(const std::string& id, v1::Job::State from, v1::Job::State to,
                            bool* changed) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("UPDATE jobs SET state = ? WHERE id = ? AND state = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, StateName(to)).Bind(2, id).Bind(3, StateName(from)).Run());
  *changed = db_->Changes() > 0;
  return Status::Ok();
}

Status JobStore::NextQueued(std::string* id) {
  id->clear();
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT id FROM jobs WHERE state = ? AND scheduler_job = '' "
                   "ORDER BY priority DESC, number LIMIT 1",
                   &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, StateName(v1::Job::QUEUED)).Step(&row));
  if (row) *id = stmt.ColumnText(0);
  return Status::Ok();
}

Status JobStore::ClaimNextQueued(v1::Job* job, v1::JobEvent* event, bool* claimed) {
  std::lock_guard lock(mutex_);
  *claimed = false;
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  std::string id;
  PBA_RETURN_IF_ERROR(NextQueued(&id));
  if (id.empty()) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE jobs SET state = ?, attempts = attempts + 1, start_time_us = ?, "
                   "end_time_us = NULL, phase = '', progress = 0, error = '' WHERE id = ?",
                   &stmt));
  PBA_RETURN_IF_ERROR(
      stmt.Bind(1, StateName(v1::Job::RUNNING)).Bind(2, NowMicros()).Bind(3, id).Run());
  stmt = Statement();
  bool found = false;
  PBA_RETURN_IF_ERROR(LoadJob(id, JobView::kFull, job, &found));
  int64_t sequence = 0;
  PBA_RETURN_IF_ERROR(NextSequence(id, 1, &sequence));
  *event = MakeEvent(id, sequence, v1::Job::RUNNING, "", 0,
                     "started (attempt " + std::to_string(job->attempts()) + ")");
  PBA_RETURN_IF_ERROR(InsertEvent(*event));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  *claimed = true;
  return Status::Ok();
}

Status JobStore::CancelQueued(const std::string& id, const std::string& message,
                              v1::JobEvent* event, bool* cancelled) {
  return EndQueued(id, v1::Job::CANCELLED, message, event, cancelled);
}

Status JobStore::EndQueued(const std::string& id, v1::Job::State state, const std::string& message,
                           v1::JobEvent* event, bool* ended) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  PBA_RETURN_IF_ERROR(Transition(id, v1::Job::QUEUED, state, ended));
  if (!*ended) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE jobs SET end_time_us = ?, error = ? WHERE id = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, NowMicros()).Bind(2, message).Bind(3, id).Run());
  int64_t sequence = 0;
  PBA_RETURN_IF_ERROR(NextSequence(id, 1, &sequence));
  *event = MakeEvent(id, sequence, state, "", 0, message);
  PBA_RETURN_IF_ERROR(InsertEvent(*event));
  return transaction.Commit();
}

Status JobStore::RecordProgress(v1::JobEvent* event) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE jobs SET phase = ?, progress = ? WHERE id = ? AND state = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, event->phase())
                          .Bind(2, event->progress())
                          .Bind(3, event->job_id())
                          .Bind(4, StateName(v1::Job::RUNNING))
                          .Run());
  if (db_->Changes() == 0) {
    return Status::FailedPrecondition("job " + event->job_id() + " is not running");
  }
  stmt = Statement();
  int64_t sequence = 0;
  PBA_RETURN_IF_ERROR(NextSequence(event->job_id(), event->sequence(), &sequence));
  event->set_sequence(sequence);
  event->set_state(v1::Job::RUNNING);
  PBA_RETURN_IF_ERROR(InsertEvent(*event));
  return transaction.Commit();
}

Status JobStore::FinishRun(const std::string& id, int64_t sequence, const RunOutcome& outcome,
                           v1::JobEvent* event) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  bool changed = false;
  PBA_RETURN_IF_ERROR(Transition(id, v1::Job::RUNNING, outcome.state, &changed));
  if (!changed) return Status::FailedPrecondition("job " + id + " is not running");
  const bool succeeded = outcome.state == v1::Job::SUCCEEDED;
  Statement stmt;
  if (succeeded) {
    PBA_RETURN_IF_ERROR(db_->Prepare(
        "UPDATE jobs SET end_time_us = ?, error = ?, summary = ?, progress = 1 WHERE id = ?",
        &stmt));
    stmt.Bind(1, NowMicros()).Bind(2, outcome.error);
    stmt.BindBlob(3, outcome.summary.SerializeAsString()).Bind(4, id);
    if (!outcome.snapshot.project().empty()) {
      PBA_RETURN_IF_ERROR(stmt.Run());
      PBA_RETURN_IF_ERROR(
          db_->Prepare("UPDATE jobs SET snapshot_project = ?, snapshot = ? WHERE id = ?", &stmt));
      stmt.Bind(1, outcome.snapshot.project()).Bind(2, outcome.snapshot.snapshot()).Bind(3, id);
    }
  } else {
    // A failed run keeps the phase and progress it reached: they tell where it broke.
    PBA_RETURN_IF_ERROR(db_->Prepare(
        "UPDATE jobs SET end_time_us = ?, error = ?, summary = NULL WHERE id = ?", &stmt));
    stmt.Bind(1, NowMicros()).Bind(2, outcome.error).Bind(3, id);
  }
  PBA_RETURN_IF_ERROR(stmt.Run());
  PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM result_files WHERE job_id = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Run());
  for (const v1::ResultFile& file : outcome.files) {
    PBA_RETURN_IF_ERROR(db_->Prepare(
        "INSERT INTO result_files (job_id, name, size, sha256) VALUES (?, ?, ?, ?)", &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, id)
                            .Bind(2, file.name())
                            .Bind(3, file.size_bytes())
                            .Bind(4, file.sha256())
                            .Run());
  }
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT phase, progress FROM jobs WHERE id = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Step(&row));
  const std::string phase = stmt.ColumnText(0);
  const double progress = stmt.ColumnDouble(1);
  stmt = Statement();
  int64_t next = 0;
  PBA_RETURN_IF_ERROR(NextSequence(id, sequence, &next));
  *event = MakeEvent(id, next, outcome.state, phase, progress, outcome.message);
  PBA_RETURN_IF_ERROR(InsertEvent(*event));
  return transaction.Commit();
}

Status JobStore::RequeueRun(const std::string& id, int64_t sequence, const std::string& message,
                            v1::JobEvent* event) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  bool changed = false;
  PBA_RETURN_IF_ERROR(Transition(id, v1::Job::RUNNING, v1::Job::QUEUED, &changed));
  if (!changed) return Status::FailedPrecondition("job " + id + " is not running");
  Statement stmt;
  // A scheduler's job is over when its PBA job goes back to the queue: the
  // next run is a new one.
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "UPDATE jobs SET phase = '', progress = 0, scheduler_job = '', scheduler_state = '', "
      "scheduler_reason = '', scheduler_node = '' WHERE id = ?",
      &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Run());
  stmt = Statement();
  int64_t next = 0;
  PBA_RETURN_IF_ERROR(NextSequence(id, sequence, &next));
  *event = MakeEvent(id, next, v1::Job::QUEUED, "", 0, message);
  PBA_RETURN_IF_ERROR(InsertEvent(*event));
  return transaction.Commit();
}

Status JobStore::ExpireResults(int64_t ended_before_us, const std::string& note,
                               std::vector<std::string>* ids) {
  std::lock_guard lock(mutex_);
  ids->clear();
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT id FROM jobs WHERE end_time_us < ? AND state IN (?, ?, ?) AND EXISTS "
                   "(SELECT 1 FROM result_files WHERE job_id = jobs.id) ORDER BY number",
                   &stmt));
  stmt.Bind(1, ended_before_us)
      .Bind(2, StateName(v1::Job::SUCCEEDED))
      .Bind(3, StateName(v1::Job::FAILED))
      .Bind(4, StateName(v1::Job::CANCELLED));
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ids->push_back(stmt.ColumnText(0));
  }
  stmt = Statement();
  for (const std::string& id : *ids) {
    PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM result_files WHERE job_id = ?", &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Run());
    PBA_RETURN_IF_ERROR(db_->Prepare(
        "UPDATE jobs SET error = CASE WHEN error = '' THEN ? ELSE error || '; ' || ? END "
        "WHERE id = ?",
        &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, note).Bind(2, note).Bind(3, id).Run());
  }
  stmt = Statement();
  return transaction.Commit();
}

Status JobStore::ClaimForScheduler(v1::Job* job, bool* claimed) {
  std::lock_guard lock(mutex_);
  *claimed = false;
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  std::string id;
  PBA_RETURN_IF_ERROR(NextQueued(&id));
  if (id.empty()) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "UPDATE jobs SET scheduler_job = ?, scheduler_state = '', scheduler_reason = '', "
      "scheduler_node = '' WHERE id = ?",
      &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, kSubmitting).Bind(2, id).Run());
  stmt = Statement();
  bool found = false;
  PBA_RETURN_IF_ERROR(LoadJob(id, JobView::kFull, job, &found));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  *claimed = found;
  return Status::Ok();
}

Status JobStore::RecordSchedulerJob(const std::string& id, const v1::SchedulerJob& scheduler,
                                    const std::string& message, v1::JobEvent* event) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE jobs SET scheduler_job = ?, scheduler_state = ?, scheduler_reason = ?, "
                   "scheduler_node = ? WHERE id = ? AND state IN (?, ?)",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, scheduler.job_id())
                          .Bind(2, scheduler.state())
                          .Bind(3, scheduler.reason())
                          .Bind(4, scheduler.node())
                          .Bind(5, id)
                          .Bind(6, StateName(v1::Job::QUEUED))
                          .Bind(7, StateName(v1::Job::RUNNING))
                          .Run());
  if (db_->Changes() == 0) return Status::FailedPrecondition("job " + id + " has ended");
  stmt = Statement();
  event->Clear();
  if (!message.empty()) {
    PBA_RETURN_IF_ERROR(
        db_->Prepare("SELECT state, phase, progress FROM jobs WHERE id = ?", &stmt));
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Step(&row));
    const v1::Job::State state = ParseState(stmt.ColumnText(0));
    const std::string phase = stmt.ColumnText(1);
    const double progress = stmt.ColumnDouble(2);
    stmt = Statement();
    int64_t sequence = 0;
    PBA_RETURN_IF_ERROR(NextSequence(id, 1, &sequence));
    *event = MakeEvent(id, sequence, state, phase, progress, message);
    PBA_RETURN_IF_ERROR(InsertEvent(*event));
  }
  return transaction.Commit();
}

Status JobStore::StartScheduled(const std::string& id, const std::string& message, v1::Job* job,
                                v1::JobEvent* event, bool* started) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  PBA_RETURN_IF_ERROR(Transition(id, v1::Job::QUEUED, v1::Job::RUNNING, started));
  if (!*started) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE jobs SET attempts = attempts + 1, start_time_us = ?, "
                   "end_time_us = NULL, phase = '', progress = 0, error = '' WHERE id = ?",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, NowMicros()).Bind(2, id).Run());
  stmt = Statement();
  bool found = false;
  PBA_RETURN_IF_ERROR(LoadJob(id, JobView::kFull, job, &found));
  int64_t sequence = 0;
  PBA_RETURN_IF_ERROR(NextSequence(id, 1, &sequence));
  *event = MakeEvent(id, sequence, v1::Job::RUNNING, "", 0,
                     "started (attempt " + std::to_string(job->attempts()) + ")" +
                         (message.empty() ? "" : ", " + message));
  PBA_RETURN_IF_ERROR(InsertEvent(*event));
  return transaction.Commit();
}

Status JobStore::ReleaseToQueue(const std::string& id) {
  std::lock_guard lock(mutex_);
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "UPDATE jobs SET scheduler_job = '', scheduler_state = '', scheduler_reason = '', "
      "scheduler_node = '' WHERE id = ? AND state = ?",
      &stmt));
  return stmt.Bind(1, id).Bind(2, StateName(v1::Job::QUEUED)).Run();
}

Status JobStore::ListScheduled(std::vector<v1::Job>* jobs) {
  std::lock_guard lock(mutex_);
  jobs->clear();
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(std::string("SELECT ") + kJobColumns +
                                       " FROM jobs WHERE scheduler_job != '' AND state IN (?, ?) "
                                       "ORDER BY number",
                                   &stmt));
  stmt.Bind(1, StateName(v1::Job::QUEUED)).Bind(2, StateName(v1::Job::RUNNING));
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ReadJobRow(stmt, JobView::kFull, &jobs->emplace_back());
  }
  return Status::Ok();
}

Status JobStore::RequeueInterrupted(const std::string& message, std::vector<v1::JobEvent>* events) {
  std::lock_guard lock(mutex_);
  events->clear();
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  std::vector<std::string> ids;
  Statement stmt;
  // A job in a scheduler's hands runs on without the server.
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT id FROM jobs WHERE state = ? AND scheduler_job = '' ORDER BY number", &stmt));
  stmt.Bind(1, StateName(v1::Job::RUNNING));
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ids.push_back(stmt.ColumnText(0));
  }
  stmt = Statement();
  for (const std::string& id : ids) {
    bool changed = false;
    PBA_RETURN_IF_ERROR(Transition(id, v1::Job::RUNNING, v1::Job::QUEUED, &changed));
    PBA_RETURN_IF_ERROR(
        db_->Prepare("UPDATE jobs SET phase = '', progress = 0 WHERE id = ?", &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Run());
    stmt = Statement();
    int64_t sequence = 0;
    PBA_RETURN_IF_ERROR(NextSequence(id, 1, &sequence));
    events->push_back(MakeEvent(id, sequence, v1::Job::QUEUED, "", 0, message));
    PBA_RETURN_IF_ERROR(InsertEvent(events->back()));
  }
  return transaction.Commit();
}

}  // namespace pba
