// The job service through a real channel to a PbaServer running in-process on
// 127.0.0.1:0, with the fake pba-solve.
#include "service/job_service.h"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "app/pba_server.h"
#include "store/atlas_store.h"
#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;
using testing::ValidScene;
using testing::WaitUntil;

namespace fs = std::filesystem;

class JobServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.data_dir = dir_.path() / "data";
    options_.listen = "127.0.0.1:0";
    options_.solver = testing::WriteFakeSolver(dir_.path());
    options_.kill_grace = std::chrono::milliseconds(1000);
    options_.drain = std::chrono::milliseconds(2000);
    StartServer();
  }

  void StartServer() {
    const Status status = PbaServer::Start(options_, &server_);
    ASSERT_TRUE(status.ok()) << status.ToString();
    ASSERT_EQ(server_->address().rfind("127.0.0.1:", 0), 0u);
    ASSERT_NE(server_->address(), "127.0.0.1:0");
    channel_ = grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials());
    stub_ = v1::JobService::NewStub(channel_);
    std::ifstream token(options_.data_dir / "admin.token");
    token >> token_;
  }

  // Every call carries the admin's token (written at the first start).
  void Authorize(grpc::ClientContext* context) const {
    context->AddMetadata("authorization", "Bearer " + token_);
  }

  grpc::Status Submit(const v1::Scene& scene, v1::Job* job, const std::string& request_id = "") {
    grpc::ClientContext context;
    Authorize(&context);
    v1::SubmitJobRequest request;
    *request.mutable_scene() = scene;
    request.set_request_id(request_id);
    return stub_->SubmitJob(&context, request, job);
  }

  grpc::Status Get(const std::string& id, v1::Job* job) {
    grpc::ClientContext context;
    Authorize(&context);
    v1::GetJobRequest request;
    request.set_id(id);
    return stub_->GetJob(&context, request, job);
  }

  v1::Job Get(const std::string& id) {
    v1::Job job;
    EXPECT_TRUE(Get(id, &job).ok());
    return job;
  }

  grpc::Status Cancel(const std::string& id, v1::Job* job) {
    grpc::ClientContext context;
    Authorize(&context);
    v1::CancelJobRequest request;
    request.set_id(id);
    return stub_->CancelJob(&context, request, job);
  }

  v1::Job WaitForState(const std::string& id, v1::Job::State state) {
    EXPECT_TRUE(WaitUntil([&] { return Get(id).state() == state; }))
        << v1::Job::State_Name(Get(id).state()) << " " << Get(id).error();
    return Get(id);
  }

  grpc::Status Watch(const std::string& id, int64_t after, std::vector<v1::JobEvent>* events) {
    grpc::ClientContext context;
    Authorize(&context);
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    v1::WatchJobRequest request;
    request.set_id(id);
    request.set_after_sequence(after);
    auto reader = stub_->WatchJob(&context, request);
    v1::JobEvent event;
    while (reader->Read(&event)) events->push_back(event);
    return reader->Finish();
  }

  grpc::Status Download(const std::string& id, const std::string& file, int64_t offset,
                        std::string* data, int* chunks = nullptr, int64_t* total = nullptr) {
    grpc::ClientContext context;
    Authorize(&context);
    v1::DownloadResultRequest request;
    request.set_job_id(id);
    request.set_file(file);
    request.set_offset(offset);
    auto reader = stub_->DownloadResult(&context, request);
    v1::DataChunk chunk;
    int count = 0;
    while (reader->Read(&chunk)) {
      EXPECT_LE(chunk.data().size(), JobServiceImpl::kChunkBytes);
      EXPECT_EQ(chunk.offset(), offset + static_cast<int64_t>(data->size()));
      data->append(chunk.data());
      if (total) *total = chunk.total_size();
      ++count;
    }
    if (chunks) *chunks = count;
    return reader->Finish();
  }

  TempDir dir_;
  ServerOptions options_;
  std::unique_ptr<PbaServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> stub_;
  std::string token_;
};

TEST_F(JobServiceTest, SubmitGetAndWatchToTheEnd) {
  v1::Job job;
  ASSERT_TRUE(Submit(ValidScene("ok"), &job).ok());
  EXPECT_FALSE(job.id().empty());
  EXPECT_EQ(job.name(), "ok");

  std::vector<v1::JobEvent> events;
  const grpc::Status watched = Watch(job.id(), 0, &events);
  ASSERT_TRUE(watched.ok()) << watched.error_message();
  ASSERT_GE(events.size(), 3u);
  EXPECT_EQ(events.front().sequence(), 1);
  EXPECT_EQ(events.front().state(), v1::Job::QUEUED);
  EXPECT_EQ(events.back().state(), v1::Job::SUCCEEDED);
  for (size_t i = 1; i < events.size(); ++i) {
    EXPECT_GT(events[i].sequence(), events[i - 1].sequence());
    EXPECT_EQ(events[i].job_id(), job.id());
  }

  const v1::Job done = Get(job.id());
  EXPECT_EQ(done.state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(done.summary().scene_name(), "ok");
  EXPECT_EQ(done.scene().name(), "ok");
  EXPECT_EQ(done.result_files_size(), 4);  // with SHA256SUMS

  // Watching a finished job replays what is left and ends.
  std::vector<v1::JobEvent> replay;
  ASSERT_TRUE(Watch(job.id(), events[1].sequence(), &replay).ok());
  ASSERT_FALSE(replay.empty());
  EXPECT_GT(replay.front().sequence(), events[1].sequence());
  EXPECT_EQ(replay.back().state(), v1::Job::SUCCEEDED);
  std::vector<v1::JobEvent> nothing;
  ASSERT_TRUE(Watch(job.id(), events.back().sequence(), &nothing).ok());
  EXPECT_TRUE(nothing.empty());
}

TEST_F(JobServiceTest, InvalidSceneIsRejectedAndNothingStored) {
  v1::Scene scene = ValidScene("bad");
  scene.mutable_material()->mutable_linear_elastic()->set_poissons_ratio(0.7);
  v1::Job job;
  const grpc::Status status = Submit(scene, &job, "req-bad");
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("poissons_ratio"), std::string::npos)
      << status.error_message();

  grpc::ClientContext context;
  Authorize(&context);
  v1::ListJobsResponse response;
  ASSERT_TRUE(stub_->ListJobs(&context, v1::ListJobsRequest(), &response).ok());
  EXPECT_EQ(response.jobs_size(), 0);
  // No job folder either.
  EXPECT_TRUE(fs::is_empty(options_.data_dir / "jobs"));
}

// Every call needs a token; a job is its submitter's to cancel.
TEST_F(JobServiceTest, CallsAreAuthenticatedAndOnlyTheOwnerCancels) {
  {
    grpc::ClientContext context;
    v1::SubmitJobRequest request;
    *request.mutable_scene() = ValidScene("anonymous");
    v1::Job job;
    EXPECT_EQ(stub_->SubmitJob(&context, request, &job).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
    grpc::ClientContext listing;
    listing.AddMetadata("authorization", "Bearer " + std::string(64, '0'));
    v1::ListJobsResponse response;
    EXPECT_EQ(stub_->ListJobs(&listing, v1::ListJobsRequest(), &response).error_code(),
              grpc::StatusCode::UNAUTHENTICATED);
  }
  v1::Job job;
  ASSERT_TRUE(Submit(ValidScene("slow"), &job).ok());
  EXPECT_EQ(job.owner(), "admin");
  // Bob, a second user, sees the job but cannot cancel it.
  std::string bob;
  {
    std::unique_ptr<AtlasStore> users;
    ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &users).ok());
    ASSERT_TRUE(users->CreateUser("bob", &bob).ok());
  }
  grpc::ClientContext get;
  get.AddMetadata("authorization", "Bearer " + bob);
  v1::GetJobRequest get_request;
  get_request.set_id(job.id());
  v1::Job seen;
  ASSERT_TRUE(stub_->GetJob(&get, get_request, &seen).ok());
  grpc::ClientContext cancel;
  cancel.AddMetadata("authorization", "Bearer " + bob);
  v1::CancelJobRequest cancel_request;
  cancel_request.set_id(job.id());
  v1::Job after;
  const grpc::Status refused = stub_->CancelJob(&cancel, cancel_request, &after);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(refused.error_message().find("admin"), std::string::npos) << refused.error_message();
  EXPECT_NE(Get(job.id()).state(), v1::Job::CANCELLED);
  // A request id another user chose is not bob's to reuse.
  v1::Job keyed;
  ASSERT_TRUE(Submit(ValidScene("ok"), &keyed, "shared-key").ok());
  grpc::ClientContext reuse;
  reuse.AddMetadata("authorization", "Bearer " + bob);
  v1::SubmitJobRequest again;
  *again.mutable_scene() = ValidScene("ok");
  again.set_request_id("shared-key");
  EXPECT_EQ(stub_->SubmitJob(&reuse, again, &after).error_code(), grpc::StatusCode::ALREADY_EXISTS);
  // The owner can.
  ASSERT_TRUE(Cancel(job.id(), &after).ok());
  EXPECT_EQ(WaitForState(job.id(), v1::Job::CANCELLED).state(), v1::Job::CANCELLED);
}

TEST_F(JobServiceTest, RepeatedRequestIdIsIdempotent) {
  v1::Job first, second;
  ASSERT_TRUE(Submit(ValidScene("ok"), &first, "req-1").ok());
  ASSERT_TRUE(Submit(ValidScene("ok"), &second, "req-1").ok());
  EXPECT_EQ(first.id(), second.id());
}

TEST_F(JobServiceTest, UnknownIdsAreNotFound) {
  v1::Job job;
  EXPECT_EQ(Get("j0123456789", &job).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Cancel("j0123456789", &job).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Get("", &job).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  std::vector<v1::JobEvent> events;
  EXPECT_EQ(Watch("j0123456789", 0, &events).error_code(), grpc::StatusCode::NOT_FOUND);
  std::string data;
  EXPECT_EQ(Download("j0123456789", "", 0, &data).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(JobServiceTest, ListPaginatesNewestFirst) {
  // Stop the executor from running them: cancel-free check of listing only.
  std::vector<std::string> ids;
  for (int i = 0; i < 5; ++i) {
    v1::Job job;
    ASSERT_TRUE(Submit(ValidScene("error"), &job).ok());
    ids.push_back(job.id());
  }
  std::vector<std::string> listed;
  std::string token;
  int pages = 0;
  do {
    grpc::ClientContext context;
    Authorize(&context);
    v1::ListJobsRequest request;
    request.set_page_size(2);
    request.set_page_token(token);
    v1::ListJobsResponse response;
    ASSERT_TRUE(stub_->ListJobs(&context, request, &response).ok());
    for (const v1::Job& job : response.jobs()) {
      listed.push_back(job.id());
      EXPECT_FALSE(job.has_scene());
      EXPECT_FALSE(job.has_summary());
    }
    token = response.next_page_token();
    ++pages;
  } while (!token.empty() && pages < 10);
  EXPECT_EQ(pages, 3);
  EXPECT_EQ(listed, std::vector<std::string>(ids.rbegin(), ids.rend()));

  grpc::ClientContext context;
  Authorize(&context);
  v1::ListJobsRequest request;
  request.set_page_token("not-a-token");
  v1::ListJobsResponse response;
  EXPECT_EQ(stub_->ListJobs(&context, request, &response).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(JobServiceTest, DownloadInChunksAndResume) {
  v1::Job job;
  ASSERT_TRUE(Submit(ValidScene("big"), &job).ok());
  job = WaitForState(job.id(), v1::Job::SUCCEEDED);

  std::string data;
  int chunks = 0;
  int64_t total = 0;
  ASSERT_TRUE(Download(job.id(), "", 0, &data, &chunks, &total).ok());
  EXPECT_EQ(static_cast<int>(data.size()), testing::kBigResultBytes);
  EXPECT_EQ(total, testing::kBigResultBytes);
  EXPECT_EQ(chunks, 3);  // 2.5 MiB in 1 MiB chunks
  EXPECT_EQ(data, std::string(testing::kBigResultBytes, 'x'));

  const int64_t offset = (1 << 20) + 123;
  std::string rest;
  ASSERT_TRUE(Download(job.id(), "result.h5", offset, &rest, &chunks).ok());
  EXPECT_EQ(static_cast<int64_t>(rest.size()), testing::kBigResultBytes - offset);
  EXPECT_EQ(chunks, 2);

  std::string summary;
  ASSERT_TRUE(Download(job.id(), "summary.json", 0, &summary).ok());
  EXPECT_NE(summary.find("\"scene_name\":\"big\""), std::string::npos);

  std::string none;
  EXPECT_EQ(Download(job.id(), "result.h5", testing::kBigResultBytes + 1, &none).error_code(),
            grpc::StatusCode::OUT_OF_RANGE);
  EXPECT_EQ(Download(job.id(), "../../pba.db", 0, &none).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(Download(job.id(), "missing.h5", 0, &none).error_code(), grpc::StatusCode::NOT_FOUND);
  // At the very end: one empty chunk that still tells the size.
  std::string end;
  ASSERT_TRUE(
      Download(job.id(), "result.h5", testing::kBigResultBytes, &end, &chunks, &total).ok());
  EXPECT_TRUE(end.empty());
  EXPECT_EQ(chunks, 1);
  EXPECT_EQ(total, testing::kBigResultBytes);
}

TEST_F(JobServiceTest, DownloadOfAFailedJobNamesTheState) {
  v1::Job job;
  ASSERT_TRUE(Submit(ValidScene("error"), &job).ok());
  WaitForState(job.id(), v1::Job::FAILED);
  std::string data;
  const grpc::Status status = Download(job.id(), "", 0, &data);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(status.error_message().find("FAILED"), std::string::npos);
  EXPECT_NE(status.error_message().find("stiffness matrix is singular"), std::string::npos);
}

TEST_F(JobServiceTest, CancelRunningJobEndsTheWatch) {
  v1::Job job;
  ASSERT_TRUE(Submit(ValidScene("slow"), &job).ok());
  std::vector<v1::JobEvent> events;
  grpc::Status watched;
  std::thread watcher([&] { watched = Watch(job.id(), 0, &events); });
  ASSERT_TRUE(WaitUntil([&] { return Get(job.id()).phase() == "mesh"; }));
  v1::Job cancelled;
  ASSERT_TRUE(Cancel(job.id(), &cancelled).ok());
  watcher.join();
  ASSERT_TRUE(watched.ok()) << watched.error_message();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().state(), v1::Job::CANCELLED);
  EXPECT_EQ(Get(job.id()).error(), "cancelled by request");

  // Cancelling a finished job returns it unchanged.
  ASSERT_TRUE(Cancel(job.id(), &cancelled).ok());
  EXPECT_EQ(cancelled.state(), v1::Job::CANCELLED);
}

TEST_F(JobServiceTest, CancelQueuedJob) {
  // The one worker is busy with a slow job, so the second one waits.
  v1::Job slow, queued;
  ASSERT_TRUE(Submit(ValidScene("slow"), &slow).ok());
  ASSERT_TRUE(Submit(ValidScene("ok"), &queued).ok());
  ASSERT_TRUE(WaitUntil([&] { return Get(slow.id()).state() == v1::Job::RUNNING; }));
  v1::Job cancelled;
  ASSERT_TRUE(Cancel(queued.id(), &cancelled).ok());
  EXPECT_EQ(cancelled.state(), v1::Job::CANCELLED);
  ASSERT_TRUE(Cancel(slow.id(), &cancelled).ok());
  WaitForState(slow.id(), v1::Job::CANCELLED);
}

TEST_F(JobServiceTest, ShutdownEndsWatchesAndRequeuesRunningJobs) {
  v1::Job job;
  ASSERT_TRUE(Submit(ValidScene("slow"), &job).ok());
  ASSERT_TRUE(WaitUntil([&] { return Get(job.id()).phase() == "mesh"; }));
  std::vector<v1::JobEvent> events;
  grpc::Status watched;
  std::thread watcher([&] { watched = Watch(job.id(), 0, &events); });
  ASSERT_TRUE(WaitUntil([&] { return !events.empty(); }));
  const auto start = std::chrono::steady_clock::now();
  server_->Shutdown();
  watcher.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
  EXPECT_EQ(watched.error_code(), grpc::StatusCode::UNAVAILABLE) << watched.error_message();

  // The next start reruns the job as attempt 2.
  server_.reset();
  StartServer();
  ASSERT_TRUE(WaitUntil([&] { return Get(job.id()).attempts() == 2; }));
  std::vector<v1::JobEvent> history;
  std::thread watcher2([&] { Watch(job.id(), 0, &history); });
  v1::Job cancelled;
  ASSERT_TRUE(Cancel(job.id(), &cancelled).ok());
  watcher2.join();
  bool requeued = false;
  for (const v1::JobEvent& event : history) {
    requeued |= event.message() == "re-queued: server shut down";
  }
  EXPECT_TRUE(requeued);
}

TEST_F(JobServiceTest, HealthServiceIsOn) {
  grpc::ClientContext context;
  Authorize(&context);
  // grpc.health.v1.Health/Check with an empty HealthCheckRequest (zero bytes).
  grpc::Slice empty("", 0);
  grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  grpc::GenericStub generic(channel_);
  grpc::CompletionQueue cq;
  auto call = generic.PrepareUnaryCall(&context, "/grpc.health.v1.Health/Check", request, &cq);
  call->StartCall();
  grpc::Status status;
  call->Finish(&response, &status, reinterpret_cast<void*>(1));
  void* tag = nullptr;
  bool ok = false;
  ASSERT_TRUE(cq.Next(&tag, &ok));
  EXPECT_TRUE(status.ok()) << status.error_message();
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
}

TEST(PbaServerTest, RefusesAMissingSolver) {
  TempDir dir;
  ServerOptions options;
  options.data_dir = dir.path() / "data";
  options.listen = "127.0.0.1:0";
  options.solver = dir.path() / "nope";
  std::unique_ptr<PbaServer> server;
  const Status status = PbaServer::Start(options, &server);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("nope"), std::string::npos);
}

}  // namespace
}  // namespace pba
