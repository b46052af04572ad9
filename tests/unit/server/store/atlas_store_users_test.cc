// Users and members that can be taken away (issue 18): disabling a user
// (seen at once by another connection, as a running server sees the offline
// admin tool), removing a project member with their locks, server admins,
// the role check that comes before parsing, and a commit found again by its
// request id.
#include "unit/server/store/atlas_store_fixture.h"

namespace pba::store_test {
namespace {

TEST_F(AtlasStoreTest, ADisabledUserIsRefusedAtOnceByAnotherConnection) {
  std::string user;
  ASSERT_OK(store_->Authenticate(tokens_["bob"], &user));
  // The offline tool is another process with its own connection; the
  // server's store must not answer from anything it read before.
  std::unique_ptr<AtlasStore> offline;
  ASSERT_OK(AtlasStore::Open(dir_.path(), &offline));
  bool changed = false;
  ASSERT_OK(offline->SetUserDisabled("bob", true, &changed));
  EXPECT_TRUE(changed);
  EXPECT_STATUS(store_->Authenticate(tokens_["bob"], &user), Status::Code::kUnauthenticated,
                "'bob' is disabled");
  // Also where the name is taken as given (a call already past the token).
  StructureInfo info;
  EXPECT_STATUS(store_->GetStructure("bob", kHippocampus, &info), Status::Code::kUnauthenticated,
                "disabled");
  ASSERT_OK(offline->SetUserDisabled("bob", true, &changed));
  EXPECT_FALSE(changed);
  ASSERT_OK(offline->SetUserDisabled("bob", false, &changed));
  EXPECT_TRUE(changed);
  ASSERT_OK(store_->Authenticate(tokens_["bob"], &user));
  EXPECT_EQ(user, "bob");
  EXPECT_STATUS(offline->SetUserDisabled("nobody", true), Status::Code::kNotFound, "'nobody'");
  auto db = RawDatabase();
  EXPECT_EQ(QueryInt(*db,
                     "SELECT COUNT(*) FROM audit_log WHERE action = 'user.disable' AND "
                     "target = 'users/bob'"),
            1);
  EXPECT_EQ(QueryInt(*db, "SELECT COUNT(*) FROM audit_log WHERE action = 'user.enable'"), 1);
}

TEST_F(AtlasStoreTest, ServerAdminsAreMadeSoAndSaidSoByAuthenticate) {
  std::string token;
  ASSERT_OK(store_->CreateUser("root", &token, /*server_admin=*/true));
  std::string user;
  bool server_admin = false;
  ASSERT_OK(store_->Authenticate(token, &user, &server_admin));
  EXPECT_TRUE(server_admin);
  ASSERT_OK(store_->Authenticate(tokens_["alice"], &user, &server_admin));
  EXPECT_FALSE(server_admin) << "a project admin is no server admin";
  // No project right follows from it.
  StructureInfo info;
  EXPECT_STATUS(store_->GetStructure("root", kHippocampus, &info), Status::Code::kPermissionDenied,
                "not a member");
}

TEST_F(AtlasStoreTest, AnAdminRemovesAMemberAndTheirLocksGoWithThem) {
  const LockInfo lock = Lock("bob");
  std::vector<std::string> released;
  EXPECT_STATUS(store_->RemoveMember("bob", "atlas", "carol", &released),
                Status::Code::kPermissionDenied, "needs admin");
  EXPECT_STATUS(store_->RemoveMember("alice", "atlas", "dave", &released), Status::Code::kNotFound,
                "'dave' is not a member");
  EXPECT_STATUS(store_->RemoveMember("alice", "atlas", "nobody", &released),
                Status::Code::kNotFound, "'nobody' does not exist");
  ASSERT_OK(store_->RemoveMember("alice", "atlas", "bob", &released));
  EXPECT_EQ(released, std::vector<std::string>{"hippocampus"});
  bool member = true;
  Role role = Role::kViewer;
  ASSERT_OK(store_->RoleOf("atlas", "bob", &role, &member));
  EXPECT_FALSE(member);
  StructureInfo info;
  EXPECT_STATUS(store_->GetStructure("bob", kHippocampus, &info), Status::Code::kPermissionDenied,
                "not a member");
  EXPECT_FALSE(Structure().lock.has_value()) << "the removed member's lock must be released";
  // Their old lock id no longer commits, even after they are back.
  ASSERT_OK(store_->SetRole("alice", "atlas", "bob", Role::kEditor));
  EXPECT_STATUS(Commit("bob", lock.lock_id, 1, "contours v2"), Status::Code::kFailedPrecondition,
                "not locked");
  const std::map<std::string, int> counts = AuditCounts();
  EXPECT_EQ(counts.at("member.remove"), 1);
  EXPECT_EQ(counts.at("lock.break"), 1);
}

TEST_F(AtlasStoreTest, TheLastAdminCannotBeRemoved) {
  std::vector<std::string> released;
  EXPECT_STATUS(store_->RemoveMember("alice", "atlas", "alice", &released),
                Status::Code::kFailedPrecondition, "last admin");
  ASSERT_OK(store_->SetRole("alice", "atlas", "bob", Role::kAdmin));
  // With a second admin, one may go (even by their own hand).
  ASSERT_OK(store_->RemoveMember("alice", "atlas", "alice", &released));
  EXPECT_STATUS(store_->RemoveMember("bob", "atlas", "bob", &released),
                Status::Code::kFailedPrecondition, "last admin");
}

TEST_F(AtlasStoreTest, CheckRoleRefusesBeforeAnythingIsRead) {
  ASSERT_OK(store_->CheckRole("bob", "atlas", Role::kEditor));
  EXPECT_STATUS(store_->CheckRole("carol", "atlas", Role::kEditor), Status::Code::kPermissionDenied,
                "needs editor");
  EXPECT_STATUS(store_->CheckRole("dave", "atlas", Role::kViewer), Status::Code::kPermissionDenied,
                "not a member");
  EXPECT_STATUS(store_->CheckRole("dave", "elsewhere", Role::kViewer), Status::Code::kNotFound,
                "'elsewhere'");
}

TEST_F(AtlasStoreTest, FindCommitReturnsWhatACommitWithTheRequestIdMade) {
  const LockInfo lock = Lock("bob");
  CommitRequest request;
  request.structure = kHippocampus;
  request.lock_id = lock.lock_id;
  request.base_revision = 1;
  request.geometry = "contours v2";
  request.request_id = "commit-1";
  Revision made;
  ASSERT_OK(store_->Commit("bob", request, &made));
  Revision found_revision;
  bool found = false;
  ASSERT_OK(store_->FindCommit("bob", kHippocampus, "commit-1", &found_revision, &found));
  EXPECT_TRUE(found);
  EXPECT_EQ(found_revision.number, made.number);
  EXPECT_EQ(found_revision.content_sha256, made.content_sha256);
  ASSERT_OK(store_->FindCommit("bob", kHippocampus, "other", &found_revision, &found));
  EXPECT_FALSE(found);
  ASSERT_OK(store_->FindCommit("bob", kHippocampus, "", &found_revision, &found));
  EXPECT_FALSE(found);
  ASSERT_OK(store_->SetRole("alice", "atlas", "carol", Role::kEditor));
  EXPECT_STATUS(store_->FindCommit("carol", kHippocampus, "commit-1", &found_revision, &found),
                Status::Code::kAlreadyExists, "another user's commit");
  EXPECT_STATUS(store_->FindCommit("dave", kHippocampus, "commit-1", &found_revision, &found),
                Status::Code::kPermissionDenied, "not a member");
}

}  // namespace
}  // namespace pba::store_test
