// The atlas service's idempotent creates (request_id on CreateProject,
// CreateStructure and CreateSnapshot), what a refused create leaves of its
// upload, and the bounds of page sizes.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "unit/server/service/atlas_service_fixture.h"

namespace pba::service_test {
namespace {

std::map<std::string, int> Actions(const std::vector<v1::AuditEntry>& entries) {
  std::map<std::string, int> counts;
  for (const v1::AuditEntry& entry : entries) ++counts[entry.action()];
  return counts;
}

TEST_F(AtlasServiceTest, ARepeatedCreateRequestIdReturnsWhatTheFirstMade) {
  // Projects.
  v1::CreateProjectRequest project;
  project.set_name("cortex");
  project.set_request_id("p-1");
  v1::Project made, again;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateProject, project, &made));
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateProject, project, &again));
  EXPECT_EQ(again.name(), "cortex");
  EXPECT_EQ(again.create_time().seconds(), made.create_time().seconds());
  EXPECT_EQ(again.create_time().nanos(), made.create_time().nanos());
  project.set_name("cerebellum");
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateProject, project, &again),
              grpc::StatusCode::INVALID_ARGUMENT, "request_id");
  project.set_name("cortex");
  project.set_request_id("");
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateProject, project, &again),
              grpc::StatusCode::ALREADY_EXISTS, "cortex");

  // Structures: the retry names the upload the first create consumed.
  const size_t audit_before = Audit().size();
  const std::string content = Contours(3000, 7);
  v1::CreateStructureRequest create;
  create.set_project("atlas");
  create.set_name("heart");
  create.set_format(v1::CONTOURS_JSON);
  create.set_upload_id(Upload("bob", content));
  create.set_message("first outline");
  create.set_request_id("s-1");
  v1::Revision first, replay;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &first));
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &replay));
  EXPECT_EQ(replay.number(), 1);
  EXPECT_EQ(replay.content_sha256(), Hash(content));
  EXPECT_EQ(replay.time().seconds(), first.time().seconds());
  EXPECT_EQ(replay.time().nanos(), first.time().nanos());
  // A rerun that uploaded again: its upload is discarded unused.
  v1::Upload fresh;
  create.set_upload_id(Upload("bob", content));
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &replay));
  v1::GetUploadRequest get_upload;
  get_upload.set_upload_id(create.upload_id());
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::GetUpload, get_upload, &fresh),
              grpc::StatusCode::NOT_FOUND, "does not exist");
  create.set_message("another outline");
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &replay),
              grpc::StatusCode::INVALID_ARGUMENT, "request_id");

  // Snapshots, unnamed: the server names them, and a retry matches.
  v1::CreateSnapshotRequest snapshot;
  snapshot.set_project("atlas");
  snapshot.set_request_id("n-1");
  v1::Snapshot pinned, repinned;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateSnapshot, snapshot, &pinned));
  EXPECT_EQ(pinned.name().rfind("snapshot ", 0), 0u) << pinned.name();
  EXPECT_EQ(pinned.members_size(), 2);
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateSnapshot, snapshot, &repinned));
  EXPECT_EQ(repinned.id(), pinned.id());
  EXPECT_EQ(repinned.name(), pinned.name());
  // carol's key is hers, and she may not snapshot.
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::CreateSnapshot, snapshot, &repinned),
              grpc::StatusCode::PERMISSION_DENIED, "editor");
  // Another user's identical key is a snapshot of its own.
  ASSERT_RPC(Call("admin", &v1::AtlasService::Stub::CreateSnapshot, snapshot, &repinned));
  EXPECT_NE(repinned.id(), pinned.id());

  // One audit entry per create that happened.
  const std::vector<v1::AuditEntry> audit = Audit();
  EXPECT_EQ(audit.size(), audit_before + 3);
  const std::map<std::string, int> actions = Actions(audit);
  EXPECT_EQ(actions.at("structure.create"), 2);  // lung (SetUp) and heart
  EXPECT_EQ(actions.at("snapshot.create"), 2);   // bob's and admin's
}

TEST_F(AtlasServiceTest, ARefusedCreateLeavesNoBlobAndTheUploadWhole) {
  // Fails the geometry check: a NIfTI without its header.
  const std::string bad(400, '\x07');
  v1::CreateStructureRequest create;
  create.set_project("atlas");
  create.set_name("heart");
  create.set_format(v1::NIFTI);
  create.set_upload_id(Upload("bob", bad));
  v1::Revision revision;
  EXPECT_CODE(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision),
              grpc::StatusCode::INVALID_ARGUMENT, "NIfTI");
  const std::string hash = Hash(bad);
  const fs::path blobs = options_.data_dir / "blobs";
  EXPECT_FALSE(fs::exists(blobs / hash.substr(0, 2) / hash.substr(2)));
  v1::GetUploadRequest get;
  get.set_upload_id(create.upload_id());
  v1::Upload upload;
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::GetUpload, get, &upload));
  EXPECT_EQ(upload.received_bytes(), 400);
  EXPECT_TRUE(fs::exists(options_.data_dir / "uploads" / create.upload_id()));

  // A create that lands moves the upload into its blob and leaves nothing.
  const std::string good = Contours(5000, 9);
  create.set_format(v1::CONTOURS_JSON);
  create.set_upload_id(Upload("bob", good));
  ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision));
  EXPECT_EQ(revision.content_sha256(), Hash(good));
  EXPECT_FALSE(fs::exists(options_.data_dir / "uploads" / create.upload_id()));
  EXPECT_FALSE(fs::exists(options_.data_dir / "uploads" / (create.upload_id() + ".meta")));
  const fs::path blob =
      blobs / revision.content_sha256().substr(0, 2) / revision.content_sha256().substr(2);
  std::ifstream in(blob, std::ios::binary);
  const std::string stored((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(stored == good);
}

TEST_F(AtlasServiceTest, NegativePageSizesAreInvalidArgumentsNamingPageSize) {
  v1::ListProjectsRequest projects;
  projects.set_page_size(-1);
  v1::ListProjectsResponse listed_projects;
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::ListProjects, projects, &listed_projects),
              grpc::StatusCode::INVALID_ARGUMENT, "page_size");
  v1::ListStructuresRequest structures;
  structures.set_project("atlas");
  structures.set_page_size(-5);
  v1::ListStructuresResponse listed_structures;
  EXPECT_CODE(
      Call("carol", &v1::AtlasService::Stub::ListStructures, structures, &listed_structures),
      grpc::StatusCode::INVALID_ARGUMENT, "page_size");
  v1::ListRevisionsRequest revisions;
  revisions.set_project("atlas");
  revisions.set_structure("lung");
  revisions.set_page_size(-1);
  v1::ListRevisionsResponse listed_revisions;
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::ListRevisions, revisions, &listed_revisions),
              grpc::StatusCode::INVALID_ARGUMENT, "page_size");
  v1::ListSnapshotsRequest snapshots;
  snapshots.set_project("atlas");
  snapshots.set_page_size(-2147483647 - 1);
  v1::ListSnapshotsResponse listed_snapshots;
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::ListSnapshots, snapshots, &listed_snapshots),
              grpc::StatusCode::INVALID_ARGUMENT, "page_size");
  v1::ListAuditRequest audit;
  audit.set_project("atlas");
  audit.set_page_size(-1);
  v1::ListAuditResponse listed_audit;
  EXPECT_CODE(Call("carol", &v1::AtlasService::Stub::ListAudit, audit, &listed_audit),
              grpc::StatusCode::INVALID_ARGUMENT, "page_size");
  // Zero is the default and a large size is capped, not refused.
  structures.set_page_size(0);
  ASSERT_RPC(
      Call("carol", &v1::AtlasService::Stub::ListStructures, structures, &listed_structures));
  EXPECT_EQ(listed_structures.structures_size(), 1);
  audit.set_page_size(1 << 30);
  ASSERT_RPC(Call("carol", &v1::AtlasService::Stub::ListAudit, audit, &listed_audit));
  EXPECT_GT(listed_audit.entries_size(), 0);
}

}  // namespace
}  // namespace pba::service_test
