// What the atlas store never lets happen: hostile names written, history
// rewritten, corrupted or orphaned blobs served, racing commits forking the
// chain; and that it survives reopening and upgrades.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "unit/server/store/atlas_store_fixture.h"

namespace pba::store_test {
namespace {

TEST_F(AtlasStoreTest, HostileNamesAreRefusedAndNothingIsWritten) {
  const LockInfo lock = Lock("bob");
  SnapshotInfo snapshot;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "base", &snapshot));
  const std::map<std::string, int64_t> before = RowCounts();
  const std::vector<std::pair<std::string, std::string>> hostile = {
      {"a/b", "'/'"},
      {"a\\b", "'\\'"},
      {"o'brien", "'''"},
      {"say \"hi\"", "'\"'"},
      {"'; DROP TABLE structures; --", "'''"},
      {"x; DELETE FROM audit_log", "';'"},
      {std::string("nul\0byte", 8), "\\x00"},
      {"line\nbreak", "\\x0a"},
      {"", "empty"},
  };
  for (const auto& [name, shown] : hostile) {
    SCOPED_TRACE(name);
    std::string token;
    EXPECT_STATUS(store_->CreateUser(name, &token), Status::Code::kInvalidArgument, "user: ");
    EXPECT_STATUS(store_->CreateUser(name, &token), Status::Code::kInvalidArgument, shown);
    EXPECT_STATUS(store_->CreateProject("alice", name), Status::Code::kInvalidArgument,
                  "project: ");
    Revision revision;
    EXPECT_STATUS(store_->CreateStructure("bob", {"atlas", name}, Metadata(), StructureFormat::kStl,
                                          "solid", &revision),
                  Status::Code::kInvalidArgument, "structure: ");
    EXPECT_STATUS(store_->CreateStructure("bob", {name, "ok"}, Metadata(), StructureFormat::kStl,
                                          "solid", &revision),
                  Status::Code::kInvalidArgument, "project: ");
    EXPECT_STATUS(store_->Tag("bob", "atlas", snapshot.id, name), Status::Code::kInvalidArgument,
                  "tag: ");
    SnapshotInfo other;
    if (!name.empty()) {  // an empty snapshot name is named by its time
      EXPECT_STATUS(store_->CreateSnapshot("bob", "atlas", name, &other),
                    Status::Code::kInvalidArgument, "name: ");
    }
    EXPECT_STATUS(store_->SetRole("alice", "atlas", name, Role::kEditor),
                  Status::Code::kInvalidArgument, "member: ");
    LockInfo info;
    EXPECT_STATUS(store_->AcquireLock(name, kHippocampus, kSecond, &info),
                  Status::Code::kInvalidArgument, "user: ");
    if (!name.empty() && name.find('/') == std::string::npos) {  // "cerebrum/a/b" is a path
      StructureMetadata metadata = Metadata();
      metadata.group_path = "cerebrum/" + name;
      EXPECT_STATUS(store_->CreateStructure("bob", {"atlas", "ok"}, metadata, StructureFormat::kStl,
                                            "solid", &revision),
                    Status::Code::kInvalidArgument, "group_path: ");
    }
  }
  EXPECT_EQ(RowCounts(), before);
  auto db = RawDatabase();
  EXPECT_EQ(QueryInt(*db, "SELECT COUNT(*) FROM sqlite_master WHERE name = 'structures'"), 1);
  EXPECT_EQ(Structure().head, 1);
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "still works"));
}

TEST_F(AtlasStoreTest, ReopeningKeepsEverythingAndTheFileIsSound) {
  const LockInfo lock = Lock("bob");
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "v2"));
  SnapshotInfo snapshot;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "s", &snapshot));
  ASSERT_OK(store_->Tag("bob", "atlas", snapshot.id, "release"));
  const std::vector<AuditEntry> audit = FullAudit();
  const std::string etag = Structure().metadata_etag;

  Reopen();
  std::string user;
  ASSERT_OK(store_->Authenticate(tokens_["bob"], &user));
  EXPECT_EQ(user, "bob");
  const std::vector<Revision> history = FullHistory();
  ASSERT_EQ(history.size(), 2u);
  EXPECT_EQ(history[0].content_sha256, Hash("v2"));
  EXPECT_EQ(Structure().metadata_etag, etag);
  // The lock and its lease survive a restart: the holder keeps working.
  LockInfo other;
  EXPECT_STATUS(store_->AcquireLock("alice", kHippocampus, kSecond, &other),
                Status::Code::kFailedPrecondition, "locked by 'bob'");
  ASSERT_OK(Commit("bob", lock.lock_id, 2, "v3"));
  SnapshotInfo resolved;
  ASSERT_OK(store_->ResolveSnapshot("carol", "atlas", "release", &resolved));
  EXPECT_EQ(resolved.revisions.at("hippocampus"), 2);
  const std::vector<AuditEntry> reopened = FullAudit();
  ASSERT_EQ(reopened.size(), audit.size() + 1);
  EXPECT_EQ(reopened[1].seq, audit[0].seq);
  EXPECT_EQ(reopened[1].action, audit[0].action);

  store_.reset();
  auto db = RawDatabase();
  Statement stmt;
  ASSERT_OK(db->Prepare("PRAGMA integrity_check", &stmt));
  bool row = false;
  ASSERT_OK(stmt.Step(&row));
  ASSERT_TRUE(row);
  EXPECT_EQ(stmt.ColumnText(0), "ok");
  ASSERT_OK(db->Prepare("PRAGMA foreign_key_check", &stmt));
  ASSERT_OK(stmt.Step(&row));
  EXPECT_FALSE(row) << "a foreign key is dangling in " << stmt.ColumnText(0);
  stmt = Statement();
  EXPECT_EQ(QueryInt(*db, "SELECT MAX(version) FROM schema_version"), LatestSchemaVersion());
}

TEST_F(AtlasStoreTest, HistoryCannotBeRewrittenUnderneath) {
  SnapshotInfo snapshot;
  ASSERT_OK(store_->CreateSnapshot("bob", "atlas", "s", &snapshot));
  auto db = RawDatabase();
  for (const char* sql : {
           "UPDATE structure_revisions SET message = 'rewritten'",
           "DELETE FROM structure_revisions",
           "UPDATE audit_log SET detail = ''",
           "DELETE FROM audit_log",
           "UPDATE snapshots SET name = 'x'",
           "DELETE FROM snapshot_members",
           "DELETE FROM snapshots",
       }) {
    EXPECT_FALSE(db->Exec(sql).ok()) << sql;
  }
  // A revision whose parent is not its predecessor would break the chain.
  const Status status = db->Exec(
      "INSERT INTO structure_revisions (structure, number, parent, author, time_us, kind, "
      "message, content_sha256, geometry_format, size_bytes, material_json, colour_r, colour_g, "
      "colour_b, group_path) SELECT structure, 3, id, author, 0, 'commit', '', content_sha256, "
      "geometry_format, size_bytes, material_json, 0, 0, 0, '' FROM structure_revisions");
  EXPECT_FALSE(status.ok());
  EXPECT_TRUE(Contains(status.message(), "previous revision")) << status.message();
  const std::vector<Revision> history = FullHistory();
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].message, "created");
}

TEST_F(AtlasStoreTest, ACorruptedBlobIsAnErrorNamingItsHash) {
  Revision revision;
  ASSERT_OK(store_->GetRevision("carol", kHippocampus, 1, &revision, nullptr));
  const std::string hash = revision.content_sha256;
  const fs::path path = dir_.path() / "blobs" / hash.substr(0, 2) / hash.substr(2);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << "contours v2";  // same length, different bytes
  }
  std::string geometry;
  EXPECT_STATUS(store_->GetRevision("carol", kHippocampus, 1, &revision, &geometry),
                Status::Code::kIo, hash);
  EXPECT_TRUE(geometry.empty());
  // The row itself is still readable without the blob.
  ASSERT_OK(store_->GetRevision("carol", kHippocampus, 1, &revision, nullptr));
}

TEST_F(AtlasStoreTest, SweepRemovesOrphanBlobsButNotReferencedOnes) {
  const LockInfo lock = Lock("bob");
  ASSERT_OK(Commit("bob", lock.lock_id, 1, "v2"));
  // What a crash between the blob write and the row insert leaves behind.
  std::unique_ptr<BlobStore> blobs;
  ASSERT_OK(BlobStore::Open(dir_.path() / "blobs", &blobs));
  std::string orphan;
  ASSERT_OK(blobs->Put("never committed", &orphan));
  // A commit refused before the write leaves no blob at all.
  EXPECT_STATUS(Commit("bob", lock.lock_id, 1, "refused geometry"), Status::Code::kAborted,
                "head is revision 2");
  bool has = true;
  ASSERT_OK(blobs->Has(Hash("refused geometry"), &has));
  EXPECT_FALSE(has);

  BlobSweepReport report;
  ASSERT_OK(store_->SweepBlobs(&report));
  EXPECT_EQ(report.removed_blobs, 1);
  EXPECT_EQ(report.kept_blobs, 2);
  ASSERT_OK(blobs->Has(orphan, &has));
  EXPECT_FALSE(has);
  std::string geometry;
  Revision revision;
  for (int number : {1, 2}) {
    ASSERT_OK(store_->GetRevision("carol", kHippocampus, number, &revision, &geometry));
  }
  EXPECT_EQ(geometry, "v2");
}

// 16 editors race to commit to one structure, 25 attempts each: read the
// head, try the lock, commit on the head read, release. Whatever the
// interleaving, each attempt either lands or is refused for a stated reason,
// and the history is one unbroken chain with one audit row per change.
TEST_F(AtlasStoreTest, RacingCommitsFormOneChain) {
  constexpr int kThreads = 16;
  constexpr int kAttempts = 25;
  for (int t = 0; t < kThreads; ++t) {
    std::string token;
    const std::string name = "editor" + std::to_string(t);
    ASSERT_OK(store_->CreateUser(name, &token));
    ASSERT_OK(store_->SetRole("alice", "atlas", name, Role::kEditor));
  }
  std::atomic<int> landed{0};
  std::atomic<int> stale{0};
  std::atomic<int> locked_out{0};
  std::atomic<int> unexpected{0};
  std::mutex mutex;
  std::set<std::string> landed_geometry;
  std::vector<std::string> problems;
  auto report = [&](const std::string& problem) {
    std::lock_guard guard(mutex);
    ++unexpected;
    if (problems.size() < 10) problems.push_back(problem);
  };
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      const std::string user = "editor" + std::to_string(t);
      for (int i = 0; i < kAttempts; ++i) {
        StructureInfo info;
        Status status = store_->GetStructure(user, kHippocampus, &info);
        if (!status.ok()) return report(status.ToString());
        const int64_t believed = info.head;
        std::this_thread::yield();  // let others move the head in between
        LockInfo lock;
        status = store_->AcquireLock(user, kHippocampus, 60 * kSecond, &lock);
        if (status.code() == Status::Code::kFailedPrecondition &&
            Contains(status.message(), "is locked by 'editor")) {
          ++locked_out;
          continue;
        }
        if (!status.ok()) {
          report("acquire: " + status.ToString());
          continue;
        }
        const std::string geometry = user + " attempt " + std::to_string(i);
        Revision revision;
        status = Commit(user, lock.lock_id, believed, geometry, &revision);
        if (status.ok()) {
          ++landed;
          std::lock_guard guard(mutex);
          landed_geometry.insert(Hash(geometry));
        } else if (status.code() == Status::Code::kAborted) {
          ++stale;
          // Under the lock the head cannot move, so the head named is the head.
          StructureInfo current;
          const Status read = store_->GetStructure(user, kHippocampus, &current);
          if (!read.ok() || !Contains(status.message(), "the head is revision " +
                                                            std::to_string(current.head) + ";")) {
            report("stale commit named the wrong head: " + status.ToString());
          }
        } else {
          report("commit: " + status.ToString());
        }
        if (status.ok() && revision.number != believed + 1) report("landed off its base");
        status = store_->ReleaseLock(user, lock.lock_id);
        if (!status.ok()) report("release: " + status.ToString());
      }
    });
  }
  for (std::thread& thread : threads) thread.join();

  EXPECT_EQ(unexpected.load(), 0) << (problems.empty() ? "" : problems.front());
  EXPECT_EQ(landed + stale + locked_out + unexpected, kThreads * kAttempts);
  EXPECT_GT(landed.load(), 0);
  std::printf("landed %d, stale base %d, locked out %d\n", landed.load(), stale.load(),
              locked_out.load());

  const std::vector<Revision> history = FullHistory(kHippocampus, 37);
  ASSERT_EQ(static_cast<int>(history.size()), 1 + landed.load());
  std::set<std::string> chained_geometry;
  for (size_t i = 0; i < history.size(); ++i) {
    const Revision& revision = history[i];
    EXPECT_EQ(revision.number, static_cast<int64_t>(history.size() - i));
    EXPECT_EQ(revision.parent, revision.number - 1);
    if (revision.number > 1) chained_geometry.insert(revision.content_sha256);
  }
  EXPECT_EQ(chained_geometry, landed_geometry);
  EXPECT_EQ(Structure().head, 1 + landed.load());

  const std::map<std::string, int> counts = AuditCounts();
  const int acquired = landed.load() + stale.load();
  EXPECT_EQ(counts.at("revision.commit"), landed.load());
  EXPECT_EQ(counts.at("lock.acquire"), acquired);
  EXPECT_EQ(counts.at("lock.release"), acquired);
  EXPECT_EQ(counts.count("lock.takeover"), 0u);
  auto db = RawDatabase();
  EXPECT_EQ(QueryInt(*db, "SELECT COUNT(*) FROM locks"), 0);
}

// A pba.db written before the atlas store existed (schema version 1, jobs
// only) gains the atlas tables on open and keeps its rows.
TEST(AtlasStoreUpgrade, AVersionOneDatabaseIsMigratedInPlace) {
  TempDir dir;
  {
    std::unique_ptr<Database> db;
    ASSERT_OK(Database::Open(dir.path() / "pba.db", &db));
    ASSERT_OK(db->Exec(
        "CREATE TABLE schema_version (version INTEGER PRIMARY KEY, description TEXT NOT NULL, "
        "applied_time_us INTEGER NOT NULL);"
        "INSERT INTO schema_version VALUES (1, 'jobs, job events and result files', 0);"
        "CREATE TABLE jobs (number INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT NOT NULL UNIQUE, "
        "name TEXT NOT NULL DEFAULT 'cube', state TEXT NOT NULL DEFAULT 'SUCCEEDED');"
        "INSERT INTO jobs (id) VALUES ('j0000000001');"));
  }
  std::unique_ptr<AtlasStore> store;
  ASSERT_OK(AtlasStore::Open(dir.path(), &store));
  std::string token;
  ASSERT_OK(store->CreateUser("alice", &token));
  ASSERT_OK(store->CreateProject("alice", "atlas"));
  store.reset();

  std::unique_ptr<Database> db;
  ASSERT_OK(Database::Open(dir.path() / "pba.db", &db));
  int version = 0;
  ASSERT_OK(ReadSchemaVersion(*db, &version));
  EXPECT_EQ(version, LatestSchemaVersion());
  Statement stmt;
  ASSERT_OK(db->Prepare("SELECT id FROM jobs", &stmt));
  bool row = false;
  ASSERT_OK(stmt.Step(&row));
  ASSERT_TRUE(row);
  EXPECT_EQ(stmt.ColumnText(0), "j0000000001");
  stmt = Statement();
  ASSERT_OK(db->Prepare("SELECT COUNT(*) FROM projects", &stmt));
  ASSERT_OK(stmt.Step(&row));
  EXPECT_EQ(stmt.ColumnInt(0), 1);
}

// A pba.db of schema version 8 with revisions, a snapshot and the audit
// log is rebuilt for the derived format (version 9) with every row, id
// and rule kept.
TEST(AtlasStoreUpgrade, AVersionEightDatabaseTakesDerivedRevisionsAndKeepsItsHistory) {
  TempDir dir;
  const std::string hash_a(64, 'a'), hash_b(64, 'b');
  {
    std::unique_ptr<Database> db;
    ASSERT_OK(Database::Open(dir.path() / "pba.db", &db));
    ASSERT_OK(ApplyMigrations(*db, 8));
    ASSERT_OK(db->Exec(
        "INSERT INTO users (id, name, token_sha256, created_us) VALUES (1, 'alice', '" +
        std::string(64, 'c') +
        "', 0);"
        "INSERT INTO projects (id, name, created_us, created_by) VALUES (1, 'atlas', 0, 1);"
        "INSERT INTO members VALUES (1, 1, 'admin');"
        "INSERT INTO structures (id, project, name, head_revision, metadata_etag, created_us, "
        "created_by) VALUES (1, 1, 'lung', NULL, 'e1', 0, 1);"
        "INSERT INTO structure_revisions (id, structure, number, parent, author, time_us, kind, "
        "message, content_sha256, geometry_format, size_bytes, material_json, colour_r, "
        "colour_g, colour_b, group_path, request_id) VALUES "
        "(1, 1, 1, NULL, 1, 10, 'create', 'created', '" +
        hash_a + "', 'contours_json', 2, '{}', 1, 2, 3, '', NULL), (2, 1, 2, 1, 1, 20, 'commit', " +
        "'second', '" + hash_b +
        "', 'nifti', 3, '{}', 1, 2, 3, 'g', 'r-2');"
        "UPDATE structures SET head_revision = 2 WHERE id = 1;"
        "INSERT INTO snapshots (id, project, name, created_us, author) VALUES (1, 1, 's', 0, 1);"
        "INSERT INTO snapshot_members VALUES (1, 1, 1);"
        "INSERT INTO audit_log (time_us, user, project, action, target, revision) VALUES "
        "(0, 1, 1, 'create', 'projects/atlas/structures/lung', 1);"));
  }
  std::unique_ptr<AtlasStore> store;
  ASSERT_OK(AtlasStore::Open(dir.path(), &store));
  Revision head, first;
  ASSERT_OK(store->GetRevision("alice", {"atlas", "lung"}, 2, &head, nullptr));
  EXPECT_EQ(head.format, StructureFormat::kNifti);
  EXPECT_EQ(head.content_sha256, hash_b);
  EXPECT_EQ(head.parent, 1);
  ASSERT_OK(store->GetRevision("alice", {"atlas", "lung"}, 1, &first, nullptr));
  EXPECT_EQ(first.message, "created");
  SnapshotInfo snapshot;
  ASSERT_OK(store->ResolveSnapshot("alice", "atlas", "1", &snapshot));
  EXPECT_EQ(snapshot.revisions.at("lung"), 1);
  store.reset();

  std::unique_ptr<Database> db;
  ASSERT_OK(Database::Open(dir.path() / "pba.db", &db));
  int version = 0;
  ASSERT_OK(ReadSchemaVersion(*db, &version));
  EXPECT_EQ(version, LatestSchemaVersion());
  const auto first_text = [&](const std::string& sql) {
    Statement stmt;
    EXPECT_TRUE(db->Prepare(sql, &stmt).ok()) << sql;
    bool row = false;
    EXPECT_TRUE(stmt.Step(&row).ok()) << sql;
    return row ? stmt.ColumnText(0) : std::string("(none)");
  };
  EXPECT_EQ(first_text("PRAGMA integrity_check"), "ok");
  EXPECT_EQ(first_text("PRAGMA foreign_key_check"), "(none)");
  EXPECT_EQ(first_text("SELECT name FROM sqlite_schema WHERE name LIKE '%_v9'"), "(none)");
  EXPECT_EQ(first_text("SELECT COUNT(*) FROM sqlite_schema WHERE type IN ('index', 'trigger') "
                       "AND tbl_name = 'structure_revisions' AND sql IS NOT NULL"),
            "5");
  // The rules hold on the rebuilt table: immutable, one chain, known formats.
  EXPECT_FALSE(db->Exec("UPDATE structure_revisions SET message = 'rewritten'").ok());
  EXPECT_FALSE(db->Exec("DELETE FROM structure_revisions").ok());
  const std::string insert =
      "INSERT INTO structure_revisions (structure, number, parent, author, time_us, kind, "
      "message, content_sha256, geometry_format, size_bytes, material_json, colour_r, colour_g, "
      "colour_b, group_path) VALUES (1, 3, %PARENT%, 1, 30, 'commit', '', '" +
      hash_a + "', '%FORMAT%', 2, '{}', 0, 0, 0, '')";
  const auto with = [&](const std::string& parent, const std::string& format) {
    std::string sql = insert;
    sql.replace(sql.find("%PARENT%"), 8, parent);
    sql.replace(sql.find("%FORMAT%"), 8, format);
    return sql;
  };
  EXPECT_FALSE(db->Exec(with("1", "derived")).ok());  // not the previous revision
  EXPECT_FALSE(db->Exec(with("2", "bogus")).ok());
  const Status derived = db->Exec(with("2", "derived"));
  EXPECT_TRUE(derived.ok()) << derived.ToString();
}

}  // namespace
}  // namespace pba::store_test
