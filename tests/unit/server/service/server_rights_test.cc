// The server's trust boundaries (issue 18) through a real channel to an
// in-process server with the fake pba-solve: who sees and cancels which job,
// users disabled while the server runs (their calls, open watches and
// queued jobs), members removed over the API (their open watches end),
// rights checked before an upload is parsed, a commit retried after a lost
// reply, plaintext only on loopback, and health per service.
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <thread>

#include "app/pba_server.h"
#include "core/sha256.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"
#include "service/atlas_service.h"
#include "service/job_service.h"
#include "store/atlas_store.h"
#include "unit/server/in_process_server.h"
#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;
using testing::WaitUntil;

constexpr char kContours[] =
    R"({"plates": [{"z_mm": 0, "polygons": [[[0, 0], [10, 0], [10, 10], [0, 10]]]}]})";

class ServerRightsTest : public testing::InProcessServerTest {
 protected:
  // alice (no server admin) owns project "atlas" with "Putamen" and
  // snapshot 1; bob and eve are in no project; admin is the server admin
  // of the first start.
  void SetUp() override {
    InProcessServerTest::SetUp();
    if (HasFatalFailure()) return;
    ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &users_).ok());
    ASSERT_TRUE(users_->CreateUser("alice", &alice_).ok());
    ASSERT_TRUE(users_->CreateUser("bob", &bob_).ok());
    ASSERT_TRUE(users_->CreateUser("eve", &eve_).ok());
    v1::CreateProjectRequest project;
    project.set_name("atlas");
    v1::Project created;
    ASSERT_TRUE(Call(alice_, [&](grpc::ClientContext* c) {
                  return atlas_->CreateProject(c, project, &created);
                }).ok());
    v1::CreateStructureRequest structure;
    structure.set_project("atlas");
    structure.set_name("Putamen");
    structure.set_format(v1::CONTOURS_JSON);
    structure.set_upload_id(Upload(alice_, kContours));
    v1::Revision revision;
    ASSERT_TRUE(Call(alice_, [&](grpc::ClientContext* c) {
                  return atlas_->CreateStructure(c, structure, &revision);
                }).ok());
    v1::CreateSnapshotRequest snapshot;
    snapshot.set_project("atlas");
    v1::Snapshot made;
    ASSERT_TRUE(Call(alice_, [&](grpc::ClientContext* c) {
                  return atlas_->CreateSnapshot(c, snapshot, &made);
                }).ok());
  }

  // A job of alice's on snapshot 1 of "atlas", the fake solver acting on
  // `name` (ok: succeeds with result.h5; slow: runs until cancelled).
  v1::Job SubmitOnSnapshot(const std::string& token, const std::string& name) {
    v1::SubmitJobRequest request;
    *request.mutable_scene() = testing::AtlasScene(name);
    request.mutable_snapshot()->set_project("atlas");
    request.mutable_snapshot()->set_snapshot("1");
    v1::Job job;
    const grpc::Status status =
        Call(token, [&](grpc::ClientContext* c) { return jobs_->SubmitJob(c, request, &job); });
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job;
  }

  grpc::Status Get(const std::string& token, const std::string& id, v1::Job* job) {
    v1::GetJobRequest request;
    request.set_id(id);
    return Call(token, [&](grpc::ClientContext* c) { return jobs_->GetJob(c, request, job); });
  }

  grpc::Status Cancel(const std::string& token, const std::string& id) {
    v1::CancelJobRequest request;
    request.set_id(id);
    v1::Job job;
    return Call(token, [&](grpc::ClientContext* c) { return jobs_->CancelJob(c, request, &job); });
  }

  grpc::Status Download(const std::string& token, const std::string& id, std::string* bytes) {
    grpc::ClientContext context;
    context.AddMetadata("authorization", "Bearer " + token);
    v1::DownloadResultRequest request;
    request.set_job_id(id);
    auto reader = jobs_->DownloadResult(&context, request);
    v1::DataChunk chunk;
    while (reader->Read(&chunk)) bytes->append(chunk.data());
    return reader->Finish();
  }

  grpc::Status Watch(const std::string& token, const std::string& id, std::atomic<int>* events) {
    grpc::ClientContext context;
    context.AddMetadata("authorization", "Bearer " + token);
    v1::WatchJobRequest request;
    request.set_id(id);
    auto reader = jobs_->WatchJob(&context, request);
    v1::JobEvent event;
    *events = 0;
    while (reader->Read(&event)) ++*events;
    return reader->Finish();
  }

  // The atlas event stream of project "atlas" (deadline 30 s, so a stream
  // that never ends fails the test instead of hanging it).
  grpc::Status AtlasWatch(const std::string& token, std::atomic<int>* events) {
    grpc::ClientContext context;
    context.AddMetadata("authorization", "Bearer " + token);
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    v1::WatchRequest request;
    request.set_project("atlas");
    auto reader = atlas_->Watch(&context, request);
    v1::AtlasEvent event;
    *events = 0;
    while (reader->Read(&event)) ++*events;
    return reader->Finish();
  }

  std::vector<std::string> ListIds(const std::string& token, int page_size = 0) {
    std::vector<std::string> ids;
    v1::ListJobsRequest request;
    request.set_page_size(page_size);
    do {
      v1::ListJobsResponse response;
      EXPECT_TRUE(Call(token, [&](grpc::ClientContext* c) {
                    return jobs_->ListJobs(c, request, &response);
                  }).ok());
      for (const v1::Job& job : response.jobs()) ids.push_back(job.id());
      request.set_page_token(response.next_page_token());
    } while (!request.page_token().empty());
    return ids;
  }

  // `user` removed from project "atlas" by the holder of `token`.
  grpc::Status RemoveMember(const std::string& token, const std::string& user,
                            v1::RemoveMemberResponse* response) {
    v1::RemoveMemberRequest request;
    request.set_project("atlas");
    request.set_user(user);
    return Call(token,
                [&](grpc::ClientContext* c) { return atlas_->RemoveMember(c, request, response); });
  }

  // A lock on "Putamen" of project "atlas", taken as `token`.
  grpc::Status LockPutamen(const std::string& token, v1::Lock* lock) {
    v1::AcquireLockRequest request;
    request.set_project("atlas");
    request.set_structure("Putamen");
    return Call(token,
                [&](grpc::ClientContext* c) { return atlas_->AcquireLock(c, request, lock); });
  }

  grpc::Status SetRole(const std::string& user, v1::Role role) {
    v1::SetRoleRequest request;
    request.set_project("atlas");
    request.set_user(user);
    request.set_role(role);
    v1::Member member;
    return Call(alice_,
                [&](grpc::ClientContext* c) { return atlas_->SetRole(c, request, &member); });
  }

  std::unique_ptr<AtlasStore> users_;  // the offline admin's view
  std::string alice_, bob_, eve_;
};

TEST_F(ServerRightsTest, AJobOnAProjectIsHiddenFromOutsidersAsIfItDidNotExist) {
  const v1::Job job = SubmitOnSnapshot(alice_, "ok");
  v1::Job got;
  ASSERT_TRUE(WaitUntil([&] {
    return Get(alice_, job.id(), &got).ok() && got.state() == v1::Job::SUCCEEDED;
  })) << got.error();

  // Word for word what an unknown id gets.
  v1::Job unknown_job;
  const grpc::Status unknown = Get(bob_, "j0000000000000000", &unknown_job);
  ASSERT_EQ(unknown.error_code(), grpc::StatusCode::NOT_FOUND);
  const grpc::Status hidden = Get(bob_, job.id(), &got);
  EXPECT_EQ(hidden.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(hidden.error_message(), "job " + job.id() + " not found");
  std::string bytes;
  EXPECT_EQ(Download(bob_, job.id(), &bytes).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_TRUE(bytes.empty());
  std::atomic<int> events = 0;
  EXPECT_EQ(Watch(bob_, job.id(), &events).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(events, 0);
  EXPECT_EQ(Cancel(bob_, job.id()).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_TRUE(ListIds(bob_).empty());

  // Its owner, a member and a server admin see it.
  ASSERT_TRUE(Download(alice_, job.id(), &bytes).ok());
  EXPECT_EQ(bytes, "hello\n");
  bytes.clear();
  ASSERT_TRUE(Download(admin_, job.id(), &bytes).ok());
  EXPECT_EQ(ListIds(admin_), std::vector<std::string>{job.id()});
  ASSERT_TRUE(SetRole("bob", v1::VIEWER).ok());
  EXPECT_TRUE(Get(bob_, job.id(), &got).ok());
  EXPECT_TRUE(Watch(bob_, job.id(), &events).ok());
  EXPECT_GT(events, 0);
  EXPECT_EQ(ListIds(bob_), std::vector<std::string>{job.id()});
  // A member who is not the owner may see but not cancel.
  EXPECT_EQ(Cancel(bob_, job.id()).error_code(), grpc::StatusCode::PERMISSION_DENIED);
}

TEST_F(ServerRightsTest, AnOpenWatchEndsWhenItsWatcherIsRemovedFromTheProject) {
  const v1::Job job = SubmitOnSnapshot(alice_, "slow");
  ASSERT_TRUE(SetRole("bob", v1::VIEWER).ok());
  std::atomic<int> events = 0;
  grpc::Status watched;
  const auto start = std::chrono::steady_clock::now();
  std::thread watcher([&] { watched = Watch(bob_, job.id(), &events); });
  ASSERT_TRUE(WaitUntil([&] { return events > 0; }));
  v1::RemoveMemberResponse response;
  ASSERT_TRUE(RemoveMember(alice_, "bob", &response).ok());
  watcher.join();
  EXPECT_EQ(watched.error_code(), grpc::StatusCode::NOT_FOUND) << watched.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - start,
            JobServiceImpl::kWatchRecheck + std::chrono::seconds(5));
  ASSERT_TRUE(Cancel(alice_, job.id()).ok());
}

TEST_F(ServerRightsTest, AnOpenAtlasWatchEndsWhenItsWatcherIsRemovedOrDisabled) {
  ASSERT_TRUE(SetRole("bob", v1::VIEWER).ok());
  ASSERT_TRUE(SetRole("eve", v1::VIEWER).ok());
  std::atomic<int> bob_events = 0, eve_events = 0;
  grpc::Status bob_watch, eve_watch;
  const auto start = std::chrono::steady_clock::now();
  std::thread bob([&] { bob_watch = AtlasWatch(bob_, &bob_events); });
  std::thread eve([&] { eve_watch = AtlasWatch(eve_, &eve_events); });
  // Both streams are open (READY sent) before their rights go.
  ASSERT_TRUE(WaitUntil([&] { return bob_events > 0 && eve_events > 0; }));

  v1::RemoveMemberResponse response;
  ASSERT_TRUE(RemoveMember(alice_, "bob", &response).ok());
  // As `pba-server admin disable-user` does it: another process, offline.
  std::unique_ptr<AtlasStore> offline;
  ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &offline).ok());
  ASSERT_TRUE(offline->SetUserDisabled("eve", true).ok());

  bob.join();
  eve.join();
  EXPECT_EQ(bob_watch.error_code(), grpc::StatusCode::PERMISSION_DENIED)
      << bob_watch.error_message();
  EXPECT_NE(bob_watch.error_message().find("not a member"), std::string::npos)
      << bob_watch.error_message();
  EXPECT_EQ(eve_watch.error_code(), grpc::StatusCode::UNAUTHENTICATED) << eve_watch.error_message();
  EXPECT_NE(eve_watch.error_message().find("disabled"), std::string::npos)
      << eve_watch.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - start,
            AtlasServiceImpl::kWatchRecheck + std::chrono::seconds(10));
}

// One user holds at most kMaxWatchesPerUser streams of each kind open; the
// next is RESOURCE_EXHAUSTED at once, another user is still served, and a
// closed stream gives its slot back.
TEST_F(ServerRightsTest, AUserHoldsABoundedNumberOfWatchStreams) {
  ASSERT_TRUE(SetRole("bob", v1::VIEWER).ok());
  const v1::Job job = SubmitOnSnapshot(alice_, "slow");
  struct Open {
    grpc::ClientContext context;
    std::unique_ptr<grpc::ClientReaderInterface<v1::AtlasEvent>> atlas;
    std::unique_ptr<grpc::ClientReaderInterface<v1::JobEvent>> job;
  };
  // Opens a stream and reads its first event (READY, or the job's first);
  // the status when the stream ended instead.
  const auto open = [&](const std::string& token, bool atlas, Open* o) {
    o->context.AddMetadata("authorization", "Bearer " + token);
    o->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    if (atlas) {
      v1::WatchRequest request;
      request.set_project("atlas");
      o->atlas = atlas_->Watch(&o->context, request);
      v1::AtlasEvent event;
      if (!o->atlas->Read(&event)) return o->atlas->Finish();
    } else {
      v1::WatchJobRequest request;
      request.set_id(job.id());
      o->job = jobs_->WatchJob(&o->context, request);
      v1::JobEvent event;
      if (!o->job->Read(&event)) return o->job->Finish();
    }
    return grpc::Status::OK;
  };
  for (const bool atlas : {true, false}) {
    const int limit =
        atlas ? AtlasServiceImpl::kMaxWatchesPerUser : JobServiceImpl::kMaxWatchesPerUser;
    std::vector<std::unique_ptr<Open>> held;
    for (int k = 0; k < limit; ++k) {
      held.push_back(std::make_unique<Open>());
      ASSERT_TRUE(open(bob_, atlas, held.back().get()).ok()) << k;
    }
    Open over;
    const grpc::Status refused = open(bob_, atlas, &over);
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << atlas;
    EXPECT_NE(refused.error_message().find("streams open"), std::string::npos)
        << refused.error_message();
    Open other;
    EXPECT_TRUE(open(alice_, atlas, &other).ok()) << atlas;
    other.context.TryCancel();
    // One closed: the server notices within a poll and frees the slot.
    held.back()->context.TryCancel();
    ASSERT_TRUE(WaitUntil([&] {
      Open again;
      const bool ok = open(bob_, atlas, &again).ok();
      again.context.TryCancel();
      return ok;
    })) << atlas;
    for (auto& o : held) o->context.TryCancel();
  }
}

TEST_F(ServerRightsTest, ListJobsPagesSkipHiddenJobs) {
  // bob's plain jobs (every user sees those) between alice's project jobs.
  std::vector<std::string> visible;
  for (int i = 0; i < 3; ++i) {
    SubmitOnSnapshot(alice_, "slow");
    v1::SubmitJobRequest request;
    *request.mutable_scene() = testing::ValidScene("slow");
    v1::Job job;
    ASSERT_TRUE(Call(bob_, [&](grpc::ClientContext* c) {
                  return jobs_->SubmitJob(c, request, &job);
                }).ok());
    visible.insert(visible.begin(), job.id());
  }
  EXPECT_EQ(ListIds(eve_, 1), visible);
  EXPECT_EQ(ListIds(eve_, 2), visible);
  EXPECT_EQ(ListIds(alice_, 2).size(), 6u);
  for (const std::string& id : ListIds(admin_)) ASSERT_TRUE(Cancel(admin_, id).ok());
}

TEST_F(ServerRightsTest, AServerAdminCancelsAnyJob) {
  const v1::Job job = SubmitOnSnapshot(alice_, "slow");
  ASSERT_TRUE(SetRole("bob", v1::EDITOR).ok());
  const grpc::Status refused = Cancel(bob_, job.id());
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(refused.error_message().find("submitted by alice"), std::string::npos);
  ASSERT_TRUE(Cancel(admin_, job.id()).ok());
  v1::Job got;
  ASSERT_TRUE(WaitUntil(
      [&] { return Get(alice_, job.id(), &got).ok() && got.state() == v1::Job::CANCELLED; }));
}

TEST_F(ServerRightsTest, AUserDisabledOfflineIsRefusedByTheRunningServerAtOnce) {
  v1::User me;
  const auto who_am_i = [&](const std::string& token) {
    return Call(
        token, [&](grpc::ClientContext* c) { return atlas_->WhoAmI(c, v1::WhoAmIRequest(), &me); });
  };
  ASSERT_TRUE(who_am_i(bob_).ok());
  // Another connection, as `pba-server admin disable-user` is another process.
  std::unique_ptr<AtlasStore> offline;
  ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &offline).ok());
  ASSERT_TRUE(offline->SetUserDisabled("bob", true).ok());
  const grpc::Status refused = who_am_i(bob_);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_NE(refused.error_message().find("disabled"), std::string::npos);
  EXPECT_EQ(ListIds(alice_).size(), 0u);
  v1::ListJobsResponse response;
  EXPECT_EQ(Call(bob_,
                 [&](grpc::ClientContext* c) {
                   return jobs_->ListJobs(c, v1::ListJobsRequest(), &response);
                 })
                .error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  ASSERT_TRUE(offline->SetUserDisabled("bob", false).ok());
  EXPECT_TRUE(who_am_i(bob_).ok());
}

TEST_F(ServerRightsTest, AQueuedJobOfAUserDisabledSinceDoesNotRun) {
  // alice's job holds the only runner while bob's waits behind it.
  ASSERT_EQ(options_.max_running, 1);
  const v1::Job blocker = SubmitOnSnapshot(alice_, "slow");
  v1::Job got;
  ASSERT_TRUE(WaitUntil(
      [&] { return Get(alice_, blocker.id(), &got).ok() && got.state() == v1::Job::RUNNING; }));
  v1::SubmitJobRequest request;
  *request.mutable_scene() = testing::ValidScene("ok");
  v1::Job queued;
  ASSERT_TRUE(Call(bob_, [&](grpc::ClientContext* c) {
                return jobs_->SubmitJob(c, request, &queued);
              }).ok());
  ASSERT_EQ(queued.state(), v1::Job::QUEUED);

  std::unique_ptr<AtlasStore> offline;
  ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &offline).ok());
  ASSERT_TRUE(offline->SetUserDisabled("bob", true).ok());
  ASSERT_TRUE(Cancel(alice_, blocker.id()).ok());

  ASSERT_TRUE(WaitUntil([&] {
    return Get(admin_, queued.id(), &got).ok() && got.state() != v1::Job::QUEUED &&
           got.state() != v1::Job::RUNNING;
  })) << v1::Job::State_Name(got.state());
  EXPECT_EQ(got.state(), v1::Job::FAILED);
  EXPECT_NE(got.error().find("owner 'bob' was disabled"), std::string::npos) << got.error();
  // It never ran: no result (the fake solver's "ok" writes one).
  EXPECT_EQ(got.result_files_size(), 0);
  EXPECT_FALSE(std::filesystem::exists(options_.data_dir / "jobs" / queued.id() / "result"));

  // alice's next job runs: only the disabled user's are refused.
  const v1::Job next = SubmitOnSnapshot(alice_, "ok");
  ASSERT_TRUE(WaitUntil([&] {
    return Get(alice_, next.id(), &got).ok() && got.state() == v1::Job::SUCCEEDED;
  })) << got.error();
}

TEST_F(ServerRightsTest, AnAdminRemovesAMemberOverTheApi) {
  ASSERT_TRUE(SetRole("bob", v1::EDITOR).ok());
  v1::Lock lock;
  ASSERT_TRUE(LockPutamen(bob_, &lock).ok());
  v1::RemoveMemberResponse response;
  EXPECT_EQ(RemoveMember(bob_, "bob", &response).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  ASSERT_TRUE(RemoveMember(alice_, "bob", &response).ok());
  EXPECT_EQ(response.released_locks_size(), 1);
  v1::GetStructureRequest get;
  get.set_project("atlas");
  get.set_structure("Putamen");
  v1::Structure structure;
  EXPECT_EQ(
      Call(bob_, [&](grpc::ClientContext* c) { return atlas_->GetStructure(c, get, &structure); })
          .error_code(),
      grpc::StatusCode::PERMISSION_DENIED);
  ASSERT_TRUE(Call(alice_, [&](grpc::ClientContext* c) {
                return atlas_->GetStructure(c, get, &structure);
              }).ok());
  EXPECT_FALSE(structure.has_lock());
  EXPECT_EQ(RemoveMember(alice_, "bob", &response).error_code(), grpc::StatusCode::NOT_FOUND);
  const grpc::Status last = RemoveMember(alice_, "alice", &response);
  EXPECT_EQ(last.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(last.error_message().find("last admin"), std::string::npos);
}

TEST_F(ServerRightsTest, AnOutsidersUploadIsNotParsedBeforeTheRoleCheck) {
  // Broken JSON: parsing it would be INVALID_ARGUMENT; the outsider must
  // hear only that they may not.
  const std::string upload = Upload(eve_, "{ not json");
  v1::CreateStructureRequest create;
  create.set_project("atlas");
  create.set_name("Caudate");
  create.set_format(v1::CONTOURS_JSON);
  create.set_upload_id(upload);
  v1::Revision revision;
  EXPECT_EQ(
      Call(eve_,
           [&](grpc::ClientContext* c) { return atlas_->CreateStructure(c, create, &revision); })
          .error_code(),
      grpc::StatusCode::PERMISSION_DENIED);
  v1::CommitStructureRequest commit;
  commit.set_project("atlas");
  commit.set_structure("Putamen");
  commit.set_lock_id("0123456789abcdef0123456789abcdef");
  commit.set_base_revision(1);
  commit.set_format(v1::CONTOURS_JSON);
  commit.set_upload_id(upload);
  EXPECT_EQ(
      Call(eve_,
           [&](grpc::ClientContext* c) { return atlas_->CommitStructure(c, commit, &revision); })
          .error_code(),
      grpc::StatusCode::PERMISSION_DENIED);
  // Untouched: still there to be used or discarded.
  v1::GetUploadRequest get;
  get.set_upload_id(upload);
  v1::Upload info;
  EXPECT_TRUE(
      Call(eve_, [&](grpc::ClientContext* c) { return atlas_->GetUpload(c, get, &info); }).ok());
}

TEST_F(ServerRightsTest, ACommitResentAfterALostReplyReturnsItsRevision) {
  v1::Lock lock;
  ASSERT_TRUE(LockPutamen(alice_, &lock).ok());
  v1::CommitStructureRequest commit;
  commit.set_project("atlas");
  commit.set_structure("Putamen");
  commit.set_lock_id(lock.lock_id());
  commit.set_base_revision(1);
  commit.set_format(v1::CONTOURS_JSON);
  commit.set_upload_id(Upload(alice_, std::string(kContours) + " "));
  commit.set_message("wider");
  commit.set_request_id("commit-wider-1");
  v1::Revision first, again;
  ASSERT_TRUE(Call(alice_, [&](grpc::ClientContext* c) {
                return atlas_->CommitStructure(c, commit, &first);
              }).ok());
  // The same request again, byte for byte: its upload is gone by now.
  const grpc::Status repeated = Call(
      alice_, [&](grpc::ClientContext* c) { return atlas_->CommitStructure(c, commit, &again); });
  ASSERT_TRUE(repeated.ok()) << repeated.error_message();
  EXPECT_EQ(again.number(), first.number());
  EXPECT_EQ(again.content_sha256(), first.content_sha256());
  v1::GetStructureRequest get;
  get.set_project("atlas");
  get.set_structure("Putamen");
  v1::Structure structure;
  ASSERT_TRUE(Call(alice_, [&](grpc::ClientContext* c) {
                return atlas_->GetStructure(c, get, &structure);
              }).ok());
  EXPECT_EQ(structure.head(), 2) << "a retry must not commit twice";
}

// grpc.health.v1.Health/Check for `service`: the request's field 1 (the
// service name) is encoded by hand, so the test needs no health.proto.
grpc::Status HealthCheck(const std::shared_ptr<grpc::Channel>& channel, const std::string& service,
                         std::string* response_bytes) {
  std::string request_bytes;
  if (!service.empty()) {
    request_bytes = std::string(1, '\x0a') + static_cast<char>(service.size()) + service;
  }
  grpc::Slice slice(request_bytes.data(), request_bytes.size());
  grpc::ByteBuffer request(&slice, 1);
  grpc::ByteBuffer response;
  grpc::GenericStub generic(channel);
  grpc::CompletionQueue cq;
  grpc::ClientContext context;
  auto call = generic.PrepareUnaryCall(&context, "/grpc.health.v1.Health/Check", request, &cq);
  call->StartCall();
  grpc::Status status;
  call->Finish(&response, &status, reinterpret_cast<void*>(1));
  void* tag = nullptr;
  bool ok = false;
  cq.Next(&tag, &ok);
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
  std::vector<grpc::Slice> slices;
  response_bytes->clear();
  if (status.ok() && response.Dump(&slices).ok()) {
    for (const grpc::Slice& s : slices) {
      response_bytes->append(reinterpret_cast<const char*>(s.begin()), s.size());
    }
  }
  return status;
}

TEST_F(ServerRightsTest, HealthIsReportedPerService) {
  // HealthCheckResponse{status: SERVING (1)}: field 1, varint 1.
  const std::string serving("\x08\x01", 2);
  std::string response;
  for (const char* service : {"", "pba.v1.JobService", "pba.v1.AtlasService"}) {
    const grpc::Status status = HealthCheck(channel_, service, &response);
    ASSERT_TRUE(status.ok()) << service << ": " << status.error_message();
    EXPECT_EQ(response, serving) << service;
  }
  EXPECT_EQ(HealthCheck(channel_, "pba.v1.NoSuchService", &response).error_code(),
            grpc::StatusCode::NOT_FOUND);
}

TEST(PbaServerListenTest, PlaintextIsRefusedOffLoopbackUnlessInsecure) {
  for (const char* loopback : {"127.0.0.1:1", "127.1.2.3:1", "[::1]:1", "localhost:1",
                               "LOCALHOST:1", "[::ffff:127.0.0.1]:1", "unix:/tmp/pba.sock"}) {
    EXPECT_TRUE(IsLoopbackListen(loopback)) << loopback;
  }
  for (const char* remote : {"0.0.0.0:1", "[::]:1", ":1", "10.0.0.1:1", "128.0.0.1:1",
                             "example.org:1", "localhost.example.org:1", "[::2]:1", "nonsense"}) {
    EXPECT_FALSE(IsLoopbackListen(remote)) << remote;
  }
  TempDir dir;
  ServerOptions options;
  options.data_dir = dir.path() / "data";
  options.listen = "0.0.0.0:0";
  options.solver = testing::WriteFakeSolver(dir.path());
  std::unique_ptr<PbaServer> server;
  const Status refused = PbaServer::Start(options, &server);
  EXPECT_EQ(refused.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(refused.ToString().find("--insecure"), std::string::npos) << refused.ToString();
  EXPECT_FALSE(std::filesystem::exists(options.data_dir)) << "refused before anything is made";
  options.insecure = true;
  const Status started = PbaServer::Start(options, &server);
  ASSERT_TRUE(started.ok()) << started.ToString();
  server->Shutdown();
}

}  // namespace
}  // namespace pba
