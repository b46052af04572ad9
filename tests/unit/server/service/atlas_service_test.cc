// The atlas service through real channels to a PbaServer running in-process
// on 127.0.0.1:0: authentication, uploads, structures, locks, metadata,
// history, downloads, snapshots, Watch and the audit log, and racing
// clients.
#include "service/atlas_service.h"

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "unit/server/service/atlas_service_fixture.h"

namespace pba::service_test {
namespace {

TEST_F(AtlasServiceTest, MissingOrBadTokensAreUnauthenticatedAndNeverEchoed) {
  v1::WhoAmIRequest request;
  v1::User user;
  {
    grpc::ClientContext context;
    EXPECT_CODE(stub_->WhoAmI(&context, request, &user), grpc::StatusCode::UNAUTHENTICATED,
                "authorization");
  }
  const std::string unknown(64, 'a');
  for (const std::string& value : {"Bearer " + unknown, std::string("Bearer s3cret-garbage"),
                                   "Basic " + tokens_["bob"], tokens_["bob"]}) {
    grpc::ClientContext context;
    context.AddMetadata("authorization", value);
    const grpc::Status status = stub_->WhoAmI(&context, request, &user);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED) << value;
    EXPECT_FALSE(Contains(status.error_message(), unknown));
    EXPECT_FALSE(Contains(status.error_message(), "s3cret"));
    EXPECT_FALSE(Contains(status.error_message(), tokens_["bob"]));
  }
  // Streams too.
  grpc::ClientContext context;
  v1::WatchRequest watch;
  watch.set_project("atlas");
  auto reader = stub_->Watch(&context, watch);
  v1::AtlasEvent event;
  EXPECT_FALSE(reader->Read(&event));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);

  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::WhoAmI, request, &user));
  EXPECT_EQ(user.name(), "bob");
}

TEST_F(AtlasServiceTest, FirstStartWritesAnAdminTokenOnlyItsOwnerCanRead) {
  const fs::path file = options_.data_dir / "admin.token";
  EXPECT_EQ(server_->admin_token_file(), file);
  struct stat info {};
  ASSERT_EQ(::stat(file.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  v1::User user;
  ASSERT_RPC(Call("admin", &v1::AtlasService::Stub::WhoAmI, v1::WhoAmIRequest(), &user));
  EXPECT_EQ(user.name(), "admin");

  // A second start finds users and leaves the file alone.
  server_->Shutdown();
  StartServer();
  EXPECT_TRUE(server_->admin_token_file().empty());
  std::ifstream in(file);
  std::string token;
  std::getline(in, token);
  EXPECT_EQ(token, tokens_["admin"]);
  ASSERT_RPC(Call("admin", &v1::AtlasService::Stub::WhoAmI, v1::WhoAmIRequest(), &user));
}

TEST_F(AtlasServiceTest, ACreateFromAnInterruptedAndResumedUpload) {
  const std::string content = Contours(2 * kMiB + 12345, 2);
  v1::Upload upload;
  ASSERT_RPC(Begin("bob", content, &upload));
  EXPECT_EQ(upload.received_bytes(), 0);
  EXPECT_GT(upload.expire_time().seconds(), 0);

  // A chunk over 1 MiB is refused.
  EXPECT_CODE(Write("bob", upload.id(), content, 0, kMiB + 1, &upload, kMiB + 1),
              grpc::StatusCode::INVALID_ARGUMENT, "1048576");
  // The first chunk, then the stream is cut.
  {
    grpc::ClientContext context;
    Authorize(&context, "bob");
    v1::Upload ignored;
    auto writer = stub_->WriteUpload(&context, &ignored);
    v1::UploadChunk chunk;
    chunk.set_upload_id(upload.id());
    chunk.set_offset(0);
    chunk.set_data(content.substr(0, kMiB));
    ASSERT_TRUE(writer->Write(chunk));
    ASSERT_TRUE(testing::WaitUntil([&] {
      v1::GetUploadRequest get;
      get.set_upload_id(upload.id());
      v1::Upload now;
      return Call("bob", &v1::AtlasService::Stub::GetUpload, get, &now).ok() &&
             now.received_bytes() == static_cast<int64_t>(kMiB);
    }));
    context.TryCancel();
    EXPECT_FALSE(writer->Finish().ok());
  }
  // Resume where GetUpload says; a chunk elsewhere is OUT_OF_RANGE naming it.
  v1::GetUploadRequest get;
  get.set_upload_id(upload.id());
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::GetUpload, get, &upload));
  const size_t received = static_cast<size_t>(upload.received_bytes());
  EXPECT_EQ(received, kMiB);
  EXPECT_CODE(Write("bob", upload.id(), content, 0, kMiB, &upload), grpc::StatusCode::OUT_OF_RANGE,
              "1048576 bytes have arrived");
  // Only its owner sees the upload.
  v1::Upload foreign;
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::GetUpload, get, &foreign),
              grpc::StatusCode::NOT_FOUND, upload.id());
  // Incomplete: not yet usable.
  v1::CreateStructureRequest create;
  create.set_project("atlas");
  create.set_name("liver");
  create.set_format(v1::CONTOURS_JSON);
  create.set_upload_id(upload.id());
  v1::Revision revision;
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision),
              grpc::StatusCode::FAILED_PRECONDITION, "incomplete");

  ASSERT_RPC(Write("bob", upload.id(), content, received, content.size(), &upload));
  EXPECT_EQ(upload.received_bytes(), static_cast<int64_t>(content.size()));
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision));
  EXPECT_EQ(revision.number(), 1);
  EXPECT_EQ(revision.kind(), "create");
  EXPECT_EQ(revision.content_sha256(), Hash(content));
  EXPECT_EQ(revision.size_bytes(), static_cast<int64_t>(content.size()));
  // Consumed.
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::GetUpload, get, &upload),
              grpc::StatusCode::NOT_FOUND, upload.id());
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision),
              grpc::StatusCode::NOT_FOUND, "upload");
  EXPECT_CODE(Create("bob", "liver", content), grpc::StatusCode::ALREADY_EXISTS, "liver");
}

TEST_F(AtlasServiceTest, ADownloadResumedByOffsetEqualsTheUpload) {
  const std::string content = Contours(2 * kMiB + 777, 3);
  v1::Lock lock;
  ASSERT_RPC(Acquire("bob", &lock));
  ASSERT_RPC(Commit("bob", lock.lock_id(), 1, content));
  std::string data;
  Download("carol", 0, 0, &data, 1);  // cut after the first chunk
  ASSERT_EQ(data.size(), kMiB);
  ASSERT_RPC(Download("carol", 2, static_cast<int64_t>(data.size()), &data));
  EXPECT_TRUE(data == content) << data.size() << " vs " << content.size();
  std::string first;
  ASSERT_RPC(Download("carol", 1, 0, &first));
  EXPECT_EQ(first, lung_content_);
  std::string none;
  EXPECT_CODE(Download("carol", 0, static_cast<int64_t>(content.size()) + 1, &none),
              grpc::StatusCode::OUT_OF_RANGE, "past the end");
  EXPECT_CODE(Download("dave", 0, 0, &none), grpc::StatusCode::PERMISSION_DENIED, "member");
}

TEST_F(AtlasServiceTest, AWrongHashOrBadGeometryIsRefusedAndNothingIsWritten) {
  const size_t audit_before = Audit().size();
  const std::string content = Contours(5000, 4);
  v1::Upload upload;
  ASSERT_RPC(Begin("bob", content, &upload, Hash("something else")));
  ASSERT_RPC(Write("bob", upload.id(), content, 0, content.size(), &upload));
  v1::CreateStructureRequest create;
  create.set_project("atlas");
  create.set_name("heart");
  create.set_format(v1::CONTOURS_JSON);
  create.set_upload_id(upload.id());
  v1::Revision revision;
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision),
              grpc::StatusCode::INVALID_ARGUMENT, "sha256");
  // Not JSON, contours that are no shape (each named by where it fails), a
  // NIfTI without its header.
  const std::string square = "[[0, 0], [5, 0], [5, 5], [0, 5]]";
  for (const auto& [format, bad, where] :
       std::vector<std::tuple<v1::GeometryFormat, std::string, std::string>>{
           {v1::CONTOURS_JSON, "{\"plates\": [1, 2", "valid JSON"},
           {v1::CONTOURS_JSON, "{}", "plates"},
           {v1::CONTOURS_JSON, "{\"plates\": []}", "plates"},
           {v1::CONTOURS_JSON, "{\"plates\": [{\"z_mm\": 0, \"polygons\": []}]}",
            "plates[0].polygons"},
           {v1::CONTOURS_JSON, "{\"plates\": [{\"z_mm\": 0, \"polygons\": [[[0, 0], [1, 1]]]}]}",
            "plates[0].polygons[0]"},
           {v1::CONTOURS_JSON,
            "{\"plates\": [{\"z_mm\": 0, \"polygons\": [[[0, 0], [1, 1], [2, 2]]]}]}", "no area"},
           {v1::CONTOURS_JSON,
            "{\"plates\": [{\"z_mm\": 0, \"polygons\": [[[0, 0], [0.05, 0], [0, 7000]]]}]}",
            "plates[0].polygons[0][2]"},
           {v1::CONTOURS_JSON,
            "{\"plates\": [{\"z_mm\": 1, \"polygons\": [" + square +
                "]}, {\"z_mm\": 1, \"polygons\": [" + square + "]}]}",
            "plates[1].z_mm"},
           {v1::NIFTI, std::string(400, '\0'), "NIfTI"}}) {
    create.set_format(format);
    create.set_upload_id(Upload("bob", bad));
    EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision),
                grpc::StatusCode::INVALID_ARGUMENT, where);
  }
  v1::GetStructureRequest get;
  get.set_project("atlas");
  get.set_structure("heart");
  v1::Structure structure;
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::GetStructure, get, &structure),
              grpc::StatusCode::NOT_FOUND, "heart");
  EXPECT_EQ(Audit().size(), audit_before);

  // A minimal NIfTI-1 mask passes: one uint8 voxel, set.
  std::string nifti(353, '\0');
  const int32_t sizeof_hdr = 348;
  const int16_t dim[4] = {3, 1, 1, 1}, datatype = 2, bitpix = 8;
  const float pixdim[4] = {1, 1, 1, 1}, vox_offset = 352;
  std::memcpy(nifti.data(), &sizeof_hdr, 4);
  std::memcpy(nifti.data() + 40, dim, sizeof dim);
  std::memcpy(nifti.data() + 70, &datatype, 2);
  std::memcpy(nifti.data() + 72, &bitpix, 2);
  std::memcpy(nifti.data() + 76, pixdim, sizeof pixdim);
  std::memcpy(nifti.data() + 108, &vox_offset, 4);
  std::memcpy(nifti.data() + 344, "n+1", 4);
  nifti[352] = 1;
  create.set_format(v1::NIFTI);
  create.set_upload_id(Upload("bob", nifti));
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision));
  EXPECT_EQ(revision.format(), v1::NIFTI);
}

TEST_F(AtlasServiceTest, CommitsNeedTheLockTheHeadAndTheRight) {
  v1::Lock lock;
  ASSERT_RPC(Acquire("bob", &lock));
  EXPECT_FALSE(lock.lock_id().empty());
  EXPECT_EQ(lock.holder(), "bob");
  // Others see the lock without its id.
  const v1::Structure structure = Get();
  ASSERT_TRUE(structure.has_lock());
  EXPECT_EQ(structure.lock().holder(), "bob");
  EXPECT_TRUE(structure.lock().lock_id().empty());

  // A foreign lock: FAILED_PRECONDITION naming the holder.
  v1::Lock other;
  EXPECT_CODE(Acquire("admin", &other), grpc::StatusCode::FAILED_PRECONDITION, "'bob'");
  EXPECT_CODE(Commit("admin", lock.lock_id(), 1, Contours(300, 5)),
              grpc::StatusCode::FAILED_PRECONDITION, "'bob'");
  // A viewer cannot commit.
  EXPECT_CODE(Commit("carol", lock.lock_id(), 1, Contours(300, 5)),
              grpc::StatusCode::PERMISSION_DENIED, "viewer");

  v1::Revision revision;
  ASSERT_RPC(Commit("bob", lock.lock_id(), 1, Contours(300, 6), &revision));
  EXPECT_EQ(revision.number(), 2);
  EXPECT_EQ(revision.parent(), 1);
  // A stale base: ABORTED naming the head.
  EXPECT_CODE(Commit("bob", lock.lock_id(), 1, Contours(300, 7)), grpc::StatusCode::ABORTED,
              "the head is revision 2");

  v1::RenewLockRequest renew;
  renew.set_lock_id(lock.lock_id());
  renew.set_lease_seconds(120);
  v1::Lock renewed;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::RenewLock, renew, &renewed));
  EXPECT_TRUE(renewed.lock_id().empty());
  EXPECT_EQ(renewed.structure(), "lung");
  renew.set_lease_seconds(3601);
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::RenewLock, renew, &renewed),
              grpc::StatusCode::INVALID_ARGUMENT, "lease_seconds");

  // Admins break locks, naming whose.
  v1::BreakLockRequest breaking;
  breaking.set_project("atlas");
  breaking.set_structure("lung");
  v1::BreakLockResponse broken;
  EXPECT_CODE(Call("admin", &v1::AtlasService::Stub::BreakLock, breaking, &broken),
              grpc::StatusCode::INVALID_ARGUMENT, "reason");
  breaking.set_reason("bob is away");
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::BreakLock, breaking, &broken),
              grpc::StatusCode::PERMISSION_DENIED, "admin");
  ASSERT_RPC(Call("admin", &v1::AtlasService::Stub::BreakLock, breaking, &broken));
  EXPECT_EQ(broken.holder(), "bob");
  EXPECT_FALSE(Get().has_lock());
  EXPECT_CODE(Release("bob", lock.lock_id()), grpc::StatusCode::FAILED_PRECONDITION,
              "no longer held");
}

TEST_F(AtlasServiceTest, MetadataByEtagRevertAndHistoryPages) {
  const v1::Structure before = Get();
  v1::UpdateMetadataRequest update;
  update.set_project("atlas");
  update.set_structure("lung");
  update.set_etag(before.metadata_etag());
  update.mutable_colour()->set_r(200);
  update.set_message("redder");
  v1::UpdateMetadataResponse updated;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::UpdateMetadata, update, &updated));
  EXPECT_NE(updated.etag(), before.metadata_etag());
  EXPECT_EQ(updated.revision().kind(), "metadata");
  EXPECT_EQ(updated.revision().metadata().colour().r(), 200);
  EXPECT_EQ(Get().metadata_etag(), updated.etag());
  // The old etag is stale: ABORTED naming the current one.
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::UpdateMetadata, update, &updated),
              grpc::StatusCode::ABORTED, updated.etag());

  v1::Lock lock;
  ASSERT_RPC(Acquire("bob", &lock));
  for (int i = 0; i < 4; ++i) {
    ASSERT_RPC(Commit("bob", lock.lock_id(), 2 + i, Contours(300, 10 + i)));
  }
  v1::RevertStructureRequest revert;
  revert.set_project("atlas");
  revert.set_structure("lung");
  revert.set_lock_id(lock.lock_id());
  revert.set_base_revision(6);
  revert.set_to_revision(1);
  v1::Revision reverted;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::RevertStructure, revert, &reverted));
  EXPECT_EQ(reverted.number(), 7);
  EXPECT_EQ(reverted.kind(), "revert");
  EXPECT_EQ(reverted.content_sha256(), Hash(lung_content_));
  EXPECT_EQ(reverted.metadata().colour().r(), 0);  // revision 1's metadata too

  // History: newest first, three per page, one chain.
  std::vector<v1::Revision> history;
  v1::ListRevisionsRequest list;
  list.set_project("atlas");
  list.set_structure("lung");
  list.set_page_size(3);
  int pages = 0;
  do {
    v1::ListRevisionsResponse page;
    ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::ListRevisions, list, &page));
    history.insert(history.end(), page.revisions().begin(), page.revisions().end());
    list.set_page_token(page.next_page_token());
    ++pages;
  } while (!list.page_token().empty());
  EXPECT_EQ(pages, 3);
  ASSERT_EQ(history.size(), 7u);
  for (size_t i = 0; i < history.size(); ++i) {
    EXPECT_EQ(history[i].number(), 7 - static_cast<int64_t>(i));
    EXPECT_EQ(history[i].parent(), 6 - static_cast<int64_t>(i));
  }
  v1::GetRevisionRequest get;
  get.set_project("atlas");
  get.set_structure("lung");
  v1::Revision head;
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::GetRevision, get, &head));
  EXPECT_EQ(head.number(), 7);
  get.set_revision(9);
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::GetRevision, get, &head),
              grpc::StatusCode::NOT_FOUND, "revision 9");
}

TEST_F(AtlasServiceTest, SnapshotsAreTaggedAndFoundByTag) {
  ASSERT_RPC(Create("bob", "heart", Contours(500, 20)));
  v1::CreateSnapshotRequest create;
  create.set_project("atlas");
  create.set_name("baseline");
  v1::Snapshot snapshot;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateSnapshot, create, &snapshot));
  EXPECT_EQ(snapshot.members_size(), 2);
  v1::TagSnapshotRequest tag;
  tag.set_project("atlas");
  tag.set_snapshot_id(snapshot.id());
  tag.set_tag("paper-2026");
  v1::Snapshot tagged;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::TagSnapshot, tag, &tagged));
  ASSERT_EQ(tagged.tags_size(), 1);
  EXPECT_EQ(tagged.tags(0), "paper-2026");
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::TagSnapshot, tag, &tagged),
              grpc::StatusCode::ALREADY_EXISTS, "paper-2026");

  // A later commit does not move the snapshot.
  v1::Lock lock;
  ASSERT_RPC(Acquire("bob", &lock));
  ASSERT_RPC(Commit("bob", lock.lock_id(), 1, Contours(300, 21)));
  v1::GetSnapshotRequest get;
  get.set_project("atlas");
  get.set_snapshot("paper-2026");
  v1::Snapshot found;
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::GetSnapshot, get, &found));
  EXPECT_EQ(found.id(), snapshot.id());
  std::map<std::string, int64_t> members;
  for (const auto& member : found.members()) members[member.structure()] = member.revision();
  EXPECT_EQ(members, (std::map<std::string, int64_t>{{"heart", 1}, {"lung", 1}}));
  get.set_snapshot(std::to_string(snapshot.id()));
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::GetSnapshot, get, &found));
  EXPECT_EQ(found.name(), "baseline");
  v1::ListSnapshotsRequest list;
  list.set_project("atlas");
  v1::ListSnapshotsResponse listed;
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::ListSnapshots, list, &listed));
  ASSERT_EQ(listed.snapshots_size(), 1);
  EXPECT_EQ(listed.snapshots(0).members_size(), 0);

  v1::ListStructuresRequest structures;
  structures.set_project("atlas");
  v1::ListStructuresResponse all;
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::ListStructures, structures, &all));
  ASSERT_EQ(all.structures_size(), 2);
  EXPECT_EQ(all.structures(0).name(), "heart");
  EXPECT_EQ(all.structures(1).name(), "lung");
  EXPECT_EQ(all.structures(1).lock().holder(), "bob");
  EXPECT_TRUE(all.structures(1).lock().lock_id().empty());
}

TEST_F(AtlasServiceTest, HostileNamesAreInvalidArguments) {
  for (const std::string& name :
       std::vector<std::string>{"a/b", "it's", "\"quoted\"", "../up", std::string("nul\0x", 5)}) {
    v1::CreateProjectRequest create;
    create.set_name(name);
    v1::Project project;
    EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateProject, create, &project),
                grpc::StatusCode::INVALID_ARGUMENT, "name");
    EXPECT_EQ(Create("bob", name, Contours(300, 30)).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT)
        << name;
  }
  v1::ListProjectsRequest list;
  v1::ListProjectsResponse projects;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::ListProjects, list, &projects));
  ASSERT_EQ(projects.projects_size(), 1);
  EXPECT_EQ(projects.projects(0).role(), v1::EDITOR);
}

// Reads a Watch stream on its own thread.
class Watcher {
 public:
  Watcher(v1::AtlasService::Stub& stub, const std::string& token) {
    context_.AddMetadata("authorization", "Bearer " + token);
    context_.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
    v1::WatchRequest request;
    request.set_project("atlas");
    reader_ = stub.Watch(&context_, request);
    thread_ = std::thread([this] {
      v1::AtlasEvent event;
      while (reader_->Read(&event)) {
        std::lock_guard lock(mutex_);
        events_.push_back(event);
      }
      status_ = reader_->Finish();
      done_ = true;
    });
  }
  ~Watcher() {
    context_.TryCancel();
    thread_.join();
  }
  std::vector<v1::AtlasEvent> events() {
    std::lock_guard lock(mutex_);
    return events_;
  }
  bool WaitFor(size_t count) {
    return testing::WaitUntil([&] { return events().size() >= count || done_; }) &&
           events().size() >= count;
  }
  bool done() const { return done_; }
  const grpc::Status& status() const { return status_; }

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReader<v1::AtlasEvent>> reader_;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<v1::AtlasEvent> events_;
  std::atomic<bool> done_{false};
  grpc::Status status_;
};

TEST_F(AtlasServiceTest, WatchSendsReadyThenAnotherClientsChangesInOrder) {
  {
    grpc::ClientContext context;
    Authorize(&context, "dave");
    v1::WatchRequest request;
    request.set_project("atlas");
    auto reader = stub_->Watch(&context, request);
    v1::AtlasEvent event;
    EXPECT_FALSE(reader->Read(&event));
    EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::PERMISSION_DENIED);
  }
  Watcher watcher(*stub_, tokens_["carol"]);
  ASSERT_TRUE(watcher.WaitFor(1));
  EXPECT_EQ(watcher.events()[0].kind(), v1::AtlasEvent::READY);

  // Another client (its own channel) changes the structure.
  auto channel = grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials());
  stub_ = v1::AtlasService::NewStub(channel);
  v1::Lock lock;
  ASSERT_RPC(Acquire("bob", &lock));
  v1::Revision revision;
  ASSERT_RPC(Commit("bob", lock.lock_id(), 1, Contours(300, 40), &revision));
  ASSERT_RPC(Release("bob", lock.lock_id()));

  ASSERT_TRUE(watcher.WaitFor(4));
  const std::vector<v1::AtlasEvent> events = watcher.events();
  ASSERT_EQ(events.size(), 4u);
  EXPECT_EQ(events[1].kind(), v1::AtlasEvent::LOCK_ACQUIRED);
  EXPECT_EQ(events[2].kind(), v1::AtlasEvent::COMMITTED);
  EXPECT_EQ(events[2].revision(), 2);
  EXPECT_EQ(events[2].structure(), "lung");
  EXPECT_EQ(events[2].user(), "bob");
  EXPECT_EQ(events[2].detail(), "edit by bob");
  EXPECT_EQ(events[3].kind(), v1::AtlasEvent::LOCK_RELEASED);

  // The audit log has them, newest first.
  const std::vector<v1::AuditEntry> audit = Audit();
  ASSERT_GE(audit.size(), 3u);
  EXPECT_EQ(audit[0].action(), "lock.release");
  EXPECT_EQ(audit[1].action(), "revision.commit");
  EXPECT_EQ(audit[1].revision(), 2);
  EXPECT_EQ(audit[1].user(), "bob");
  EXPECT_EQ(audit[2].action(), "lock.acquire");
  EXPECT_GT(audit[0].sequence(), audit[1].sequence());
}

TEST_F(AtlasServiceTest, ShutdownEndsAnOpenWatch) {
  Watcher watcher(*stub_, tokens_["carol"]);
  ASSERT_TRUE(watcher.WaitFor(1));
  const auto start = std::chrono::steady_clock::now();
  server_->Shutdown();
  ASSERT_TRUE(testing::WaitUntil([&] { return watcher.done(); }));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
  EXPECT_EQ(watcher.status().error_code(), grpc::StatusCode::UNAVAILABLE);
}

// 8 clients x 10 rounds of acquire, commit on the head they believe, release:
// every commit lands or is refused naming the head, and the history stays one
// chain with a revision per landed commit.
TEST_F(AtlasServiceTest, RacingClientsBuildOneChain) {
  constexpr int kClients = 8;
  constexpr int kRounds = 10;
  std::atomic<int> landed{0};
  std::atomic<int> stale{0};
  std::atomic<int> unexpected{0};
  std::vector<std::thread> clients;
  for (int c = 0; c < kClients; ++c) {
    clients.emplace_back([&, c] {
      auto channel = grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials());
      auto stub = v1::AtlasService::NewStub(channel);
      auto call = [&](auto method, const auto& request, auto* response) {
        grpc::ClientContext context;
        context.AddMetadata("authorization", "Bearer " + tokens_["bob"]);
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
        return ((*stub).*method)(&context, request, response);
      };
      int64_t believed_head = 1;
      for (int round = 0; round < kRounds; ++round) {
        const std::string content = Contours(200, 1000 * c + round);
        v1::BeginUploadRequest begin;
        begin.set_size_bytes(static_cast<int64_t>(content.size()));
        begin.set_sha256(Hash(content));
        v1::Upload upload;
        if (!call(&v1::AtlasService::Stub::BeginUpload, begin, &upload).ok()) {
          ++unexpected;
          continue;
        }
        {
          grpc::ClientContext context;
          context.AddMetadata("authorization", "Bearer " + tokens_["bob"]);
          auto writer = stub->WriteUpload(&context, &upload);
          v1::UploadChunk chunk;
          chunk.set_upload_id(upload.id());
          chunk.set_data(content);
          writer->Write(chunk);
          writer->WritesDone();
          if (!writer->Finish().ok()) ++unexpected;
        }
        v1::AcquireLockRequest acquire;
        acquire.set_project("atlas");
        acquire.set_structure("lung");
        v1::Lock lock;
        grpc::Status status;
        // Someone else may hold it: wait for a turn.
        for (int attempt = 0; attempt < 2000; ++attempt) {
          status = call(&v1::AtlasService::Stub::AcquireLock, acquire, &lock);
          if (status.error_code() != grpc::StatusCode::FAILED_PRECONDITION) break;
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        if (!status.ok()) {
          ++unexpected;
          continue;
        }
        v1::CommitStructureRequest commit;
        commit.set_project("atlas");
        commit.set_structure("lung");
        commit.set_lock_id(lock.lock_id());
        commit.set_base_revision(believed_head);
        commit.set_format(v1::CONTOURS_JSON);
        commit.set_upload_id(upload.id());
        v1::Revision revision;
        status = call(&v1::AtlasService::Stub::CommitStructure, commit, &revision);
        if (status.ok()) {
          ++landed;
          believed_head = revision.number();
        } else if (status.error_code() == grpc::StatusCode::ABORTED &&
                   Contains(status.error_message(), "the head is revision")) {
          ++stale;
          // Learn the head from the refusal, as a client would re-read it.
          const std::string& message = status.error_message();
          const size_t at = message.find("the head is revision ") + 21;
          believed_head = std::stoll(message.substr(at));
        } else {
          ++unexpected;
        }
        v1::ReleaseLockRequest release;
        release.set_lock_id(lock.lock_id());
        v1::ReleaseLockResponse released;
        if (!call(&v1::AtlasService::Stub::ReleaseLock, release, &released).ok()) ++unexpected;
      }
    });
  }
  for (std::thread& client : clients) client.join();
  std::cout << landed << " commits landed, " << stale << " refused as stale\n";
  EXPECT_EQ(unexpected.load(), 0);
  EXPECT_EQ(landed + stale, kClients * kRounds);
  EXPECT_GE(landed.load(), 1);

  const v1::Structure structure = Get();
  EXPECT_EQ(structure.head(), 1 + landed.load());
  v1::ListRevisionsRequest list;
  list.set_project("atlas");
  list.set_structure("lung");
  list.set_page_size(1000);
  v1::ListRevisionsResponse history;
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::ListRevisions, list, &history));
  ASSERT_EQ(history.revisions_size(), 1 + landed.load());
  std::set<std::string> contents;
  for (int i = 0; i < history.revisions_size(); ++i) {
    EXPECT_EQ(history.revisions(i).number(), history.revisions_size() - i);
    EXPECT_EQ(history.revisions(i).parent(), history.revisions_size() - i - 1);
    contents.insert(history.revisions(i).content_sha256());
  }
  EXPECT_EQ(static_cast<int>(contents.size()), history.revisions_size());
}

TEST(CreateFirstAdminTest, OnlyWithoutUsersAndAStaleTokenFileIsReplaced) {
  TempDir dir;
  std::unique_ptr<AtlasStore> store;
  ASSERT_TRUE(AtlasStore::Open(dir.path(), &store).ok());
  const fs::path file = dir.path() / "admin.token";
  std::ofstream(file) << "a token of a database that is gone\n";
  bool created = false;
  ASSERT_TRUE(CreateFirstAdmin(*store, "admin", file, &created).ok());
  EXPECT_TRUE(created);
  std::ifstream in(file);
  std::string token;
  std::getline(in, token);
  std::string user;
  ASSERT_TRUE(store->Authenticate(token, &user).ok());
  EXPECT_EQ(user, "admin");
  struct stat info {};
  ASSERT_EQ(::stat(file.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);

  // Users exist now: nothing happens, the file stays.
  ASSERT_TRUE(CreateFirstAdmin(*store, "admin2", file, &created).ok());
  EXPECT_FALSE(created);
  std::ifstream again(file);
  std::string same;
  std::getline(again, same);
  EXPECT_EQ(same, token);
}

}  // namespace
}  // namespace pba::service_test
