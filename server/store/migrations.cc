#include "store/migrations.h"

#include <chrono>
#include <string>
#include <vector>

#include "store/transaction.h"

namespace pba {
namespace {

struct Migration {
  int version;
  const char* description;
  const char* sql;
};

// Job states are stored by their pba.v1.Job.State names so that the file
// reads well in the sqlite3 shell. Times are microseconds since the Unix
// epoch (UTC). `number` orders jobs by creation, independent of the clock.
const std::vector<Migration>& Migrations() {
  static const std::vector<Migration> kMigrations = {
      {1, "jobs, job events and result files", R"sql(
CREATE TABLE jobs (
  number INTEGER PRIMARY KEY AUTOINCREMENT,
  id TEXT NOT NULL UNIQUE,
  request_id TEXT UNIQUE,
  name TEXT NOT NULL,
  state TEXT NOT NULL,
  scene BLOB NOT NULL,
  create_time_us INTEGER NOT NULL,
  start_time_us INTEGER,
  end_time_us INTEGER,
  phase TEXT NOT NULL DEFAULT '',
  progress REAL NOT NULL DEFAULT 0,
  error TEXT NOT NULL DEFAULT '',
  attempts INTEGER NOT NULL DEFAULT 0,
  summary BLOB
);
CREATE INDEX jobs_by_state ON jobs (state, number);
CREATE TABLE job_events (
  job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  sequence INTEGER NOT NULL,
  time_us INTEGER NOT NULL,
  state TEXT NOT NULL,
  phase TEXT NOT NULL DEFAULT '',
  progress REAL NOT NULL DEFAULT 0,
  message TEXT NOT NULL DEFAULT '',
  PRIMARY KEY (job_id, sequence)
) WITHOUT ROWID;
CREATE TABLE result_files (
  job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  name TEXT NOT NULL,
  size INTEGER NOT NULL,
  sha256 TEXT NOT NULL,
  PRIMARY KEY (job_id, name)
) WITHOUT ROWID;
)sql"},
  };
  return kMigrations;
}

int64_t NowMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

int LatestSchemaVersion() { return Migrations().back().version; }

Status ReadSchemaVersion(Database& db, int* version) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db.Prepare("SELECT COALESCE(MAX(version), 0) FROM schema_version", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Step(&row));
  *version = row ? static_cast<int>(stmt.ColumnInt(0)) : 0;
  return Status::Ok();
}

Status ApplyMigrations(Database& db) {
  PBA_RETURN_IF_ERROR(
      db.Exec("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER PRIMARY KEY, "
              "description TEXT NOT NULL, applied_time_us INTEGER NOT NULL)"));
  int current = 0;
  PBA_RETURN_IF_ERROR(ReadSchemaVersion(db, &current));
  if (current > LatestSchemaVersion()) {
    return Status::FailedPrecondition("the database has schema version " + std::to_string(current) +
                                      " but this server knows versions up to " +
                                      std::to_string(LatestSchemaVersion()) +
                                      "; use a newer pba-server");
  }
  for (const Migration& migration : Migrations()) {
    if (migration.version <= current) continue;
    Transaction transaction(db);
    PBA_RETURN_IF_ERROR(transaction.status());
    PBA_RETURN_IF_ERROR(db.Exec(migration.sql));
    Statement stmt;
    PBA_RETURN_IF_ERROR(db.Prepare(
        "INSERT INTO schema_version (version, description, applied_time_us) VALUES (?, ?, ?)",
        &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, int64_t{migration.version})
                            .Bind(2, migration.description)
                            .Bind(3, NowMicros())
                            .Run());
    PBA_RETURN_IF_ERROR(transaction.Commit());
  }
  return Status::Ok();
}

}  // namespace pba
