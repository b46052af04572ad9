// Users, projects, structures, locks, commits, metadata, history,
// snapshots and the audit log of the atlas store.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "unit/server/store/atlas_store_fixture.h"

namespace pba::store_test {
namespace {

TEST_F(AtlasStoreTest, TokensAuthenticateAndOnlyTheirHashIsStored) {
  const std::string& token = tokens_["bob"];
  ASSERT_EQ(token.size(), 64u);
  EXPECT_TRUE(IsSha256Hex(token)) << token;
  EXPECT_NE(tokens_["alice"], token);
  std::string user;
  ASSERT_OK(store_->Authenticate(token, &user));
  EXPECT_EQ(user, "bob");

  std::string wrong = token;
  wrong[0] = wrong[0] == 'a' ? 'b' : 'a';
  EXPECT_STATUS(store_->Authenticate(wrong, &user), Status::Code::kUnauthenticated, "unknown");
  EXPECT_STATUS(store_->Authenticate("not a token", &user), Status::Code::kUnauthenticated,
                "malformed");
  const Status refused = store_->Authenticate(wrong, &user);
  EXPECT_FALSE(Contains(refused.ToString(), wrong)) << "the message echoes the token";

  auto db = RawDatabase();
  Statement stmt;
  ASSERT_OK(db->Prepare("SELECT token_sha256 FROM users WHERE name = 'bob'", &stmt));
  bool row = false;
  ASSERT_OK(stmt.Step(&row));
  ASSERT_TRUE(row);
  EXPECT_EQ(stmt.ColumnText(0), Hash(token));
  stmt = Statement();
  EXPECT_EQ(QueryInt(*db, "SELECT COUNT(*) FROM users WHERE token_sha256 = '" + token + "'"), 0);

  std::string again;
  EXPECT_STATUS(store_->CreateUser("bob", &again), Status::Code::kAlreadyExists, "bob");

  // A disabled user is refused even with the right token.
  ASSERT_OK(db->Exec("UPDATE users SET disabled = 1 WHERE name = 'bob'"));
  EXPECT_STATUS(store_->Authenticate(token, &user), Status::Code::kUnauthenticated, "disabled");
  LockInfo lock;
  EXPECT_STATUS(store_->AcquireLock("bob", kHippocampus, kSecond, &lock),
                Status::Code::kUnauthenticated, "disabled");
}

TEST_F(AtlasStoreTest, RolesAreSetByAdminsAndTheLastAdminStays) {
  Role role = Role::kViewer;
  bool member = false;
  ASSERT_OK(store_->RoleOf("atlas", "alice", &role, &member));
  EXPECT_TRUE(member);
  EXPECT_EQ(role, Role::kAdmin);
  ASSERT_OK(store_->RoleOf("atlas", "bob", &role, &member));
  EXPECT_EQ(role, Role::kEditor);
  ASSERT_OK(store_->RoleOf("atlas", "dave", &role, &member));
  EXPECT_FALSE(member);
  EXPECT_STATUS(store_->RoleOf("nowhere", "dave", &role, &member), Status::Code::kNotFound,
                "nowhere");

  EXPECT_STATUS(store_->SetRole("bob", "atlas", "dave", Role::kEditor),
                Status::Code::kPermissionDenied, "needs admin");
  EXPECT_STATUS(store_->SetRole("dave", "atlas", "dave", Role::kAdmin),
                Status::Code::kPermissionDenied, "not a member");
  EXPECT_STATUS(store_->SetRole("alice", "atlas", "erin", Role::kEditor), Status::Code::kNotFound,
                "erin");
  EXPECT_STATUS(store_->SetRole("alice", "atlas", "alice", Role::kEditor),
                Status::Code::kFailedPrecondition, "last admin");
  ASSERT_OK(store_->SetRole("alice", "atlas", "bob", Role::kAdmin));
  ASSERT_OK(store_->SetRole("bob", "atlas", "alice", Role::kViewer));
  ASSERT_OK(store_->RoleOf("atlas", "alice", &role, &member));
  EXPECT_EQ(role, Role::kViewer);

  const std::map<std::string, int> counts = AuditCounts();
  EXPECT_EQ(counts.at("member.set_role"), 4);  // SetUp's two and the two above
}

TEST_F(AtlasStoreTest, ListProjectsPagesThroughTheCallersProjects) {
  for (int i = 0; i < 6; ++i) ASSERT_OK(store_->CreateProject("dave", "p" + std::to_string(i)));
  std::vector<ProjectInfo> page;
  std::string token;
  ASSERT_OK(store_->ListProjects("dave", 4, "", &page, &token));
  ASSERT_EQ(page.size(), 4u);
  EXPECT_EQ(page[0].name, "p0");
  EXPECT_EQ(page[0].role, Role::kAdmin);
  EXPECT_EQ(page[0].created_by, "dave");
  ASSERT_FALSE(token.empty());
  const std::string dave_token = token;
  ASSERT_OK(store_->ListProjects("dave", 4, token, &page, &token));
  ASSERT_EQ(page.size(), 2u);
  EXPECT_EQ(page[1].name, "p5");
  EXPECT_TRUE(token.empty());

  // Only projects the user is a member of.
  ASSERT_OK(store_->ListProjects("carol", 0, "", &page, &token));
  ASSERT_EQ(page.size(), 1u);
  EXPECT_EQ(page[0].name, "atlas");
  EXPECT_EQ(page[0].role, Role::kViewer);

  EXPECT_STATUS(store_->ListProjects("dave", -1, "", &page, &token), Status::Code::kInvalidArgument,
                "page_size");
  EXPECT_STATUS(store_->ListProjects("dave", 2, "garbage", &page, &token),
                Status::Code::kInvalidArgument, "page_token");
  // Another user's token pages another listing.
  EXPECT_STATUS(store_->ListProjects("carol", 2, dave_token, &page, &token),
                Status::Code::kInvalidArgument, "page_token");
  EXPECT_STATUS(store_->CreateProject("dave", "p0"), Status::Code::kAlreadyExists, "p0");
}

TEST_F(AtlasStoreTest, ListStructuresPagesByNameForViewers) {
  // Created out of name order: the listing sorts by name, not by creation.
  for (const char* name : {"thalamus", "amygdala", "pons", "cerebellum", "insula"}) {
    Revision revision;
    ASSERT_OK(store_->CreateStructure("bob", {"atlas", name}, Metadata(), StructureFormat::kStl,
                                      "solid", &revision));
  }
  const LockInfo lock = Lock("bob", {"atlas", "insula"});
  std::vector<std::string> names;
  std::vector<StructureInfo> page;
  std::string token;
  int pages = 0;
  do {
    ASSERT_OK(store_->ListStructures("carol", "atlas", 4, token, &page, &token));
    ++pages;
    for (const StructureInfo& info : page) {
      names.push_back(info.name);
      EXPECT_EQ(info.project, "atlas");
      EXPECT_EQ(info.head, 1);
      EXPECT_EQ(info.metadata, Metadata());
      EXPECT_FALSE(info.metadata_etag.empty());
      EXPECT_EQ(info.created_us, kStart);
      if (info.name == "insula") {
        ASSERT_TRUE(info.lock.has_value());
        EXPECT_EQ(info.lock->owner, "bob");
        EXPECT_TRUE(info.lock->lock_id.empty()) << "only the holder knows the lock id";
        EXPECT_EQ(info.lock->lease_expiry_us, lock.lease_expiry_us);
      } else {
        EXPECT_FALSE(info.lock.has_value()) << info.name;
      }
    }
  } while (!token.empty());
  EXPECT_EQ(pages, 2);
  EXPECT_EQ(names, (std::vector<std::string>{"amygdala", "cerebellum", "hippocampus", "insula",
                                             "pons", "thalamus"}));

  // GetStructure shows the lock the same way.
  const StructureInfo insula = Structure({"atlas", "insula"});
  ASSERT_TRUE(insula.lock.has_value());
  EXPECT_EQ(insula.lock->owner, "bob");
  EXPECT_TRUE(insula.lock->lock_id.empty());
  EXPECT_FALSE(Structure().lock.has_value());

  ASSERT_OK(store_->ListStructures("carol", "atlas", 0, "", &page, &token));
  EXPECT_EQ(page.size(), 6u);
  EXPECT_TRUE(token.empty());
  EXPECT_STATUS(store_->ListStructures("dave", "atlas", 0, "", &page, &token),
                Status::Code::kPermissionDenied, "not a member");
  EXPECT_STATUS(store_->ListStructures("carol", "nowhere", 0, "", &page, &token),
                Status::Code::kNotFound, "nowhere");
  EXPECT_STATUS(store_->ListStructures("carol", "atlas", -1, "", &page, &token),
                Status::Code::kInvalidArgument, "page_size");
  // A token of another listing is refused.
  std::vector<Revision> history;
  std::string history_token;
  for (int i = 0; i < 2; ++i) {
    Revision revision;
    std::string etag;
    ASSERT_OK(store_->UpdateMetadata("bob", kHippocampus, Structure().metadata_etag,
                                     {Colour{i, 0, 0}, std::nullopt, std::nullopt}, "", &revision,
                                     &etag));
  }
  ASSERT_OK(store_->History("carol", kHippocampus, 1, "", &history, &history_token));
  ASSERT_FALSE(history_token.empty());
  EXPECT_STATUS(store_->ListStructures("carol", "atlas", 2, history_token, &page, &token),
                Status::Code::kInvalidArgument, "page_token");
}

TEST_F(AtlasStoreTest, CountUsersCountsEveryUser) {
  int64_t count = 0;
  ASSERT_OK(store_->CountUsers(&count));
  EXPECT_EQ(count, 4);
}

TEST_F(AtlasStoreTest, ReleaseAndBreakNameWhatTheyRemoved) {
  LockInfo lock = Lock("bob");
  EXPECT_EQ(lock.structure.project, "atlas");
  EXPECT_EQ(lock.structure.structure, "hippocampus");
  LockInfo renewed;
  ASSERT_OK(store_->RenewLock("bob", lock.lock_id, 60 * kSecond, &renewed));
  EXPECT_EQ(renewed.structure.structure, "hippocampus");
  StructureRef released;
  ASSERT_OK(store_->ReleaseLock("bob", lock.lock_id, &released));
  EXPECT_EQ(released.project, "atlas");
  EXPECT_EQ(released.structure, "hippocampus");
  Lock("bob");
  std::string holder;
  ASSERT_OK(store_->BreakLock("alice", kHippocampus, "bob is on leave", &holder));
  EXPECT_EQ(holder, "bob");
}

TEST_F(AtlasStoreTest, CreateStructureStoresRevisionOneAndItsBlob) {
  Revision revision;
  std::string geometry;
  ASSERT_OK(store_->GetRevision("carol", kHippocampus, 1, &revision, &geometry));
  EXPECT_EQ(revision.number, 1);
  EXPECT_EQ(revision.parent, 0);
  EXPECT_EQ(revision.author, "bob");
  EXPECT_EQ(revision.kind, "create");
  EXPECT_EQ(revision.time_us, kStart);
  EXPECT_EQ(revision.content_sha256, Hash("contours v1"));
  EXPECT_EQ(revision.size_bytes, 11);
  EXPECT_EQ(revision.format, StructureFormat::kContours);
  EXPECT_EQ(revision.metadata, Metadata());
  EXPECT_EQ(geometry, "contours v1");
  EXPECT_TRUE(fs::exists(dir_.path() / "blobs" / revision.content_sha256.substr(0, 2) /
                         revision.content_sha256.substr(2)));
  const StructureInfo info = Structure();
  EXPECT_EQ(info.head, 1);
  EXPECT_EQ(info.metadata, Metadata());
  EXPECT_FALSE(info.metadata_etag.empty());

  Revision other;
  EXPECT_STATUS(store_->CreateStructure("alice", kHippocampus, Metadata(), StructureFormat::kStl,
                                        "x", &other),
                Status::Code::kAlreadyExists, "hippocampus");
  EXPECT_STATUS(store_->CreateStructure("carol", {"atlas", "amygdala"}, Metadata(),
                                        StructureFormat::kStl, "x", &other),
                Status::Code::kPermissionDenied, "carol");
  EXPECT_STATUS(store_->CreateStructure("dave", {"atlas", "amygdala"}, Metadata(),
                                        StructureFormat::kStl, "x", &other),
                Status::Code::kPermissionDenied, "not a member");
  EXPECT_STATUS(store_->CreateStructure("bob", {"nowhere", "amygdala"}, Metadata(),
                                        StructureFormat::kStl, "x", &other),
                Status::Code::kNotFound, "nowhere");
  EXPECT_STATUS(store_->CreateStructure("bob", {"atlas", "amygdala"}, Metadata(),
                                        StructureFormat::kStl, "", &other),
                Status::Code::kInvalidArgument, "geometry");
  StructureMetadata bad = Metadata();
  bad.material_json = "{\"mu\": }";
  EXPECT_STATUS(store_->CreateStructure("bob", {"atlas", "amygdala"}, bad, StructureFormat::kStl,
                                        "x", &other),
                Status::Code::kInvalidArgument, "material_json");
  EXPECT_STATUS(store_->GetRevision("carol", kHippocampus, 2, &revision, nullptr),
                Status::Code::kNotFound, "head is revision 1");
  StructureInfo scratch;
  EXPECT_STATUS(store_->GetStructure("carol", {"atlas", "amygdala"}, &scratch),
                Status::Code::kNotFound, "amygdala");
  EXPECT_STATUS(store_->GetStructure("dave", kHippocampus, &scratch),
                Status::Code::kPermissionDenied, "dave");
}

TEST_F(AtlasStoreTest, ALockHeldByAnotherIsRefusedNamingHolderAndExpiry) {
  const LockInfo lock = Lock("bob", kHippocampus, 90 * kSecond);
  EXPECT_EQ(lock.lock_id.size(), 32u);
  EXPECT_EQ(lock.owner, "bob");
  EXPECT_EQ(lock.acquired_us, kStart);
  EXPECT_EQ(lock.lease_expiry_us, kStart + 90 * kSecond);
  EXPECT_TRUE(lock.took_over_from.empty());

  LockInfo other;
  EXPECT_STATUS(store_->AcquireLock("alice", kHippocampus, kSecond, &other),
                Status::Code::kFailedPrecondition, "locked by 'bob' until 2026-01-01T00:01:30");
  EXPECT_STATUS(store_->AcquireLock("bob", kHippocampus, kSecond, &other),
                Status::Code::kFailedPrecondition, "you, in another session");
  EXPECT_STATUS(store_->AcquireLock("carol", kHippocampus, kSecond, &other),
                Status::Code::kPermissionDenied, "needs editor");
  EXPECT_STATUS(store_->AcquireLock("bob", kHippocampus, 0, &other), Status::Code::kInvalidArgument,
                "lease");
  EXPECT_STATUS(store_->AcquireLock("bob", kHippocampus, AtlasStore::kMaxLeaseMicros + 1, &other),
                Status::Code::kInvalidArgument, "lease");
  EXPECT_STATUS(store_->AcquireLock("bob", {"atlas", "cortex"}, kSecond, &other),
                Status::Code::kNotFound, "cortex");

  // alice can neither commit under nor release bob's lock.
  EXPECT_STATUS(Commit("alice", lock.lock_id, 1, "alice's shape"),
                Status::Code::kFailedPrecondition, "locked by 'bob'");
  EXPECT_STATUS(Commit("alice", "", 1, "alice's shape"), Status::Code::kFailedPrecondition,
                "locked by 'bob'");
  EXPECT_STATUS(store_->ReleaseLock("alice", lock.lock_id), Status::Code::kFailedPrecondition,
                "another user");
  EXPECT_STATUS(store_->RenewLock("alice", lock.lock_id, kSecond, &other),
                Status::Code::kFailedPrecondition, "another user");

  ASSERT_OK(store_->ReleaseLock("bob", lock.lock_id));
  EXPECT_STATUS(store_->ReleaseLock("bob", lock.lock_id), Status::Code::kFailedPrecondition,
                "no longer held");
  EXPECT_EQ(Lock("alice").owner, "alice");

  const std::map<std::string, int> counts = AuditCounts();
  EXPECT_EQ(counts.at("lock.acquire"), 2);
  EXPECT_EQ(counts.at("lock.release"), 1);
}

TEST_F(AtlasStoreTest, CommitNeedsTheLockAndTheHeadAsBase) {
  EXPECT_STATUS(Commit("bob", "", 1, "v2"), Status::Code::kFailedPrecondition, "not locked");
  const LockInfo lock = Lock("bob");
  Revision revision;
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "v2", &revision));
  EXPECT_EQ(revision.number, 2);
  EXPECT_EQ(revision.parent, 1);
  EXPECT_EQ(revision.kind, "commit");
  EXPECT_EQ(revision.message, "edit by bob");
  EXPECT_EQ(revision.content_sha256, Hash("v2"));
  EXPECT_EQ(revision.metadata, Metadata()) << "metadata is carried over from the head";

  EXPECT_STATUS(Commit("bob", lock.lock_id, 1, "v2 again"), Status::Code::kAborted,
                "the head is revision 2");
  EXPECT_STATUS(Commit("bob", lock.lock_id, 7, "v2 again"), Status::Code::kAborted,
                "base revision 7");
  EXPECT_STATUS(Commit("bob", "0123456789abcdef0123456789abcdef", 2, "v3"),
                Status::Code::kFailedPrecondition, "not your current lock");
  ASSERT_OK(store_->SetRole("alice", "atlas", "bob", Role::kViewer));
  EXPECT_STATUS(Commit("bob", lock.lock_id, 2, "v3"), Status::Code::kPermissionDenied, "viewer");
  ASSERT_OK(store_->SetRole("alice", "atlas", "bob", Role::kEditor));
  ASSERT_OK(Commit("bob", lock.lock_id, 2, "v3", &revision));
  EXPECT_EQ(revision.number, 3);

  EXPECT_EQ(Structure().head, 3);
  EXPECT_EQ(AuditCounts().at("revision.commit"), 2);
}

// A commit retried with its request id, after it landed and the lock was
// given back, returns the revision it made: nothing new is written or
// audited. Another user cannot reuse the key.
TEST_F(AtlasStoreTest, ARepeatedCommitRequestIdReturnsTheRevisionItMade) {
  const LockInfo lock = Lock("bob");
  CommitRequest request;
  request.structure = kHippocampus;
  request.lock_id = lock.lock_id;
  request.base_revision = 1;
  request.geometry = "contours v2";
  request.message = "wider";
  request.request_id = "commit-7f3a";
  Revision first;
  bool replayed = true;
  ASSERT_OK(store_->Commit("bob", request, &first, &replayed));
  EXPECT_FALSE(replayed);
  EXPECT_EQ(first.number, 2);
  ASSERT_OK(store_->ReleaseLock("bob", lock.lock_id));
  const auto audit = AuditCounts();

  Revision again;
  ASSERT_OK(store_->Commit("bob", request, &again, &replayed));
  EXPECT_TRUE(replayed);
  EXPECT_EQ(again.number, 2);
  EXPECT_EQ(again.content_sha256, first.content_sha256);
  EXPECT_EQ(Structure().head, 2);
  EXPECT_EQ(AuditCounts(), audit);

  // The same key from alice (an admin, holding a fresh lock) is not hers.
  const LockInfo hers = Lock("alice");
  request.lock_id = hers.lock_id;
  request.base_revision = 2;
  EXPECT_STATUS(store_->Commit("alice", request, &again), Status::Code::kAlreadyExists,
                "another user's commit");
  // Without the key the same content is a new revision.
  request.request_id.clear();
  ASSERT_OK(store_->Commit("alice", request, &again, &replayed));
  EXPECT_FALSE(replayed);
  EXPECT_EQ(again.number, 3);
}

TEST_F(AtlasStoreTest, ALapsedLeaseCannotCommitOrRenewAndMayBeTakenOver) {
  const LockInfo bobs = Lock("bob", kHippocampus, 10 * kSecond);
  now_ += 9 * kSecond;
  LockInfo renewed;
  ASSERT_OK(store_->RenewLock("bob", bobs.lock_id, 10 * kSecond, &renewed));
  EXPECT_EQ(renewed.lease_expiry_us, kStart + 19 * kSecond);
  now_ += 9 * kSecond;  // 18 s: alive only thanks to the renewal
  ASSERT_OK(Commit("bob", bobs.lock_id, 1, "v2"));

  now_ += 1 * kSecond;  // 19 s: the lease has just lapsed
  EXPECT_STATUS(Commit("bob", bobs.lock_id, 2, "v3"), Status::Code::kFailedPrecondition,
                "lapsed at 2026-01-01T00:00:19");
  EXPECT_STATUS(store_->RenewLock("bob", bobs.lock_id, 10 * kSecond, &renewed),
                Status::Code::kFailedPrecondition, "lapsed");
  // Another user sees the lapse too.
  EXPECT_STATUS(Commit("alice", "", 2, "v3"), Status::Code::kFailedPrecondition,
                "whose lease lapsed");

  LockInfo alices;
  ASSERT_OK(store_->AcquireLock("alice", kHippocampus, 10 * kSecond, &alices));
  EXPECT_EQ(alices.took_over_from, "bob");
  EXPECT_NE(alices.lock_id, bobs.lock_id);
  EXPECT_STATUS(Commit("bob", bobs.lock_id, 2, "v3"), Status::Code::kFailedPrecondition,
                "locked by 'alice'");
  EXPECT_STATUS(store_->ReleaseLock("bob", bobs.lock_id), Status::Code::kFailedPrecondition,
                "no longer held");
  ASSERT_OK(Commit("alice", alices.lock_id, 2, "v3"));

  const std::vector<AuditEntry> audit = FullAudit();
  const auto takeover = std::find_if(audit.begin(), audit.end(), [](const AuditEntry& entry) {
    return entry.action == "lock.takeover";
  });
  ASSERT_NE(takeover, audit.end());
  EXPECT_EQ(takeover->user, "alice");
  EXPECT_TRUE(Contains(takeover->detail, "bob")) << takeover->detail;
  EXPECT_TRUE(Contains(takeover->detail, "lapsed")) << takeover->detail;
  EXPECT_EQ(AuditCounts().at("lock.renew"), 1);
}

TEST_F(AtlasStoreTest, OnlyAdminsBreakLocksAndItIsAudited) {
  const LockInfo lock = Lock("bob");
  ASSERT_OK(store_->SetRole("alice", "atlas", "dave", Role::kEditor));
  EXPECT_STATUS(store_->BreakLock("dave", kHippocampus, "stuck"), Status::Code::kPermissionDenied,
                "needs admin");
  EXPECT_STATUS(store_->BreakLock("alice", kHippocampus, ""), Status::Code::kInvalidArgument,
                "reason");
  ASSERT_OK(store_->BreakLock("alice", kHippocampus, "bob is on holiday"));
  EXPECT_STATUS(store_->BreakLock("alice", kHippocampus, "again"),
                Status::Code::kFailedPrecondition, "not locked");
  EXPECT_STATUS(Commit("bob", lock.lock_id, 1, "v2"), Status::Code::kFailedPrecondition,
                "not locked");

  const std::vector<AuditEntry> audit = FullAudit();
  ASSERT_FALSE(audit.empty());
  EXPECT_EQ(audit.front().action, "lock.break");
  EXPECT_EQ(audit.front().user, "alice");
  EXPECT_EQ(audit.front().target, "projects/atlas/structures/hippocampus");
  EXPECT_TRUE(Contains(audit.front().detail, "bob is on holiday")) << audit.front().detail;
  EXPECT_TRUE(Contains(audit.front().detail, "lock of bob")) << audit.front().detail;
}

TEST_F(AtlasStoreTest, MetadataEditsAreOptimisticAndVersioned) {
  const StructureInfo before = Structure();
  MetadataUpdate update;
  update.colour = Colour{10, 20, 30};
  Revision revision;
  std::string etag;
  ASSERT_OK(store_->UpdateMetadata("bob", kHippocampus, before.metadata_etag, update, "recolour",
                                   &revision, &etag));
  EXPECT_EQ(revision.number, 2);
  EXPECT_EQ(revision.kind, "metadata");
  EXPECT_EQ(revision.content_sha256, Hash("contours v1")) << "geometry kept";
  EXPECT_EQ(revision.metadata.colour, (Colour{10, 20, 30}));
  EXPECT_EQ(revision.metadata.group_path, Metadata().group_path);
  EXPECT_NE(etag, before.metadata_etag);
  EXPECT_EQ(Structure().metadata_etag, etag);

  // A stale etag is refused with the current one named.
  update.colour = Colour{1, 2, 3};
  EXPECT_STATUS(store_->UpdateMetadata("alice", kHippocampus, before.metadata_etag, update, "",
                                       &revision, &etag),
                Status::Code::kAborted, "the current etag is '" + Structure().metadata_etag + "'");
  EXPECT_STATUS(store_->UpdateMetadata("carol", kHippocampus, etag, update, "", &revision, &etag),
                Status::Code::kPermissionDenied, "carol");
  update.colour = Colour{1, 256, 3};
  EXPECT_STATUS(store_->UpdateMetadata("bob", kHippocampus, etag, update, "", &revision, &etag),
                Status::Code::kInvalidArgument, "colour.g");
  EXPECT_STATUS(
      store_->UpdateMetadata("bob", kHippocampus, etag, MetadataUpdate(), "", &revision, &etag),
      Status::Code::kInvalidArgument, "update");

  // A geometry-only commit keeps the etag; one that changes the material does not.
  const LockInfo lock = Lock("bob");
  ASSERT_OK(Commit("bob", lock.lock_id, 2, "v3"));
  EXPECT_EQ(Structure().metadata_etag, etag);
  ASSERT_OK(Commit("bob", lock.lock_id, 3, "v4", &revision, R"({"model": "linear_elastic"})"));
  EXPECT_EQ(revision.metadata.material_json, R"({"model": "linear_elastic"})");
  EXPECT_EQ(revision.metadata.colour, (Colour{10, 20, 30}));
  EXPECT_NE(Structure().metadata_etag, etag);

  // A metadata edit needs no lock, and moves the head under the lock holder.
  etag = Structure().metadata_etag;
  update = MetadataUpdate();
  update.group_path = "cerebrum";
  ASSERT_OK(store_->UpdateMetadata("alice", kHippocampus, etag, update, "", &revision, &etag));
  EXPECT_EQ(revision.number, 5);
  EXPECT_STATUS(Commit("bob", lock.lock_id, 4, "v5"), Status::Code::kAborted,
                "the head is revision 5");

  // No change, no revision.
  ASSERT_OK(store_->UpdateMetadata("alice", kHippocampus, etag, update, "", &revision, &etag));
  EXPECT_EQ(revision.number, 5);
  EXPECT_EQ(Structure().head, 5);
  EXPECT_EQ(AuditCounts().at("revision.metadata"), 2);
}

TEST_F(AtlasStoreTest, HistoryIsNewestFirstAndRevertAddsARevision) {
  const LockInfo lock = Lock("bob");
  for (int i = 2; i <= 5; ++i)
    ASSERT_OK(Commit("bob", lock.lock_id, i - 1, "v" + std::to_string(i)));
  const std::vector<Revision> history = FullHistory(kHippocampus, 2);
  ASSERT_EQ(history.size(), 5u);
  for (size_t i = 0; i < history.size(); ++i) {
    EXPECT_EQ(history[i].number, 5 - static_cast<int64_t>(i));
    EXPECT_EQ(history[i].parent, history[i].number - 1);
  }
  EXPECT_EQ(history.back().content_sha256, Hash("contours v1"));

  std::vector<Revision> page;
  std::string token;
  ASSERT_OK(store_->History("carol", kHippocampus, 2, "", &page, &token));
  std::string next;
  EXPECT_STATUS(store_->History("carol", {"atlas", "hippocampus"}, -3, token, &page, &next),
                Status::Code::kInvalidArgument, "page_size");

  Revision reverted;
  EXPECT_STATUS(store_->Revert("bob", kHippocampus, lock.lock_id, 4, 1, "", &reverted),
                Status::Code::kAborted, "the head is revision 5");
  EXPECT_STATUS(store_->Revert("bob", kHippocampus, lock.lock_id, 5, 9, "", &reverted),
                Status::Code::kNotFound, "no revision 9");
  EXPECT_STATUS(store_->Revert("alice", kHippocampus, "", 5, 1, "", &reverted),
                Status::Code::kFailedPrecondition, "locked by 'bob'");
  ASSERT_OK(store_->Revert("bob", kHippocampus, lock.lock_id, 5, 1, "", &reverted));
  EXPECT_EQ(reverted.number, 6);
  EXPECT_EQ(reverted.parent, 5);
  EXPECT_EQ(reverted.kind, "revert");
  EXPECT_EQ(reverted.message, "revert to revision 1");
  EXPECT_EQ(reverted.content_sha256, Hash("contours v1"));
  std::string geometry;
  Revision got;
  ASSERT_OK(store_->GetRevision("carol", kHippocampus, 6, &got, &geometry));
  EXPECT_EQ(geometry, "contours v1");
  // Revision 5 is untouched.
  ASSERT_OK(store_->GetRevision("carol", kHippocampus, 5, &got, &geometry));
  EXPECT_EQ(geometry, "v5");
  EXPECT_EQ(AuditCounts().at("revision.revert"), 1);
}

TEST_F(AtlasStoreTest, SnapshotsPinHeadsAndTagsAreUniquePerProject) {
  Revision revision;
  const StructureRef amygdala{"atlas", "amygdala"};
  ASSERT_OK(store_->CreateStructure("bob", amygdala, Metadata(), StructureFormat::kNifti, "labels",
                                    &revision));
  const LockInfo lock = Lock("bob");
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "v2"));

  SnapshotInfo snapshot;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "before smoothing", &snapshot));
  EXPECT_GT(snapshot.id, 0);
  EXPECT_EQ(snapshot.author, "bob");
  EXPECT_EQ(snapshot.revisions,
            (std::map<std::string, int64_t>{{"amygdala", 1}, {"hippocampus", 2}}));
  // Later commits do not move the snapshot.
  ASSERT_OK(Commit("bob", lock.lock_id, 2, "v3"));
  ASSERT_OK(store_->Tag("bob", "atlas", snapshot.id, "paper-2026"));
  EXPECT_STATUS(store_->Tag("alice", "atlas", snapshot.id, "paper-2026"),
                Status::Code::kAlreadyExists, "already names snapshot");
  EXPECT_STATUS(store_->Tag("bob", "atlas", snapshot.id, "2026"), Status::Code::kInvalidArgument,
                "all digits");
  EXPECT_STATUS(store_->Tag("bob", "atlas", snapshot.id + 100, "later"), Status::Code::kNotFound,
                "no snapshot");
  EXPECT_STATUS(store_->Tag("carol", "atlas", snapshot.id, "mine"), Status::Code::kPermissionDenied,
                "carol");

  SnapshotInfo resolved;
  ASSERT_OK(store_->ResolveSnapshot("carol", "atlas", "paper-2026", &resolved));
  EXPECT_EQ(resolved.id, snapshot.id);
  EXPECT_EQ(resolved.revisions, snapshot.revisions);
  EXPECT_EQ(resolved.tags, std::vector<std::string>{"paper-2026"});
  ASSERT_OK(store_->ResolveSnapshot("carol", "atlas", std::to_string(snapshot.id), &resolved));
  EXPECT_EQ(resolved.name, "before smoothing");
  EXPECT_STATUS(store_->ResolveSnapshot("carol", "atlas", "nope", &resolved),
                Status::Code::kNotFound, "nope");
  EXPECT_STATUS(store_->ResolveSnapshot("carol", "atlas", "999999999999999999999", &resolved),
                Status::Code::kNotFound, "999");

  // A tag is unique per project, not globally.
  ASSERT_OK(store_->CreateProject("dave", "other"));
  SnapshotInfo elsewhere;
  ASSERT_OK(store_->CreateSnapshot("dave", "other", "empty", &elsewhere));
  EXPECT_TRUE(elsewhere.revisions.empty());
  ASSERT_OK(store_->Tag("dave", "other", elsewhere.id, "paper-2026"));
  // ... and a snapshot of another project cannot be tagged or resolved here.
  EXPECT_STATUS(store_->Tag("bob", "atlas", elsewhere.id, "foreign"), Status::Code::kNotFound,
                "no snapshot");
  EXPECT_STATUS(store_->ResolveSnapshot("bob", "atlas", std::to_string(elsewhere.id), &resolved),
                Status::Code::kNotFound, "no snapshot");

  SnapshotInfo second;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "after smoothing", &second));
  EXPECT_EQ(second.revisions.at("hippocampus"), 3);
  std::vector<SnapshotInfo> listed;
  std::string token;
  ASSERT_OK(store_->ListSnapshots("carol", "atlas", 1, "", &listed, &token));
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].id, second.id);
  ASSERT_FALSE(token.empty());
  ASSERT_OK(store_->ListSnapshots("carol", "atlas", 1, token, &listed, &token));
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].id, snapshot.id);
  EXPECT_EQ(listed[0].tags, std::vector<std::string>{"paper-2026"});
  EXPECT_TRUE(token.empty());

  const std::map<std::string, int> counts = AuditCounts();
  EXPECT_EQ(counts.at("snapshot.create"), 2);
  EXPECT_EQ(counts.at("snapshot.tag"), 1);
}

// A snapshot is found by the name it was given when one alone has it; a
// name several share is refused listing them; a tag wins over a name.
TEST_F(AtlasStoreTest, ASnapshotIsFoundByItsNameWhenOneAloneHasIt) {
  SnapshotInfo first, second, resolved;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "after smoothing", &first));
  ASSERT_OK(store_->ResolveSnapshot("carol", "atlas", "after smoothing", &resolved));
  EXPECT_EQ(resolved.id, first.id);
  EXPECT_EQ(resolved.revisions, first.revisions);
  EXPECT_STATUS(store_->ResolveSnapshot("carol", "atlas", "before smoothing", &resolved),
                Status::Code::kNotFound, "tagged, numbered or named 'before smoothing'");
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "after smoothing", &second));
  EXPECT_STATUS(store_->ResolveSnapshot("carol", "atlas", "after smoothing", &resolved),
                Status::Code::kInvalidArgument,
                "are named 'after smoothing' (" + std::to_string(first.id) + ", " +
                    std::to_string(second.id) + "): name one by its id or a tag");
  ASSERT_OK(store_->Tag("bob", "atlas", second.id, "after smoothing"));
  ASSERT_OK(store_->ResolveSnapshot("carol", "atlas", "after smoothing", &resolved));
  EXPECT_EQ(resolved.id, second.id);
  // Not across projects.
  ASSERT_OK(store_->CreateProject("dave", "other"));
  EXPECT_STATUS(store_->ResolveSnapshot("dave", "other", "after smoothing", &resolved),
                Status::Code::kNotFound, "named");
}

TEST_F(AtlasStoreTest, TheAuditLogNamesWhoDidWhatToWhichRevisionNewestFirst) {
  const LockInfo lock = Lock("bob");
  now_ += kSecond;
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "v2"));
  ASSERT_OK(store_->ReleaseLock("bob", lock.lock_id));

  const std::vector<AuditEntry> audit = FullAudit();
  // SetUp: project.create, two member.set_role, structure.create; then three here.
  ASSERT_EQ(audit.size(), 7u);
  const std::vector<std::string> actions = {
      "lock.release",    "revision.commit", "lock.acquire",  "structure.create",
      "member.set_role", "member.set_role", "project.create"};
  for (size_t i = 0; i < audit.size(); ++i) {
    EXPECT_EQ(audit[i].action, actions[i]) << i;
    if (i > 0) {
      EXPECT_LT(audit[i].seq, audit[i - 1].seq);
    }
  }
  EXPECT_EQ(audit[1].user, "bob");
  EXPECT_EQ(audit[1].target, "projects/atlas/structures/hippocampus");
  EXPECT_EQ(audit[1].revision, 2);
  EXPECT_EQ(audit[1].time_us, kStart + kSecond);
  EXPECT_EQ(audit[3].revision, 1);
  EXPECT_EQ(audit[2].revision, 0);
  EXPECT_EQ(audit[6].user, "alice");
  EXPECT_EQ(audit[6].target, "projects/atlas");

  // Pages of 3 walk the same rows.
  std::vector<AuditEntry> paged;
  std::string token;
  int pages = 0;
  do {
    std::vector<AuditEntry> page;
    ASSERT_OK(store_->ListAudit("carol", "atlas", 3, token, &page, &token));
    paged.insert(paged.end(), page.begin(), page.end());
    ++pages;
  } while (!token.empty());
  EXPECT_EQ(pages, 3);
  ASSERT_EQ(paged.size(), audit.size());
  for (size_t i = 0; i < paged.size(); ++i) EXPECT_EQ(paged[i].seq, audit[i].seq);

  std::vector<AuditEntry> page;
  EXPECT_STATUS(store_->ListAudit("dave", "atlas", 3, "", &page, &token),
                Status::Code::kPermissionDenied, "not a member");
  EXPECT_STATUS(store_->ListAudit("carol", "atlas", -1, "", &page, &token),
                Status::Code::kInvalidArgument, "page_size");
}

}  // namespace
}  // namespace pba::store_test

namespace pba::store_test {
namespace {

int64_t CreateRequestRows(Database& db) {
  Statement stmt;
  EXPECT_TRUE(db.Prepare("SELECT COUNT(*) FROM create_requests", &stmt).ok());
  bool row = false;
  EXPECT_TRUE(stmt.Step(&row).ok());
  return stmt.ColumnInt(0);
}

TEST_F(AtlasStoreTest, ARepeatedCreateProjectRequestIdReplaysPerUser) {
  bool replayed = true;
  ASSERT_OK(store_->CreateProject("bob", "cortex", "req-1", &replayed));
  EXPECT_FALSE(replayed);
  const std::map<std::string, int64_t> before = RowCounts();
  // A retry, even after the name is taken (by it): nothing written.
  ASSERT_OK(store_->CreateProject("bob", "cortex", "req-1", &replayed));
  EXPECT_TRUE(replayed);
  EXPECT_EQ(RowCounts(), before);
  // Without a key the name is taken.
  EXPECT_STATUS(store_->CreateProject("bob", "cortex"), Status::Code::kAlreadyExists, "cortex");
  // The key with other arguments, or for another kind of create, is a client bug.
  EXPECT_STATUS(store_->CreateProject("bob", "cerebellum", "req-1"), Status::Code::kInvalidArgument,
                "request_id");
  SnapshotInfo snapshot;
  EXPECT_STATUS(store_->CreateSnapshot("bob", "atlas", "s", &snapshot, "req-1"),
                Status::Code::kInvalidArgument,
                "request_id: you already used it to create a project");
  EXPECT_EQ(RowCounts(), before);
  // Another user's key does not collide.
  ASSERT_OK(store_->CreateProject("dave", "brainstem", "req-1", &replayed));
  EXPECT_FALSE(replayed);
  EXPECT_STATUS(store_->CreateProject("dave", "x", std::string(201, 'k')),
                Status::Code::kInvalidArgument, "request_id");
  auto db = RawDatabase();
  EXPECT_EQ(CreateRequestRows(*db), 2);
  // The rows are append-only, as the audit log is.
  EXPECT_FALSE(db->Exec("UPDATE create_requests SET request_id = 'x'").ok());
  EXPECT_FALSE(db->Exec("DELETE FROM create_requests").ok());
}

TEST_F(AtlasStoreTest, ARepeatedCreateStructureRequestIdReturnsRevisionOne) {
  NewStructure request;
  request.structure = {"atlas", "amygdala"};
  request.metadata = Metadata();
  request.format = StructureFormat::kContours;
  request.geometry = "outline";
  request.message = "traced";
  request.request_id = "create-9c1e";
  Revision first;
  bool replayed = true;
  ASSERT_OK(store_->CreateStructure("bob", request, &first, &replayed));
  EXPECT_FALSE(replayed);
  const int creates = AuditCounts()["structure.create"];
  const std::map<std::string, int64_t> before = RowCounts();

  // The geometry is not compared: a retry may not have its upload any more.
  now_ += kSecond;
  request.geometry = "other bytes";
  Revision again;
  ASSERT_OK(store_->CreateStructure("bob", request, &again, &replayed));
  EXPECT_TRUE(replayed);
  EXPECT_EQ(again.number, 1);
  EXPECT_EQ(again.time_us, first.time_us);
  EXPECT_EQ(again.content_sha256, Hash("outline"));
  bool found = false;
  ASSERT_OK(store_->FindCreatedStructure("bob", request, &again, &found));
  EXPECT_TRUE(found);
  EXPECT_EQ(again.content_sha256, first.content_sha256);
  EXPECT_EQ(RowCounts(), before);
  EXPECT_EQ(AuditCounts()["structure.create"], creates);

  // Other arguments under the same key.
  NewStructure changed = request;
  changed.message = "traced again";
  EXPECT_STATUS(store_->CreateStructure("bob", changed, &again), Status::Code::kInvalidArgument,
                "request_id");
  EXPECT_STATUS(store_->FindCreatedStructure("bob", changed, &again, &found),
                Status::Code::kInvalidArgument, "request_id");
  changed = request;
  changed.metadata.colour.r = 1;
  EXPECT_STATUS(store_->CreateStructure("bob", changed, &again), Status::Code::kInvalidArgument,
                "request_id");
  changed = request;
  changed.structure.structure = "thalamus";
  EXPECT_STATUS(store_->CreateStructure("bob", changed, &again), Status::Code::kInvalidArgument,
                "request_id");
  EXPECT_EQ(RowCounts(), before);
  // Rights come first: a viewer replays nothing.
  EXPECT_STATUS(store_->FindCreatedStructure("carol", request, &again, &found),
                Status::Code::kPermissionDenied, "carol");
  // Another user's identical key is a create of its own (the name is taken).
  EXPECT_STATUS(store_->CreateStructure("alice", request, &again), Status::Code::kAlreadyExists,
                "amygdala");
  ASSERT_OK(store_->FindCreatedStructure("alice", request, &again, &found));
  EXPECT_FALSE(found);
}

TEST_F(AtlasStoreTest, ARepeatedCreateSnapshotRequestIdReturnsTheSameSnapshot) {
  SnapshotInfo first;
  bool replayed = true;
  // Unnamed: named by its time.
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "", &first, "snap-1", &replayed));
  EXPECT_FALSE(replayed);
  EXPECT_EQ(first.name, "snapshot 2026-01-01 00.00.00 UTC");
  const std::map<std::string, int64_t> before = RowCounts();
  // A retry later, after the heads moved, is the same snapshot.
  now_ += 90 * kSecond;
  const LockInfo lock = Lock("bob");
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "v2"));
  const std::map<std::string, int64_t> after_commit = RowCounts();
  SnapshotInfo again;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "", &again, "snap-1", &replayed));
  EXPECT_TRUE(replayed);
  EXPECT_EQ(again.id, first.id);
  EXPECT_EQ(again.name, first.name);
  EXPECT_EQ(again.revisions, first.revisions);
  EXPECT_EQ(RowCounts(), after_commit);
  EXPECT_EQ(AuditCounts()["snapshot.create"], 1);
  EXPECT_STATUS(store_->CreateSnapshot("bob", "atlas", "named", &again, "snap-1"),
                Status::Code::kInvalidArgument, "request_id");
  // alice's "snap-1" is hers.
  ASSERT_OK(store_->CreateSnapshot("alice", "atlas", "", &again, "snap-1", &replayed));
  EXPECT_FALSE(replayed);
  EXPECT_NE(again.id, first.id);
  EXPECT_EQ(again.name, "snapshot 2026-01-01 00.01.30 UTC");
  EXPECT_EQ(before.at("snapshots") + 1, RowCounts().at("snapshots"));
}

}  // namespace
}  // namespace pba::store_test
