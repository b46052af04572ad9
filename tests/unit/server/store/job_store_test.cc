#include "store/job_store.h"

#include <gtest/gtest.h>

#include <set>

#include "store/atlas_store.h"
#include "store/database.h"
#include "store/job_id.h"
#include "store/migrations.h"
#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;
using testing::ValidScene;

class JobStoreTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(JobStore::Open(db_path(), &store_).ok()); }
  std::filesystem::path db_path() const { return dir_.path() / "pba.db"; }

  v1::Job Create(const std::string& name, const std::string& request_id = "") {
    v1::Job job;
    bool created = false;
    EXPECT_TRUE(store_->CreateJob(ValidScene(name), request_id, "alice", &job, &created).ok());
    return job;
  }

  std::vector<v1::JobEvent> Events(const std::string& id) {
    std::vector<v1::JobEvent> events;
    EXPECT_TRUE(store_->ListEvents(id, 0, &events).ok());
    return events;
  }

  v1::Job Get(const std::string& id) {
    v1::Job job;
    bool found = false;
    EXPECT_TRUE(store_->GetJob(id, JobView::kFull, &job, &found).ok());
    EXPECT_TRUE(found);
    return job;
  }

  TempDir dir_;
  std::unique_ptr<JobStore> store_;
};

TEST_F(JobStoreTest, CreateAndGet) {
  v1::Job created = Create("cube");
  EXPECT_TRUE(IsWellFormedJobId(created.id())) << created.id();
  EXPECT_EQ(created.state(), v1::Job::QUEUED);
  EXPECT_EQ(created.name(), "cube");
  EXPECT_EQ(created.attempts(), 0);

  v1::Job got = Get(created.id());
  EXPECT_EQ(got.scene().SerializeAsString(), ValidScene("cube").SerializeAsString());
  EXPECT_TRUE(got.has_create_time());
  EXPECT_FALSE(got.has_start_time());

  std::vector<v1::JobEvent> events = Events(created.id());
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].sequence(), 1);
  EXPECT_EQ(events[0].state(), v1::Job::QUEUED);

  bool found = true;
  v1::Job missing;
  ASSERT_TRUE(store_->GetJob("j0000000000", JobView::kBasic, &missing, &found).ok());
  EXPECT_FALSE(found);
}

TEST_F(JobStoreTest, EmptyNameBecomesUnnamed) { EXPECT_EQ(Create("").name(), "unnamed"); }

TEST_F(JobStoreTest, RepeatedRequestIdReturnsTheSameJob) {
  v1::Job first;
  bool created = false;
  ASSERT_TRUE(store_->CreateJob(ValidScene("a"), "req-1", "alice", &first, &created).ok());
  EXPECT_TRUE(created);
  v1::Job second;
  ASSERT_TRUE(store_->CreateJob(ValidScene("b"), "req-1", "alice", &second, &created).ok());
  EXPECT_FALSE(created);
  EXPECT_EQ(second.id(), first.id());
  EXPECT_EQ(second.name(), "a");
  EXPECT_EQ(second.owner(), "alice");
  // Another user's request id is not theirs: refused, nothing stored.
  v1::Job other;
  const Status refused = store_->CreateJob(ValidScene("e"), "req-1", "bob", &other, &created);
  EXPECT_EQ(refused.code(), Status::Code::kAlreadyExists) << refused.ToString();
  EXPECT_FALSE(created);

  std::vector<v1::Job> jobs;
  std::string token;
  ASSERT_TRUE(store_->ListJobs(0, "", &jobs, &token).ok());
  EXPECT_EQ(jobs.size(), 1u);
  // Jobs without a request_id never collide with each other.
  Create("c");
  Create("d");
  ASSERT_TRUE(store_->ListJobs(0, "", &jobs, &token).ok());
  EXPECT_EQ(jobs.size(), 3u);
}

TEST_F(JobStoreTest, StateTransitionsWriteEvents) {
  const v1::Job job = Create("cube");
  v1::Job claimed;
  v1::JobEvent started;
  bool ok = false;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &started, &ok).ok());
  ASSERT_TRUE(ok);
  EXPECT_EQ(claimed.id(), job.id());
  EXPECT_EQ(claimed.state(), v1::Job::RUNNING);
  EXPECT_EQ(claimed.attempts(), 1);
  EXPECT_TRUE(claimed.has_start_time());
  EXPECT_EQ(started.sequence(), 2);
  EXPECT_EQ(started.message(), "started (attempt 1)");

  // Nothing else is queued.
  v1::Job none;
  ASSERT_TRUE(store_->ClaimNextQueued(&none, &started, &ok).ok());
  EXPECT_FALSE(ok);

  v1::JobEvent progress;
  progress.set_job_id(job.id());
  progress.set_sequence(5);  // 3 and 4 were live-only events
  progress.set_phase("solve");
  progress.set_progress(0.5);
  ASSERT_TRUE(store_->RecordProgress(&progress).ok());
  EXPECT_EQ(progress.sequence(), 5);
  EXPECT_EQ(Get(job.id()).phase(), "solve");
  EXPECT_DOUBLE_EQ(Get(job.id()).progress(), 0.5);

  RunOutcome outcome;
  outcome.state = v1::Job::SUCCEEDED;
  outcome.message = "succeeded";
  outcome.summary.set_scene_name("cube");
  v1::ResultFile file;
  file.set_name("result.h5");
  file.set_size_bytes(6);
  file.set_sha256("abc");
  outcome.files.push_back(file);
  v1::JobEvent finished;
  // A stale sequence is raised above the stored ones.
  ASSERT_TRUE(store_->FinishRun(job.id(), 3, outcome, &finished).ok());
  EXPECT_EQ(finished.sequence(), 6);
  EXPECT_EQ(finished.state(), v1::Job::SUCCEEDED);

  const v1::Job done = Get(job.id());
  EXPECT_EQ(done.state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(done.summary().scene_name(), "cube");
  EXPECT_DOUBLE_EQ(done.progress(), 1.0);
  EXPECT_TRUE(done.has_end_time());
  ASSERT_EQ(done.result_files_size(), 1);
  EXPECT_EQ(done.result_files(0).sha256(), "abc");
  v1::ResultFile got_file;
  bool found = false;
  ASSERT_TRUE(store_->GetResultFile(job.id(), "result.h5", &got_file, &found).ok());
  EXPECT_TRUE(found);
  EXPECT_EQ(got_file.size_bytes(), 6);
  ASSERT_TRUE(store_->GetResultFile(job.id(), "../pba.db", &got_file, &found).ok());
  EXPECT_FALSE(found);

  std::vector<v1::JobEvent> events = Events(job.id());
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[0].state(), v1::Job::QUEUED);
  EXPECT_EQ(events[1].state(), v1::Job::RUNNING);
  EXPECT_EQ(events[2].sequence(), 5);
  EXPECT_EQ(events[3].state(), v1::Job::SUCCEEDED);
  std::vector<v1::JobEvent> after;
  ASSERT_TRUE(store_->ListEvents(job.id(), 2, &after).ok());
  EXPECT_EQ(after.size(), 2u);

  // A finished job cannot be finished, re-queued or cancelled again.
  EXPECT_FALSE(store_->FinishRun(job.id(), 7, outcome, &finished).ok());
  EXPECT_FALSE(store_->RequeueRun(job.id(), 7, "again", &finished).ok());
  bool cancelled = true;
  ASSERT_TRUE(store_->CancelQueued(job.id(), "no", &finished, &cancelled).ok());
  EXPECT_FALSE(cancelled);
  EXPECT_EQ(Events(job.id()).size(), 4u);
}

TEST_F(JobStoreTest, FailedRunKeepsItsProgressAndError) {
  const v1::Job job = Create("cube");
  v1::Job claimed;
  v1::JobEvent event;
  bool ok = false;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  event.set_phase("assemble");
  event.set_progress(0.3);
  event.set_sequence(event.sequence() + 1);
  ASSERT_TRUE(store_->RecordProgress(&event).ok());
  RunOutcome outcome;
  outcome.state = v1::Job::FAILED;
  outcome.error = "pba-solve exited with code 3";
  outcome.message = outcome.error;
  ASSERT_TRUE(store_->FinishRun(job.id(), event.sequence() + 1, outcome, &event).ok());
  const v1::Job failed = Get(job.id());
  EXPECT_EQ(failed.state(), v1::Job::FAILED);
  EXPECT_EQ(failed.error(), "pba-solve exited with code 3");
  EXPECT_EQ(failed.phase(), "assemble");
  EXPECT_FALSE(failed.has_summary());
  EXPECT_EQ(event.phase(), "assemble");
}

TEST_F(JobStoreTest, CancelQueued) {
  const v1::Job job = Create("cube");
  v1::JobEvent event;
  bool cancelled = false;
  ASSERT_TRUE(
      store_->CancelQueued(job.id(), "cancelled before it started", &event, &cancelled).ok());
  EXPECT_TRUE(cancelled);
  EXPECT_EQ(event.sequence(), 2);
  const v1::Job got = Get(job.id());
  EXPECT_EQ(got.state(), v1::Job::CANCELLED);
  EXPECT_EQ(got.error(), "cancelled before it started");
  // A cancelled job is not claimed.
  v1::Job claimed;
  bool ok = true;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  EXPECT_FALSE(ok);
}

TEST_F(JobStoreTest, ClaimsOldestFirst) {
  const v1::Job first = Create("first");
  Create("second");
  v1::Job claimed;
  v1::JobEvent event;
  bool ok = false;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  EXPECT_EQ(claimed.id(), first.id());
}

TEST_F(JobStoreTest, PaginatesNewestFirst) {
  std::vector<std::string> ids;
  for (int i = 0; i < 7; ++i) ids.push_back(Create("job" + std::to_string(i)).id());
  std::vector<std::string> listed;
  std::string token;
  int pages = 0;
  do {
    std::vector<v1::Job> jobs;
    std::string next;
    ASSERT_TRUE(store_->ListJobs(3, token, &jobs, &next).ok());
    EXPECT_LE(jobs.size(), 3u);
    for (const v1::Job& job : jobs) {
      listed.push_back(job.id());
      EXPECT_FALSE(job.has_scene());
    }
    token = next;
    ++pages;
  } while (!token.empty() && pages < 10);
  EXPECT_EQ(pages, 3);
  ASSERT_EQ(listed.size(), ids.size());
  for (size_t i = 0; i < ids.size(); ++i) EXPECT_EQ(listed[i], ids[ids.size() - 1 - i]);

  // Exactly one full page: no next token.
  std::vector<v1::Job> jobs;
  std::string next;
  ASSERT_TRUE(store_->ListJobs(7, "", &jobs, &next).ok());
  EXPECT_EQ(jobs.size(), 7u);
  EXPECT_TRUE(next.empty());
  // Default and maximum page sizes.
  ASSERT_TRUE(store_->ListJobs(0, "", &jobs, &next).ok());
  EXPECT_EQ(jobs.size(), 7u);
  ASSERT_TRUE(store_->ListJobs(100000, "", &jobs, &next).ok());
  EXPECT_EQ(jobs.size(), 7u);
}

TEST_F(JobStoreTest, RejectsBadPageTokens) {
  Create("a");
  std::vector<v1::Job> jobs;
  std::string next;
  for (const std::string token :
       {"garbage", "zz", "6a6f62732e76313a", "6a6f62732e76313a2d31", "0"}) {
    const Status status = store_->ListJobs(10, token, &jobs, &next);
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << token;
    EXPECT_EQ(status.field(), "page_token");
  }
  EXPECT_EQ(store_->ListJobs(-1, "", &jobs, &next).code(), Status::Code::kInvalidArgument);
}

TEST_F(JobStoreTest, ReopeningKeepsDataAndRequeuesRunningJobs) {
  const v1::Job running = Create("running");
  const v1::Job queued = Create("queued");
  v1::Job claimed;
  v1::JobEvent event;
  bool ok = false;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  ASSERT_EQ(claimed.id(), running.id());
  store_.reset();

  ASSERT_TRUE(JobStore::Open(db_path(), &store_).ok());
  EXPECT_EQ(Get(queued.id()).state(), v1::Job::QUEUED);
  EXPECT_EQ(Get(running.id()).state(), v1::Job::RUNNING);
  std::vector<v1::JobEvent> requeued;
  ASSERT_TRUE(store_->RequeueInterrupted("re-queued: test", &requeued).ok());
  ASSERT_EQ(requeued.size(), 1u);
  EXPECT_EQ(requeued[0].job_id(), running.id());
  const v1::Job back = Get(running.id());
  EXPECT_EQ(back.state(), v1::Job::QUEUED);
  EXPECT_EQ(back.attempts(), 1);
  std::vector<v1::JobEvent> events = Events(running.id());
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[2].state(), v1::Job::QUEUED);
  EXPECT_EQ(events[2].message(), "re-queued: test");

  // Re-claimed, it is attempt 2.
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  EXPECT_EQ(claimed.id(), running.id());
  EXPECT_EQ(claimed.attempts(), 2);
}

TEST_F(JobStoreTest, RecordsTheSchemaVersion) {
  int version = 0;
  ASSERT_TRUE(store_->SchemaVersion(&version).ok());
  EXPECT_EQ(version, LatestSchemaVersion());
  store_.reset();

  // Reopening does not apply migrations again.
  ASSERT_TRUE(JobStore::Open(db_path(), &store_).ok());
  store_.reset();
  std::unique_ptr<Database> db;
  ASSERT_TRUE(Database::Open(db_path(), &db).ok());
  Statement stmt;
  ASSERT_TRUE(db->Prepare("SELECT COUNT(*), MAX(version) FROM schema_version", &stmt).ok());
  bool row = false;
  ASSERT_TRUE(stmt.Step(&row).ok());
  ASSERT_TRUE(row);
  EXPECT_EQ(stmt.ColumnInt(0), LatestSchemaVersion());
  EXPECT_EQ(stmt.ColumnInt(1), LatestSchemaVersion());
  stmt = Statement();

  // A database from a newer server is refused.
  ASSERT_TRUE(db->Exec("INSERT INTO schema_version VALUES (999, 'future', 0)").ok());
  db.reset();
  const Status status = JobStore::Open(db_path(), &store_);
  EXPECT_EQ(status.code(), Status::Code::kFailedPrecondition);
}

TEST_F(JobStoreTest, UsesWalAndForeignKeys) {
  std::unique_ptr<Database> db;
  ASSERT_TRUE(Database::Open(db_path(), &db).ok());
  Statement stmt;
  ASSERT_TRUE(db->Prepare("PRAGMA journal_mode", &stmt).ok());
  bool row = false;
  ASSERT_TRUE(stmt.Step(&row).ok());
  EXPECT_EQ(stmt.ColumnText(0), "wal");
  stmt = Statement();
  // An event for a job that does not exist violates the foreign key.
  EXPECT_FALSE(db->Exec("INSERT INTO job_events (job_id, sequence, time_us, state) "
                        "VALUES ('nope', 1, 0, 'QUEUED')")
                   .ok());
}

TEST(JobIdTest, ShortUniqueAndWellFormed) {
  std::set<std::string> ids;
  for (int i = 0; i < 1000; ++i) {
    const std::string id = NewJobId();
    EXPECT_TRUE(IsWellFormedJobId(id)) << id;
    ids.insert(id);
  }
  EXPECT_EQ(ids.size(), 1000u);
  EXPECT_FALSE(IsWellFormedJobId("j123"));
  EXPECT_FALSE(IsWellFormedJobId("../../etc"));
  EXPECT_FALSE(IsWellFormedJobId("jABCDEF0123"));
}

// The atlas store opens its own connection to the same pba.db; the
// migrations are shared, so either store may open the file first.
TEST_F(JobStoreTest, SharesTheDatabaseWithTheAtlasStore) {
  const v1::Job job = Create("cube");
  std::unique_ptr<AtlasStore> atlas;
  ASSERT_TRUE(AtlasStore::Open(db_path().parent_path(), &atlas).ok());
  std::string token;
  ASSERT_TRUE(atlas->CreateUser("alice", &token).ok());
  ASSERT_TRUE(atlas->CreateProject("alice", "atlas").ok());
  Create("sphere");
  EXPECT_EQ(Get(job.id()).name(), "cube");
  std::vector<v1::Job> jobs;
  std::string next;
  ASSERT_TRUE(store_->ListJobs(0, "", &jobs, &next).ok());
  EXPECT_EQ(jobs.size(), 2u);
  std::string user;
  ASSERT_TRUE(atlas->Authenticate(token, &user).ok());
  EXPECT_EQ(user, "alice");
}

TEST_F(JobStoreTest, ClaimsHighestPriorityFirstThenOldest) {
  NewJob low, high, high_later;
  low.scene = ValidScene("low");
  high.scene = ValidScene("high");
  high_later.scene = ValidScene("high later");
  high.priority = high_later.priority = 10;
  low.priority = -5;
  v1::Job job;
  bool created = false;
  for (NewJob* request : {&low, &high, &high_later}) {
    request->owner = "alice";
    ASSERT_TRUE(store_->CreateJob(*request, &job, &created).ok());
  }
  Create("normal");
  std::vector<std::string> order;
  for (int i = 0; i < 4; ++i) {
    v1::Job claimed;
    v1::JobEvent event;
    bool ok = false;
    ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
    ASSERT_TRUE(ok);
    order.push_back(claimed.name());
  }
  EXPECT_EQ(order, (std::vector<std::string>{"high", "high later", "normal", "low"}));
}

TEST_F(JobStoreTest, KeepsSnapshotImportPriorityAndTimeLimit) {
  v1::AtlasImport import;
  import.set_project("atlas");
  import.set_source(v1::AtlasImport::PLATES);
  NewJob request;
  request.owner = "alice";
  request.priority = 3;
  request.timeout_s = 60;
  request.atlas_import = &import;
  v1::Job job;
  bool created = false;
  ASSERT_TRUE(store_->CreateJob(request, &job, &created).ok());
  EXPECT_EQ(job.name(), "import into atlas");
  EXPECT_EQ(job.priority(), 3);
  EXPECT_EQ(job.timeout_s(), 60);
  EXPECT_EQ(job.atlas_import().source(), v1::AtlasImport::PLATES);

  NewJob on_snapshot;
  on_snapshot.owner = "bob";
  on_snapshot.scene = ValidScene("on a snapshot");
  on_snapshot.snapshot.set_project("atlas");
  on_snapshot.snapshot.set_snapshot("7");
  ASSERT_TRUE(store_->CreateJob(on_snapshot, &job, &created).ok());
  const v1::Job stored = Get(job.id());
  EXPECT_EQ(stored.snapshot().project(), "atlas");
  EXPECT_EQ(stored.snapshot().snapshot(), "7");
  EXPECT_FALSE(stored.has_atlas_import());
  // The list view carries them too.
  std::vector<v1::Job> jobs;
  std::string next;
  ASSERT_TRUE(store_->ListJobs(0, "", &jobs, &next).ok());
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0].snapshot().snapshot(), "7");
  EXPECT_EQ(jobs[1].priority(), 3);
}

TEST_F(JobStoreTest, AFailingBeforeCommitStoresNothing) {
  NewJob request;
  request.owner = "alice";
  request.scene = ValidScene("never");
  std::string seen_id;
  request.before_commit = [&](const std::string& id) {
    seen_id = id;
    return Status::Io("the disk is full");
  };
  v1::Job job;
  bool created = false;
  const Status status = store_->CreateJob(request, &job, &created);
  EXPECT_EQ(status.code(), Status::Code::kIo);
  EXPECT_FALSE(created);
  EXPECT_TRUE(IsWellFormedJobId(seen_id));
  bool found = true;
  ASSERT_TRUE(store_->GetJob(seen_id, JobView::kBasic, &job, &found).ok());
  EXPECT_FALSE(found);
}

// A user's open jobs (queued or running) are bounded; a repeated request
// id still finds its job, another user is not held back, and a job that
// ends makes room.
TEST_F(JobStoreTest, BoundsTheJobsOneUserHasOpen) {
  const auto submit = [&](const std::string& name, const std::string& owner,
                          const std::string& request_id, v1::Job* job) {
    NewJob request;
    request.scene = ValidScene(name);
    request.owner = owner;
    request.request_id = request_id;
    request.max_open = 2;
    bool created = false;
    return store_->CreateJob(request, job, &created);
  };
  v1::Job first, second, third;
  ASSERT_TRUE(submit("a", "alice", "key-a", &first).ok());
  v1::Job claimed;
  bool ok = false;
  v1::JobEvent started;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &started, &ok).ok());
  ASSERT_TRUE(ok);                                           // one RUNNING
  ASSERT_TRUE(submit("b", "alice", "key-b", &second).ok());  // and one QUEUED
  const Status refused = submit("c", "alice", "key-c", &third);
  EXPECT_EQ(refused.code(), Status::Code::kResourceExhausted) << refused.ToString();
  EXPECT_NE(refused.ToString().find("already has 2 jobs queued or running"), std::string::npos)
      << refused.ToString();
  EXPECT_NE(refused.ToString().find("--max-open-jobs"), std::string::npos) << refused.ToString();
  v1::Job again;
  ASSERT_TRUE(submit("b", "alice", "key-b", &again).ok());
  EXPECT_EQ(again.id(), second.id());
  v1::Job bobs;
  EXPECT_TRUE(submit("d", "bob", "", &bobs).ok());
  v1::JobEvent cancelled;
  bool was_queued = false;
  ASSERT_TRUE(store_->CancelQueued(second.id(), "no", &cancelled, &was_queued).ok());
  ASSERT_TRUE(was_queued);
  EXPECT_TRUE(submit("c", "alice", "key-c", &third).ok());
  std::vector<v1::Job> jobs;
  std::string token;
  ASSERT_TRUE(store_->ListJobs(0, "", &jobs, &token).ok());
  EXPECT_EQ(jobs.size(), 4u);
}

TEST_F(JobStoreTest, FindsAJobByItsOwnersRequestId) {
  const v1::Job job = Create("cube", "key-1");
  v1::Job found_job;
  bool found = false;
  ASSERT_TRUE(store_->FindByRequestId("key-1", "alice", &found_job, &found).ok());
  EXPECT_TRUE(found);
  EXPECT_EQ(found_job.id(), job.id());
  ASSERT_TRUE(store_->FindByRequestId("key-2", "alice", &found_job, &found).ok());
  EXPECT_FALSE(found);
  EXPECT_EQ(store_->FindByRequestId("key-1", "bob", &found_job, &found).code(),
            Status::Code::kAlreadyExists);
}

TEST_F(JobStoreTest, ExpiresTheFilesOfJobsThatEndedLongAgo) {
  const v1::Job job = Create("old");
  v1::Job claimed;
  v1::JobEvent event;
  bool ok = false;
  ASSERT_TRUE(store_->ClaimNextQueued(&claimed, &event, &ok).ok());
  RunOutcome outcome;
  outcome.state = v1::Job::SUCCEEDED;
  outcome.snapshot.set_project("atlas");
  outcome.snapshot.set_snapshot("4");
  v1::ResultFile file;
  file.set_name("result.h5");
  file.set_size_bytes(6);
  file.set_sha256("00");
  outcome.files.push_back(file);
  ASSERT_TRUE(store_->FinishRun(job.id(), event.sequence() + 1, outcome, &event).ok());
  EXPECT_EQ(Get(job.id()).snapshot().snapshot(), "4");
  ASSERT_EQ(Get(job.id()).result_files_size(), 1);

  std::vector<std::string> ids;
  // Ended after the cutoff: kept.
  ASSERT_TRUE(store_->ExpireResults(0, "removed", &ids).ok());
  EXPECT_TRUE(ids.empty());
  ASSERT_TRUE(store_->ExpireResults(INT64_MAX, "removed after 30 days", &ids).ok());
  EXPECT_EQ(ids, (std::vector<std::string>{job.id()}));
  const v1::Job expired = Get(job.id());
  EXPECT_EQ(expired.state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(expired.result_files_size(), 0);
  EXPECT_EQ(expired.error(), "removed after 30 days");
  // Once is enough.
  ASSERT_TRUE(store_->ExpireResults(INT64_MAX, "again", &ids).ok());
  EXPECT_TRUE(ids.empty());
}

}  // namespace
}  // namespace pba

namespace pba {
namespace {

// Jobs in a cluster scheduler's hands: claimed without leaving the queue,
// named, started when the scheduler starts them, kept RUNNING across a
// restart, and invisible to the local claim.
TEST_F(JobStoreTest, JobsInASchedulersHands) {
  const v1::Job first = Create("first");
  const v1::Job second = Create("second");
  v1::Job claimed;
  bool got = false;
  ASSERT_TRUE(store_->ClaimForScheduler(&claimed, &got).ok());
  ASSERT_TRUE(got);
  EXPECT_EQ(claimed.id(), first.id());
  EXPECT_EQ(claimed.state(), v1::Job::QUEUED);
  EXPECT_EQ(claimed.scheduler().job_id(), "submitting");
  EXPECT_EQ(Events(first.id()).size(), 1u);  // no event for the claim
  // The local claim and a second scheduler claim pass it by.
  v1::Job other;
  v1::JobEvent event;
  ASSERT_TRUE(store_->ClaimForScheduler(&other, &got).ok());
  EXPECT_EQ(other.id(), second.id());
  ASSERT_TRUE(store_->ReleaseToQueue(second.id()).ok());
  EXPECT_FALSE(Get(second.id()).has_scheduler());
  ASSERT_TRUE(store_->ClaimNextQueued(&other, &event, &got).ok());
  ASSERT_TRUE(got);
  EXPECT_EQ(other.id(), second.id());

  v1::SchedulerJob scheduler;
  scheduler.set_system("slurm");
  scheduler.set_job_id("41");
  scheduler.set_state("PENDING");
  scheduler.set_reason("Resources");
  ASSERT_TRUE(store_->RecordSchedulerJob(first.id(), scheduler, "submitted", &event).ok());
  EXPECT_EQ(event.state(), v1::Job::QUEUED);
  EXPECT_EQ(event.message(), "submitted");
  v1::Job now = Get(first.id());
  EXPECT_EQ(now.scheduler().system(), "slurm");
  EXPECT_EQ(now.scheduler().job_id(), "41");
  EXPECT_EQ(now.scheduler().reason(), "Resources");
  // Without a message: the state kept, no event.
  scheduler.set_reason("Priority");
  ASSERT_TRUE(store_->RecordSchedulerJob(first.id(), scheduler, "", &event).ok());
  EXPECT_EQ(Get(first.id()).scheduler().reason(), "Priority");
  EXPECT_EQ(Events(first.id()).size(), 2u);

  bool started = false;
  ASSERT_TRUE(
      store_->StartScheduled(first.id(), "Slurm job 41 on n1", &now, &event, &started).ok());
  ASSERT_TRUE(started);
  EXPECT_EQ(now.state(), v1::Job::RUNNING);
  EXPECT_EQ(now.attempts(), 1);
  EXPECT_EQ(event.message(), "started (attempt 1), Slurm job 41 on n1");
  ASSERT_TRUE(store_->StartScheduled(first.id(), "", &now, &event, &started).ok());
  EXPECT_FALSE(started);  // once

  std::vector<v1::Job> scheduled;
  ASSERT_TRUE(store_->ListScheduled(&scheduled).ok());
  ASSERT_EQ(scheduled.size(), 1u);
  EXPECT_EQ(scheduled[0].id(), first.id());

  // A restart re-queues the local run, not the scheduler's.
  store_.reset();
  ASSERT_TRUE(JobStore::Open(db_path(), &store_).ok());
  std::vector<v1::JobEvent> requeued;
  ASSERT_TRUE(store_->RequeueInterrupted("restart", &requeued).ok());
  ASSERT_EQ(requeued.size(), 1u);
  EXPECT_EQ(requeued[0].job_id(), second.id());
  EXPECT_EQ(Get(first.id()).state(), v1::Job::RUNNING);

  // Back in the queue, the scheduler's job is forgotten; a queued job fails
  // with its reason.
  ASSERT_TRUE(store_->RequeueRun(first.id(), 0, "re-queued: NODE_FAIL", &event).ok());
  EXPECT_FALSE(Get(first.id()).has_scheduler());
  bool ended = false;
  ASSERT_TRUE(store_->EndQueued(first.id(), v1::Job::FAILED, "refused", &event, &ended).ok());
  EXPECT_TRUE(ended);
  EXPECT_EQ(Get(first.id()).state(), v1::Job::FAILED);
  EXPECT_EQ(Get(first.id()).error(), "refused");
  // A job that ends while it is being handed over never had a Slurm job.
  ASSERT_TRUE(store_->ClaimForScheduler(&other, &got).ok());
  ASSERT_TRUE(got);
  ASSERT_TRUE(store_->CancelQueued(other.id(), "cancelled", &event, &ended).ok());
  EXPECT_TRUE(ended);
  EXPECT_FALSE(Get(other.id()).has_scheduler());
  // Nothing is recorded of a job that has ended.
  EXPECT_EQ(store_->RecordSchedulerJob(first.id(), scheduler, "late", &event).code(),
            Status::Code::kFailedPrecondition);
}

}  // namespace
}  // namespace pba
