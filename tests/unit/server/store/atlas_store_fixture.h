// The fixture the atlas store tests share: a store in a temporary
// directory with four users, one project and one structure, an injected
// clock, and ways to look underneath it.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "core/sha256.h"
#include "store/atlas_store.h"
#include "store/database.h"
#include "store/migrations.h"
#include "unit/server/temp_dir.h"

namespace pba::store_test {

namespace fs = std::filesystem;
using testing::TempDir;

constexpr int64_t kSecond = 1000 * 1000;
// 2026-01-01T00:00:00Z: the injected clock starts here.
constexpr int64_t kStart = 1767225600LL * kSecond;

inline std::string Hash(const std::string& bytes) { return Sha256Hex(bytes); }

inline bool Contains(const std::string& text, const std::string& fragment) {
  return text.find(fragment) != std::string::npos;
}

#define EXPECT_STATUS(expr, expected_code, fragment)                  \
  do {                                                                \
    const ::pba::Status status_ = (expr);                             \
    EXPECT_EQ(status_.code(), (expected_code)) << status_.ToString(); \
    EXPECT_TRUE(Contains(status_.ToString(), (fragment)))             \
        << "'" << (fragment) << "' not in: " << status_.ToString();   \
  } while (false)

#define ASSERT_OK(expr)                              \
  do {                                               \
    const ::pba::Status status_ = (expr);            \
    ASSERT_TRUE(status_.ok()) << status_.ToString(); \
  } while (false)

class AtlasStoreTest : public ::testing::Test {
 protected:
  // alice creates project "atlas" (admin); bob is an editor, carol a viewer,
  // dave a user outside the project. "hippocampus" exists at revision 1.
  void SetUp() override {
    Open();
    for (const char* name : {"alice", "bob", "carol", "dave"}) {
      ASSERT_OK(store_->CreateUser(name, &tokens_[name]));
    }
    ASSERT_OK(store_->CreateProject("alice", "atlas"));
    ASSERT_OK(store_->SetRole("alice", "atlas", "bob", Role::kEditor));
    ASSERT_OK(store_->SetRole("alice", "atlas", "carol", Role::kViewer));
    Revision first;
    ASSERT_OK(store_->CreateStructure("bob", kHippocampus, Metadata(), StructureFormat::kContours,
                                      "contours v1", &first));
  }

  void Open() {
    ASSERT_OK(AtlasStore::Open(dir_.path(), &store_, [this] { return now_.load(); }));
  }
  void Reopen() {
    store_.reset();
    Open();
  }

  static StructureMetadata Metadata() {
    StructureMetadata metadata;
    metadata.colour = {220, 180, 40};
    metadata.group_path = "cerebrum/limbic system";
    metadata.material_json = R"({"model": "neo_hookean", "mu_pa": 1000})";
    return metadata;
  }

  LockInfo Lock(const std::string& user, const StructureRef& ref = kHippocampus,
                int64_t lease = 60 * kSecond) {
    LockInfo info;
    const Status status = store_->AcquireLock(user, ref, lease, &info);
    EXPECT_TRUE(status.ok()) << status.ToString();
    return info;
  }

  Status Commit(const std::string& user, const std::string& lock_id, int64_t base,
                const std::string& geometry, Revision* revision = nullptr,
                std::optional<std::string> material = std::nullopt) {
    CommitRequest request;
    request.structure = kHippocampus;
    request.lock_id = lock_id;
    request.base_revision = base;
    request.geometry = geometry;
    request.material_json = std::move(material);
    request.message = "edit by " + user;
    Revision ignored;
    return store_->Commit(user, request, revision != nullptr ? revision : &ignored);
  }

  StructureInfo Structure(const StructureRef& ref = kHippocampus) {
    StructureInfo info;
    const Status status = store_->GetStructure("alice", ref, &info);
    EXPECT_TRUE(status.ok()) << status.ToString();
    return info;
  }

  std::vector<Revision> FullHistory(const StructureRef& ref = kHippocampus, int page_size = 7) {
    std::vector<Revision> all;
    std::string token;
    do {
      std::vector<Revision> page;
      const Status status = store_->History("carol", ref, page_size, token, &page, &token);
      EXPECT_TRUE(status.ok()) << status.ToString();
      if (!status.ok()) break;
      all.insert(all.end(), page.begin(), page.end());
    } while (!token.empty());
    return all;
  }

  std::vector<AuditEntry> FullAudit(const std::string& project = "atlas") {
    std::vector<AuditEntry> all;
    std::string token;
    do {
      std::vector<AuditEntry> page;
      const Status status = store_->ListAudit("carol", project, 1000, token, &page, &token);
      EXPECT_TRUE(status.ok()) << status.ToString();
      if (!status.ok()) break;
      all.insert(all.end(), page.begin(), page.end());
    } while (!token.empty());
    return all;
  }

  std::map<std::string, int> AuditCounts() {
    std::map<std::string, int> counts;
    for (const AuditEntry& entry : FullAudit()) ++counts[entry.action];
    return counts;
  }

  // A second connection to pba.db, for looking underneath the store.
  std::unique_ptr<Database> RawDatabase() {
    std::unique_ptr<Database> db;
    EXPECT_TRUE(Database::Open(dir_.path() / "pba.db", &db).ok());
    return db;
  }

  int64_t QueryInt(Database& db, const std::string& sql) {
    Statement stmt;
    EXPECT_TRUE(db.Prepare(sql, &stmt).ok()) << sql;
    bool row = false;
    EXPECT_TRUE(stmt.Step(&row).ok()) << sql;
    return row ? stmt.ColumnInt(0) : -1;
  }

  std::map<std::string, int64_t> RowCounts() {
    auto db = RawDatabase();
    std::map<std::string, int64_t> counts;
    for (const char* table :
         {"users", "projects", "members", "structures", "structure_revisions", "locks", "snapshots",
          "snapshot_members", "snapshot_tags", "audit_log"}) {
      counts[table] = QueryInt(*db, std::string("SELECT COUNT(*) FROM ") + table);
    }
    return counts;
  }

  static inline const StructureRef kHippocampus{"atlas", "hippocampus"};

  TempDir dir_;
  std::atomic<int64_t> now_{kStart};
  std::map<std::string, std::string> tokens_;
  std::unique_ptr<AtlasStore> store_;
};

}  // namespace pba::store_test
