// Who lists which jobs (JobReader): a job on a project only for its members,
// its owner and server admins; pages stay full around the hidden jobs.
#include <gtest/gtest.h>

#include <set>

#include "store/atlas_store.h"
#include "store/database.h"
#include "store/job_store.h"
#include "unit/server/server_test_support.h"

namespace pba {
namespace {

using testing::TempDir;
using testing::ValidScene;

class JobStoreReaderTest : public ::testing::Test {
 protected:
  // alice's project "atlas"; eve is in no project.
  void SetUp() override {
    ASSERT_TRUE(JobStore::Open(dir_.path() / "pba.db", &jobs_).ok());
    ASSERT_TRUE(AtlasStore::Open(dir_.path(), &atlas_).ok());
    std::string token;
    ASSERT_TRUE(atlas_->CreateUser("alice", &token).ok());
    ASSERT_TRUE(atlas_->CreateUser("eve", &token).ok());
    ASSERT_TRUE(atlas_->CreateProject("alice", "atlas").ok());
  }

  std::string Create(const std::string& owner, const std::string& project, bool import) {
    NewJob request;
    request.scene = ValidScene("job");
    request.owner = owner;
    v1::AtlasImport atlas_import;
    if (import) {
      atlas_import.set_project(project);
      atlas_import.set_source(v1::AtlasImport::SYNTHETIC);
      request.atlas_import = &atlas_import;
    } else if (!project.empty()) {
      request.snapshot.set_project(project);
      request.snapshot.set_snapshot("1");
    }
    v1::Job job;
    bool created = false;
    EXPECT_TRUE(jobs_->CreateJob(request, &job, &created).ok());
    return job.id();
  }

  // Every page of `reader`'s listing, in order, with page_size 2.
  std::vector<std::string> ListAll(const JobReader& reader, std::vector<size_t>* page_sizes) {
    std::vector<std::string> ids;
    std::string token;
    do {
      std::vector<v1::Job> page;
      const Status status = jobs_->ListJobs(reader, 2, token, &page, &token);
      EXPECT_TRUE(status.ok()) << status.ToString();
      if (!status.ok()) break;
      page_sizes->push_back(page.size());
      for (const v1::Job& job : page) ids.push_back(job.id());
    } while (!token.empty());
    return ids;
  }

  TempDir dir_;
  std::unique_ptr<JobStore> jobs_;
  std::unique_ptr<AtlasStore> atlas_;
};

TEST_F(JobStoreReaderTest, AReaderListsOnlyTheJobsTheyMaySeeInFullPages) {
  // Newest first: the listing order is the reverse of creation.
  std::vector<std::string> everyone, project;
  everyone.push_back(Create("alice", "", false));
  project.push_back(Create("alice", "atlas", false));
  project.push_back(Create("alice", "atlas", true));
  everyone.push_back(Create("alice", "", false));
  project.push_back(Create("alice", "atlas", false));
  const std::string eves_own = Create("eve", "atlas", false);  // theirs, though not a member
  project.push_back(Create("alice", "atlas", true));
  everyone.push_back(Create("eve", "", false));

  JobReader eve{"eve", false};
  std::vector<size_t> pages;
  const std::vector<std::string> seen = ListAll(eve, &pages);
  const std::vector<std::string> expected = {everyone[2], eves_own, everyone[1], everyone[0]};
  EXPECT_EQ(seen, expected);
  // Hidden jobs are skipped in the query, so no page comes back short.
  EXPECT_EQ(pages, (std::vector<size_t>{2, 2}));

  JobReader alice{"alice", false};
  pages.clear();
  EXPECT_EQ(ListAll(alice, &pages).size(), 8u) << "a member sees the project's jobs";
  JobReader admin{"nobody", true};
  pages.clear();
  EXPECT_EQ(ListAll(admin, &pages).size(), 8u);

  // Made a member, eve sees them; removed, no longer.
  ASSERT_TRUE(atlas_->SetRole("alice", "atlas", "eve", Role::kViewer).ok());
  pages.clear();
  EXPECT_EQ(ListAll(eve, &pages).size(), 8u);
  std::vector<std::string> released;
  ASSERT_TRUE(atlas_->RemoveMember("alice", "atlas", "eve", &released).ok());
  pages.clear();
  EXPECT_EQ(ListAll(eve, &pages), expected);
}

// A pba.db of schema version 6 (before server admins and job projects):
// its "admin" becomes a server admin and its jobs get their projects, an
// import's from the name its submit gave it, and their ranks (one process).
TEST(JobStoreUpgradeTest, VersionSixGainsServerAdminsAndJobProjects) {
  TempDir dir;
  const std::filesystem::path path = dir.path() / "pba.db";
  {
    std::unique_ptr<JobStore> jobs;
    ASSERT_TRUE(JobStore::Open(path, &jobs).ok());
  }
  {
    // Back to version 6: what migrations 7, 8 and 10 added to these tables,
    // undone (9 rebuilds structure_revisions as it is).
    std::unique_ptr<Database> db;
    ASSERT_TRUE(Database::Open(path, &db).ok());
    const Status undone = db->Exec(
        "DROP INDEX jobs_scheduled; ALTER TABLE jobs DROP COLUMN scheduler_job; "
        "ALTER TABLE jobs DROP COLUMN scheduler_state; "
        "ALTER TABLE jobs DROP COLUMN scheduler_reason; "
        "ALTER TABLE jobs DROP COLUMN scheduler_node; "
        "ALTER TABLE jobs DROP COLUMN ranks; "
        "DROP INDEX jobs_by_project; ALTER TABLE jobs DROP COLUMN project; "
        "ALTER TABLE users DROP COLUMN server_admin; DELETE FROM schema_version WHERE version >= 7;"
        "INSERT INTO users (name, token_sha256, created_us) VALUES "
        "  ('admin', printf('%064d', 1), 0), ('alice', printf('%064d', 2), 0);"
        "INSERT INTO jobs (id, name, state, scene, create_time_us, snapshot_project, snapshot, "
        "  atlas_import) VALUES "
        "  ('j0000000001', 'cube', 'SUCCEEDED', x'', 0, '', '', NULL),"
        "  ('j0000000002', 'atlas job', 'SUCCEEDED', x'', 0, 'atlas', '1', NULL),"
        "  ('j0000000003', 'import into brain', 'QUEUED', x'', 0, '', '', x'0a05627261696e');");
    ASSERT_TRUE(undone.ok()) << undone.ToString();
  }
  std::unique_ptr<JobStore> jobs;
  ASSERT_TRUE(JobStore::Open(path, &jobs).ok());
  jobs.reset();
  std::unique_ptr<Database> db;
  ASSERT_TRUE(Database::Open(path, &db).ok());
  const auto text = [&](const std::string& sql) {
    Statement stmt;
    EXPECT_TRUE(db->Prepare(sql, &stmt).ok()) << sql;
    bool row = false;
    EXPECT_TRUE(stmt.Step(&row).ok()) << sql;
    return row ? stmt.ColumnText(0) : std::string("(no row)");
  };
  EXPECT_EQ(text("SELECT group_concat(name) FROM users WHERE server_admin = 1"), "admin");
  EXPECT_EQ(text("SELECT group_concat(job, ' ') FROM "
                 "(SELECT id || ':' || project AS job FROM jobs ORDER BY number)"),
            "j0000000001: j0000000002:atlas j0000000003:brain");
  // Migration 8: every earlier job ran as one process.
  EXPECT_EQ(text("SELECT group_concat(ranks) FROM jobs"), "0,0,0");
}

}  // namespace
}  // namespace pba
