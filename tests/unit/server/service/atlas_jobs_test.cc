// Jobs on the atlas store through a real channel to an in-process server
// with the fake pba-solve: submits against a snapshot and atlas imports are
// checked (and refused without a trace), a snapshot is staged as a
// structure set, and a project's watchers hear of its jobs.
#include "service/atlas_jobs.h"

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "app/pba_server.h"
#include "atlas/structure_set.h"
#include "core/sha256.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"
#include "service/atlas_event_hub.h"
#include "store/atlas_store.h"
#include "store/job_store.h"
#include "unit/server/in_process_server.h"
#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;
using testing::WaitUntil;
namespace fs = std::filesystem;

constexpr char kContours[] =
    R"({"plates": [{"z_mm": 0, "polygons": [[[0, 0], [10, 0], [10, 10], [0, 10]]]}]})";

class AtlasJobsTest : public testing::InProcessServerTest {
 protected:
  void SetUp() override {
    InProcessServerTest::SetUp();
    if (HasFatalFailure()) return;
    // The admin's project "atlas" with one structure and snapshot 1.
    v1::CreateProjectRequest project;
    project.set_name("atlas");
    v1::Project created;
    ASSERT_TRUE(Call(admin_, [&](grpc::ClientContext* c) {
                  return atlas_->CreateProject(c, project, &created);
                }).ok());
    CreateStructure("Putamen", kContours);
    v1::CreateSnapshotRequest snapshot;
    snapshot.set_project("atlas");
    snapshot.set_name("first");
    v1::Snapshot made;
    ASSERT_TRUE(Call(admin_, [&](grpc::ClientContext* c) {
                  return atlas_->CreateSnapshot(c, snapshot, &made);
                }).ok());
    ASSERT_EQ(made.id(), 1);
    // An outsider.
    std::unique_ptr<AtlasStore> users;
    ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &users).ok());
    ASSERT_TRUE(users->CreateUser("eve", &eve_).ok());
  }

  void CreateStructure(const std::string& name, const std::string& contours) {
    v1::CreateStructureRequest request;
    request.set_project("atlas");
    request.set_name(name);
    request.mutable_metadata()->mutable_colour()->set_r(200);
    request.set_format(v1::CONTOURS_JSON);
    request.set_upload_id(Upload(admin_, contours));
    v1::Revision revision;
    const grpc::Status status = Call(admin_, [&](grpc::ClientContext* c) {
      return atlas_->CreateStructure(c, request, &revision);
    });
    ASSERT_TRUE(status.ok()) << status.error_message();
  }

  grpc::Status Submit(const std::string& token, const v1::SubmitJobRequest& request, v1::Job* job) {
    return Call(token, [&](grpc::ClientContext* c) { return jobs_->SubmitJob(c, request, job); });
  }

  int CountJobs() {
    v1::ListJobsRequest request;
    v1::ListJobsResponse response;
    EXPECT_TRUE(Call(admin_, [&](grpc::ClientContext* c) {
                  return jobs_->ListJobs(c, request, &response);
                }).ok());
    return response.jobs_size();
  }

  v1::Job Get(const std::string& id) {
    v1::GetJobRequest request;
    request.set_id(id);
    v1::Job job;
    EXPECT_TRUE(
        Call(admin_, [&](grpc::ClientContext* c) { return jobs_->GetJob(c, request, &job); }).ok());
    return job;
  }

  std::string eve_;
};

v1::SubmitJobRequest OnSnapshot(const v1::Scene& scene, const std::string& snapshot) {
  v1::SubmitJobRequest request;
  *request.mutable_scene() = scene;
  request.mutable_snapshot()->set_project("atlas");
  request.mutable_snapshot()->set_snapshot(snapshot);
  return request;
}

TEST_F(AtlasJobsTest, ASubmitAgainstASnapshotIsChecked) {
  struct Case {
    v1::SubmitJobRequest request;
    const char* token_of;
    grpc::StatusCode code;
    const char* fragment;
  };
  v1::Scene with_source = testing::AtlasScene("ok");
  with_source.mutable_geometry()->mutable_atlas()->set_source("synthetic");
  v1::SubmitJobRequest no_project = OnSnapshot(testing::AtlasScene("ok"), "1");
  no_project.mutable_snapshot()->set_project("");
  v1::SubmitJobRequest too_high = OnSnapshot(testing::AtlasScene("ok"), "1");
  too_high.set_priority(101);
  v1::SubmitJobRequest server_file;
  *server_file.mutable_scene() = with_source;
  server_file.mutable_scene()->mutable_geometry()->mutable_atlas()->set_source("/etc/atlas");
  const std::vector<Case> cases = {
      {server_file, "admin", grpc::INVALID_ARGUMENT, "names a file on the server"},
      {OnSnapshot(testing::ValidScene("ok"), "1"), "admin", grpc::INVALID_ARGUMENT,
       "snapshot: only an atlas scene"},
      {OnSnapshot(with_source, "1"), "admin", grpc::INVALID_ARGUMENT,
       "scene.geometry.atlas.source"},
      {no_project, "admin", grpc::INVALID_ARGUMENT, "snapshot.project"},
      {OnSnapshot(testing::AtlasScene("ok"), "9"), "admin", grpc::NOT_FOUND, "no snapshot"},
      {OnSnapshot(testing::AtlasScene("ok"), "nosuchtag"), "admin", grpc::NOT_FOUND, "nosuchtag"},
      {OnSnapshot(testing::AtlasScene("ok"), "1"), "eve", grpc::PERMISSION_DENIED, ""},
      {too_high, "admin", grpc::INVALID_ARGUMENT, "priority"},
  };
  for (const Case& c : cases) {
    v1::Job job;
    const grpc::Status status =
        Submit(std::string(c.token_of) == "eve" ? eve_ : admin_, c.request, &job);
    EXPECT_EQ(status.error_code(), c.code) << status.error_message();
    EXPECT_NE(status.error_message().find(c.fragment), std::string::npos) << status.error_message();
  }
  EXPECT_EQ(CountJobs(), 0);
}

TEST_F(AtlasJobsTest, AJobAgainstASnapshotGetsItsStructuresStaged) {
  // A later commit must not change what snapshot 1 gives.
  CreateStructure("Caudate", kContours);
  v1::Job job;
  ASSERT_TRUE(Submit(admin_, OnSnapshot(testing::AtlasScene("ok"), "1"), &job).ok());
  EXPECT_EQ(job.snapshot().project(), "atlas");
  EXPECT_EQ(job.snapshot().snapshot(), "1");
  ASSERT_TRUE(WaitUntil([&] { return Get(job.id()).state() == v1::Job::SUCCEEDED; }))
      << Get(job.id()).error();
  const fs::path folder = options_.data_dir / "jobs" / job.id();
  std::ifstream manifest_file(folder / "result" / "manifest.json");
  std::stringstream manifest;
  manifest << manifest_file.rdbuf();
  EXPECT_NE(manifest.str().find("\"Putamen\""), std::string::npos) << manifest.str();
  EXPECT_EQ(manifest.str().find("Caudate"), std::string::npos) << manifest.str();
  std::ifstream scene_file(folder / "scene.json");
  std::stringstream scene;
  scene << scene_file.rdbuf();
  EXPECT_NE(scene.str().find((folder / "snapshot").string()), std::string::npos) << scene.str();
  // The staged copy is not kept after the run.
  EXPECT_FALSE(fs::exists(folder / "snapshot"));
}

// The store lets two structures share a colour; a structure set may not:
// the staged copy moves the repeat to the nearest free colour.
TEST_F(AtlasJobsTest, StructuresSharingAColourAreStagedWithDistinctOnes) {
  CreateStructure("Caudate", kContours);  // the same colour as Putamen
  v1::CreateSnapshotRequest snapshot;
  snapshot.set_project("atlas");
  snapshot.set_name("both");
  v1::Snapshot made;
  ASSERT_TRUE(Call(admin_, [&](grpc::ClientContext* c) {
                return atlas_->CreateSnapshot(c, snapshot, &made);
              }).ok());
  v1::Job job;
  ASSERT_TRUE(
      Submit(admin_, OnSnapshot(testing::AtlasScene("ok"), std::to_string(made.id())), &job).ok());
  ASSERT_TRUE(WaitUntil([&] { return Get(job.id()).state() == v1::Job::SUCCEEDED; }))
      << Get(job.id()).error();
  std::ifstream manifest_file(options_.data_dir / "jobs" / job.id() / "result" / "manifest.json");
  std::stringstream manifest;
  manifest << manifest_file.rdbuf();
  EXPECT_NE(manifest.str().find("\"200,0,0\""), std::string::npos) << manifest.str();
  EXPECT_NE(manifest.str().find("\"200,0,1\""), std::string::npos) << manifest.str();
}

// A structure named "manifest" (a legal name) gets a file beside the
// manifest, not the manifest's, and "putamen" one apart from "Putamen"'s
// (one file where case is folded): the staged set reads back with every
// SHA-256 matching, which is what pba-solve checks.
TEST_F(AtlasJobsTest, AStructureNamedManifestIsStagedBesideTheManifest) {
  CreateStructure("manifest", R"({"plates": [{"z_mm": 0, "polygons": [[[20, 0], [30, 0], )"
                              R"([30, 10], [20, 10]]]}]})");
  CreateStructure("putamen", R"({"plates": [{"z_mm": 0, "polygons": [[[40, 0], [50, 0], )"
                             R"([50, 10], [40, 10]]]}]})");
  v1::CreateSnapshotRequest snapshot;
  snapshot.set_project("atlas");
  v1::Snapshot made;
  ASSERT_TRUE(Call(admin_, [&](grpc::ClientContext* c) {
                return atlas_->CreateSnapshot(c, snapshot, &made);
              }).ok());
  std::unique_ptr<AtlasStore> store;
  ASSERT_TRUE(AtlasStore::Open(options_.data_dir, &store).ok());
  std::unique_ptr<JobStore> job_store;
  ASSERT_TRUE(JobStore::Open(dir_.path() / "staging-jobs.db", &job_store).ok());
  AtlasEventHub hub;
  AtlasJobs staging(*store, hub, *job_store);
  v1::Job job;
  job.set_id("jstaging");
  job.set_owner("admin");
  job.mutable_snapshot()->set_project("atlas");
  job.mutable_snapshot()->set_snapshot(std::to_string(made.id()));
  const fs::path dir = dir_.path() / "staged";
  fs::create_directories(dir);
  v1::Scene scene = testing::AtlasScene("ok");
  std::vector<std::string> input;
  const Status staged = staging.Stage(job, dir, &scene, &input);
  ASSERT_TRUE(staged.ok()) << staged.ToString();
  StructureSet set;
  const Status read = ReadStructureSet(dir / "snapshot", &set);
  ASSERT_TRUE(read.ok()) << read.ToString();
  std::map<std::string, std::string> files;
  for (const StructureEntry& e : set.structures) files[e.name] = e.file;
  EXPECT_EQ(files["manifest"], "manifest_2.json");
  EXPECT_EQ(files["Putamen"], "Putamen.json");
  EXPECT_EQ(files["putamen"], "putamen_2.json");
}

TEST_F(AtlasJobsTest, TheProjectsWatchersHearOfItsJobs) {
  grpc::ClientContext context;
  context.AddMetadata("authorization", "Bearer " + admin_);
  v1::WatchRequest watch;
  watch.set_project("atlas");
  auto reader = atlas_->Watch(&context, watch);
  v1::AtlasEvent event;
  ASSERT_TRUE(reader->Read(&event));
  ASSERT_EQ(event.kind(), v1::AtlasEvent::READY);
  v1::Job job;
  ASSERT_TRUE(Submit(admin_, OnSnapshot(testing::AtlasScene("ok"), "1"), &job).ok());
  std::vector<std::string> states;
  while (states.size() < 3 && reader->Read(&event)) {
    if (event.kind() != v1::AtlasEvent::JOB_STATE_CHANGED) continue;
    EXPECT_EQ(event.job_id(), job.id());
    EXPECT_EQ(event.snapshot(), 1);
    states.push_back(event.job_state());
  }
  context.TryCancel();
  EXPECT_EQ(states, (std::vector<std::string>{"QUEUED", "RUNNING", "SUCCEEDED"}));
}

v1::SubmitJobRequest Import(v1::AtlasImport::Source source,
                            std::vector<std::pair<std::string, std::string>> files) {
  v1::SubmitJobRequest request;
  auto* import = request.mutable_atlas_import();
  import->set_project("atlas");
  import->set_source(source);
  for (const auto& [name, upload] : files) {
    auto* file = import->add_files();
    file->set_name(name);
    file->set_upload_id(upload);
  }
  return request;
}

TEST_F(AtlasJobsTest, AnImportIsCheckedAndARefusalLeavesNoTrace) {
  const std::string upload = Upload(admin_, "{}");
  struct Case {
    v1::SubmitJobRequest request;
    bool as_eve;
    grpc::StatusCode code;
    const char* fragment;
  };
  v1::SubmitJobRequest with_scene = Import(v1::AtlasImport::SYNTHETIC, {});
  *with_scene.mutable_scene() = testing::ValidScene("ok");
  const std::vector<Case> cases = {
      {Import(v1::AtlasImport::SOURCE_UNSPECIFIED, {}), false, grpc::INVALID_ARGUMENT,
       "atlas_import.source"},
      {Import(v1::AtlasImport::SYNTHETIC, {{"plates.json", upload}}), false, grpc::INVALID_ARGUMENT,
       "send no files"},
      {Import(v1::AtlasImport::PLATES, {{"../plates.json", upload}}), false, grpc::INVALID_ARGUMENT,
       "atlas_import.files[0].name"},
      {Import(v1::AtlasImport::PLATES, {{"plate_01.png", upload}}), false, grpc::INVALID_ARGUMENT,
       "plates.json"},
      {Import(v1::AtlasImport::LABEL_VOLUME, {{"a.nii", upload}, {"b.nrrd", upload}}), false,
       grpc::INVALID_ARGUMENT, "exactly one"},
      {Import(v1::AtlasImport::PLATES, {{"plates.json", "0123456789abcdef0123456789abcdef"}}),
       false, grpc::NOT_FOUND, "atlas_import.files[0].upload_id"},
      {Import(v1::AtlasImport::SYNTHETIC, {}), true, grpc::PERMISSION_DENIED, "editor"},
      {with_scene, false, grpc::INVALID_ARGUMENT, "a job of its own"},
  };
  for (const Case& c : cases) {
    v1::Job job;
    const grpc::Status status = Submit(c.as_eve ? eve_ : admin_, c.request, &job);
    EXPECT_EQ(status.error_code(), c.code) << status.error_message();
    EXPECT_NE(status.error_message().find(c.fragment), std::string::npos) << status.error_message();
  }
  EXPECT_EQ(CountJobs(), 0);
  // Nothing half-made in the jobs folder, and the unused upload is still there.
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(options_.data_dir / "jobs", ec)) {
    ADD_FAILURE() << "left behind: " << entry.path();
  }
  v1::GetUploadRequest get;
  get.set_upload_id(upload);
  v1::Upload info;
  EXPECT_TRUE(
      Call(admin_, [&](grpc::ClientContext* c) { return atlas_->GetUpload(c, get, &info); }).ok());
}

TEST_F(AtlasJobsTest, AnImportTakesItsUploadsAtOnceAndARepeatReturnsTheJob) {
  const std::string upload = Upload(admin_, "{\"plates\": []}");
  v1::SubmitJobRequest request = Import(v1::AtlasImport::PLATES, {{"plates.json", upload}});
  request.set_request_id("import-1");
  // Keep the fake solver from running it: a queued job is enough here.
  v1::Job job;
  ASSERT_TRUE(Submit(admin_, request, &job).ok());
  EXPECT_EQ(job.name(), "import into atlas");
  // The upload is gone: its bytes are the job's now.
  v1::GetUploadRequest get;
  get.set_upload_id(upload);
  v1::Upload info;
  EXPECT_EQ(Call(admin_, [&](grpc::ClientContext* c) { return atlas_->GetUpload(c, get, &info); })
                .error_code(),
            grpc::NOT_FOUND);
  v1::Job again;
  ASSERT_TRUE(Submit(admin_, request, &again).ok());
  EXPECT_EQ(again.id(), job.id());
  EXPECT_EQ(CountJobs(), 1);
}

}  // namespace
}  // namespace pba
