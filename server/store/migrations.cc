#include "store/migrations.h"

#include <chrono>
#include <iterator>
#include <string>

#include "store/transaction.h"

namespace pba {
namespace {

struct Migration {
  int version;
  const char* description;
  const char* sql;
  // Rebuilds a table (SQLite cannot change a constraint in place): run as
  // SQLite's "12-step" procedure prescribes, with foreign keys off and
  // checked before the commit.
  bool rebuilds_tables = false;
};

// Job states are stored by their pba.v1.Job.State names so that the file
// reads well in the sqlite3 shell. Times are microseconds since the Unix
// epoch (UTC). `number` orders jobs by creation, independent of the clock.
// Applied in this order; the last entry's version is LatestSchemaVersion().
constexpr Migration kMigrations[] = {
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
    // The atlas store. Rows are keyed by integer ids; names are unique where
    // clients address by them. Revisions, snapshots and the audit log are
    // append-only (triggers refuse UPDATE and DELETE), so history cannot be
    // rewritten even by a buggy caller. Metadata (colour, group, material)
    // is versioned in the revisions beside the geometry, so a snapshot pins
    // the material a job used; structures keep only the head pointer and the
    // metadata etag. The composite foreign keys tie a revision to its own
    // structure wherever a (revision, structure) pair is stored.
    {2, "atlas store: users, projects, members, structures, revisions, locks, snapshots, audit",
     R"sql(
CREATE TABLE users (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  token_sha256 TEXT NOT NULL UNIQUE CHECK (length(token_sha256) = 64),
  created_us INTEGER NOT NULL,
  disabled INTEGER NOT NULL DEFAULT 0 CHECK (disabled IN (0, 1))
);
CREATE TABLE projects (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  created_us INTEGER NOT NULL,
  created_by INTEGER NOT NULL REFERENCES users (id)
);
CREATE TABLE members (
  project INTEGER NOT NULL REFERENCES projects (id),
  user INTEGER NOT NULL REFERENCES users (id),
  role TEXT NOT NULL CHECK (role IN ('viewer', 'editor', 'admin')),
  PRIMARY KEY (project, user)
) WITHOUT ROWID;
CREATE INDEX members_by_user ON members (user, project);
CREATE TABLE structures (
  id INTEGER PRIMARY KEY,
  project INTEGER NOT NULL REFERENCES projects (id),
  name TEXT NOT NULL,
  -- NULL only inside the transaction that creates the structure.
  head_revision INTEGER,
  metadata_etag TEXT NOT NULL,
  created_us INTEGER NOT NULL,
  created_by INTEGER NOT NULL REFERENCES users (id),
  UNIQUE (project, name),
  FOREIGN KEY (head_revision, id) REFERENCES structure_revisions (id, structure)
);
CREATE TABLE structure_revisions (
  id INTEGER PRIMARY KEY,
  structure INTEGER NOT NULL REFERENCES structures (id),
  number INTEGER NOT NULL CHECK (number >= 1),
  parent INTEGER,
  author INTEGER NOT NULL REFERENCES users (id),
  time_us INTEGER NOT NULL,
  kind TEXT NOT NULL CHECK (kind IN ('create', 'commit', 'metadata', 'revert')),
  message TEXT NOT NULL,
  content_sha256 TEXT NOT NULL CHECK (length(content_sha256) = 64),
  geometry_format TEXT NOT NULL
    CHECK (geometry_format IN ('contours_json', 'nifti', 'stl', 'obj', 'vtk')),
  size_bytes INTEGER NOT NULL CHECK (size_bytes >= 0),
  material_json TEXT NOT NULL,
  colour_r INTEGER NOT NULL CHECK (colour_r BETWEEN 0 AND 255),
  colour_g INTEGER NOT NULL CHECK (colour_g BETWEEN 0 AND 255),
  colour_b INTEGER NOT NULL CHECK (colour_b BETWEEN 0 AND 255),
  group_path TEXT NOT NULL,
  UNIQUE (structure, number),
  UNIQUE (id, structure),
  CHECK ((number = 1) = (parent IS NULL)),
  FOREIGN KEY (parent, structure) REFERENCES structure_revisions (id, structure)
);
CREATE INDEX structure_revisions_by_hash ON structure_revisions (content_sha256);
-- A revision's parent is the previous revision of the same structure, so the
-- history of a structure is one chain numbered 1, 2, 3, ...
CREATE TRIGGER structure_revisions_chain BEFORE INSERT ON structure_revisions
WHEN NEW.parent IS NOT NULL AND
     (SELECT number FROM structure_revisions WHERE id = NEW.parent) IS NOT NEW.number - 1
BEGIN
  SELECT RAISE(ABORT, 'a revision''s parent must be the previous revision of its structure');
END;
CREATE TRIGGER structure_revisions_no_update BEFORE UPDATE ON structure_revisions
BEGIN
  SELECT RAISE(ABORT, 'structure revisions are immutable');
END;
CREATE TRIGGER structure_revisions_no_delete BEFORE DELETE ON structure_revisions
BEGIN
  SELECT RAISE(ABORT, 'structure revisions are never deleted');
END;
CREATE TABLE locks (
  structure INTEGER PRIMARY KEY REFERENCES structures (id),
  owner INTEGER NOT NULL REFERENCES users (id),
  lock_id TEXT NOT NULL UNIQUE,
  acquired_us INTEGER NOT NULL,
  lease_expiry_us INTEGER NOT NULL
);
CREATE TABLE snapshots (
  id INTEGER PRIMARY KEY,
  project INTEGER NOT NULL REFERENCES projects (id),
  name TEXT NOT NULL,
  created_us INTEGER NOT NULL,
  author INTEGER NOT NULL REFERENCES users (id),
  UNIQUE (id, project)
);
CREATE INDEX snapshots_by_project ON snapshots (project, id);
CREATE TABLE snapshot_members (
  snapshot INTEGER NOT NULL REFERENCES snapshots (id),
  structure INTEGER NOT NULL REFERENCES structures (id),
  revision INTEGER NOT NULL,
  PRIMARY KEY (snapshot, structure),
  FOREIGN KEY (revision, structure) REFERENCES structure_revisions (id, structure)
) WITHOUT ROWID;
CREATE TABLE snapshot_tags (
  project INTEGER NOT NULL REFERENCES projects (id),
  tag TEXT NOT NULL,
  snapshot INTEGER NOT NULL,
  PRIMARY KEY (project, tag),
  FOREIGN KEY (snapshot, project) REFERENCES snapshots (id, project)
) WITHOUT ROWID;
CREATE TRIGGER snapshots_no_update BEFORE UPDATE ON snapshots
BEGIN
  SELECT RAISE(ABORT, 'snapshots are immutable');
END;
CREATE TRIGGER snapshots_no_delete BEFORE DELETE ON snapshots
BEGIN
  SELECT RAISE(ABORT, 'snapshots are immutable');
END;
CREATE TRIGGER snapshot_members_no_update BEFORE UPDATE ON snapshot_members
BEGIN
  SELECT RAISE(ABORT, 'snapshots are immutable');
END;
CREATE TRIGGER snapshot_members_no_delete BEFORE DELETE ON snapshot_members
BEGIN
  SELECT RAISE(ABORT, 'snapshots are immutable');
END;
-- project is NULL for changes outside any project (a new user); user is NULL
-- for changes made by the server itself rather than by a user.
CREATE TABLE audit_log (
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  time_us INTEGER NOT NULL,
  user INTEGER REFERENCES users (id),
  project INTEGER REFERENCES projects (id),
  action TEXT NOT NULL,
  target TEXT NOT NULL,
  revision INTEGER REFERENCES structure_revisions (id),
  detail TEXT NOT NULL DEFAULT ''
);
CREATE INDEX audit_log_by_project ON audit_log (project, seq);
CREATE TRIGGER audit_log_no_update BEFORE UPDATE ON audit_log
BEGIN
  SELECT RAISE(ABORT, 'the audit log is append-only');
END;
CREATE TRIGGER audit_log_no_delete BEFORE DELETE ON audit_log
BEGIN
  SELECT RAISE(ABORT, 'the audit log is append-only');
END;
)sql"},
    // Jobs carry the user who submitted them: only they may cancel one.
    // Jobs stored before have no owner ('').
    {3, "jobs: the submitting user", R"sql(
ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT '';
)sql"},
    // A commit may carry the client's request id, so that a commit retried
    // after a lost reply finds the revision it made instead of failing on
    // the moved head (per structure; NULL for revisions without one).
    {4, "structure revisions: the committing request's id", R"sql(
ALTER TABLE structure_revisions ADD COLUMN request_id TEXT;
CREATE UNIQUE INDEX structure_revisions_by_request
  ON structure_revisions (structure, request_id) WHERE request_id IS NOT NULL;
)sql"},
    // Creates (projects, structures, snapshots) may carry the client's
    // request id too, so that a create retried after a lost reply returns
    // what the first one made instead of ALREADY_EXISTS or a second
    // snapshot. Keys are per user (another user's key never collides) and
    // shared by the three kinds. arguments_sha256 fingerprints the
    // request's arguments (CreateFingerprint, atlas_store_internal.h), so
    // a key reused for different arguments is told apart from a retry.
    // Append-only, as the rows they point at are.
    {5, "creates: the creating request's id", R"sql(
CREATE TABLE create_requests (
  user INTEGER NOT NULL REFERENCES users (id),
  request_id TEXT NOT NULL CHECK (length(request_id) BETWEEN 1 AND 200),
  kind TEXT NOT NULL CHECK (kind IN ('project', 'structure', 'snapshot')),
  arguments_sha256 TEXT NOT NULL CHECK (length(arguments_sha256) = 64),
  project INTEGER NOT NULL REFERENCES projects (id),
  structure INTEGER REFERENCES structures (id),
  snapshot INTEGER REFERENCES snapshots (id),
  time_us INTEGER NOT NULL,
  PRIMARY KEY (user, request_id),
  CHECK ((kind = 'structure') = (structure IS NOT NULL)),
  CHECK ((kind = 'snapshot') = (snapshot IS NOT NULL))
) WITHOUT ROWID;
CREATE TRIGGER create_requests_no_update BEFORE UPDATE ON create_requests
BEGIN
  SELECT RAISE(ABORT, 'create requests are immutable');
END;
CREATE TRIGGER create_requests_no_delete BEFORE DELETE ON create_requests
BEGIN
  SELECT RAISE(ABORT, 'create requests are never deleted');
END;
)sql"},
    // Jobs: a priority (the queue runs the highest first), a wall-clock
    // limit, the atlas snapshot a job ran against (or an import made), and
    // an import's request. A snapshot made by an import names its job, so
    // that an import finished again after a crash finds what it made.
    {6, "jobs: priority, time limit, snapshot, atlas import", R"sql(
ALTER TABLE jobs ADD COLUMN priority INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN timeout_s INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN snapshot_project TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN snapshot TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN atlas_import BLOB;
CREATE INDEX jobs_queue ON jobs (state, priority DESC, number);
ALTER TABLE snapshots ADD COLUMN import_job TEXT;
CREATE UNIQUE INDEX snapshots_by_import_job ON snapshots (import_job)
  WHERE import_job IS NOT NULL;
)sql"},
    // Trust boundaries (issue 18). Server admins see and cancel every
    // job; the user "admin" a first start created is one (a first start
    // makes no other name). A job's project (the snapshot's, or the one
    // an import goes into) decides who sees it, so ListJobs can filter
    // and page in SQL: an import's project is in its request blob, which
    // SQL cannot read, but its name was made "import into <project>" by
    // the submit (JobStore::CreateJob), so that fills older rows.
    {7, "users: server admins; jobs: the project they belong to", R"sql(
ALTER TABLE users ADD COLUMN server_admin INTEGER NOT NULL DEFAULT 0
  CHECK (server_admin IN (0, 1));
UPDATE users SET server_admin = 1 WHERE name = 'admin';
ALTER TABLE jobs ADD COLUMN project TEXT NOT NULL DEFAULT '';
UPDATE jobs SET project = snapshot_project WHERE snapshot_project != '';
UPDATE jobs SET project = substr(name, 13)
  WHERE project = '' AND atlas_import IS NOT NULL AND name LIKE 'import into %';
CREATE INDEX jobs_by_project ON jobs (project, number);
)sql"},
    // The MPI processes a job runs on (SubmitJobRequest.ranks).
    {8, "jobs: MPI ranks", R"sql(
ALTER TABLE jobs ADD COLUMN ranks INTEGER NOT NULL DEFAULT 0;
)sql"},
    // Derived structures (atlas/derived_structure.h): a revision's geometry
    // may be a recipe, format 'derived'. The CHECK on geometry_format is
    // part of the table, so the table is rebuilt with every row, id and
    // index as it was, and its triggers made again.
    {9, "structure revisions: the derived format", R"sql(
CREATE TABLE structure_revisions_v9 (
  id INTEGER PRIMARY KEY,
  structure INTEGER NOT NULL REFERENCES structures (id),
  number INTEGER NOT NULL CHECK (number >= 1),
  parent INTEGER,
  author INTEGER NOT NULL REFERENCES users (id),
  time_us INTEGER NOT NULL,
  kind TEXT NOT NULL CHECK (kind IN ('create', 'commit', 'metadata', 'revert')),
  message TEXT NOT NULL,
  content_sha256 TEXT NOT NULL CHECK (length(content_sha256) = 64),
  geometry_format TEXT NOT NULL
    CHECK (geometry_format IN ('contours_json', 'nifti', 'stl', 'obj', 'vtk', 'derived')),
  size_bytes INTEGER NOT NULL CHECK (size_bytes >= 0),
  material_json TEXT NOT NULL,
  colour_r INTEGER NOT NULL CHECK (colour_r BETWEEN 0 AND 255),
  colour_g INTEGER NOT NULL CHECK (colour_g BETWEEN 0 AND 255),
  colour_b INTEGER NOT NULL CHECK (colour_b BETWEEN 0 AND 255),
  group_path TEXT NOT NULL,
  request_id TEXT,
  UNIQUE (structure, number),
  UNIQUE (id, structure),
  CHECK ((number = 1) = (parent IS NULL)),
  FOREIGN KEY (parent, structure) REFERENCES structure_revisions (id, structure)
);
INSERT INTO structure_revisions_v9 (id, structure, number, parent, author, time_us, kind,
    message, content_sha256, geometry_format, size_bytes, material_json, colour_r, colour_g,
    colour_b, group_path, request_id)
  SELECT id, structure, number, parent, author, time_us, kind, message, content_sha256,
    geometry_format, size_bytes, material_json, colour_r, colour_g, colour_b, group_path,
    request_id
  FROM structure_revisions;
DROP TABLE structure_revisions;
ALTER TABLE structure_revisions_v9 RENAME TO structure_revisions;
CREATE INDEX structure_revisions_by_hash ON structure_revisions (content_sha256);
CREATE UNIQUE INDEX structure_revisions_by_request
  ON structure_revisions (structure, request_id) WHERE request_id IS NOT NULL;
CREATE TRIGGER structure_revisions_chain BEFORE INSERT ON structure_revisions
WHEN NEW.parent IS NOT NULL AND
     (SELECT number FROM structure_revisions WHERE id = NEW.parent) IS NOT NEW.number - 1
BEGIN
  SELECT RAISE(ABORT, 'a revision''s parent must be the previous revision of its structure');
END;
CREATE TRIGGER structure_revisions_no_update BEFORE UPDATE ON structure_revisions
BEGIN
  SELECT RAISE(ABORT, 'structure revisions are immutable');
END;
CREATE TRIGGER structure_revisions_no_delete BEFORE DELETE ON structure_revisions
BEGIN
  SELECT RAISE(ABORT, 'structure revisions are never deleted');
END;
)sql",
     true},
    // A job handed to a cluster scheduler (jobs/slurm_executor.h): its id
    // there ('submitting' between the claim and the scheduler's answer) and
    // what the scheduler last said of it.
    {10, "jobs: the cluster scheduler's job", R"sql(
ALTER TABLE jobs ADD COLUMN scheduler_job TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN scheduler_state TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN scheduler_reason TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN scheduler_node TEXT NOT NULL DEFAULT '';
CREATE INDEX jobs_scheduled ON jobs (scheduler_job) WHERE scheduler_job != '';
)sql"},
};

int64_t NowMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The first row PRAGMA foreign_key_check finds, as text; "" for none.
Status DanglingForeignKey(Database& db, std::string* dangling) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db.Prepare("PRAGMA foreign_key_check", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Step(&row));
  *dangling = row ? stmt.ColumnText(0) + " row " + std::to_string(stmt.ColumnInt(1)) + " -> " +
                        stmt.ColumnText(2)
                  : "";
  return Status::Ok();
}

Status ApplyMigrationSql(Database& db, const Migration& migration) {
  Transaction transaction(db);
  PBA_RETURN_IF_ERROR(transaction.status());
  PBA_RETURN_IF_ERROR(db.Exec(migration.sql));
  if (migration.rebuilds_tables) {
    std::string dangling;
    PBA_RETURN_IF_ERROR(DanglingForeignKey(db, &dangling));
    if (!dangling.empty()) {
      return Status::Internal("schema version " + std::to_string(migration.version) +
                              " would leave a foreign key dangling: " + dangling);
    }
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db.Prepare(
      "INSERT INTO schema_version (version, description, applied_time_us) VALUES (?, ?, ?)",
      &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, int64_t{migration.version})
                          .Bind(2, migration.description)
                          .Bind(3, NowMicros())
                          .Run());
  return transaction.Commit();
}

// One migration in its own transaction; a rebuild with foreign keys off
// (a no-op inside a transaction, so around it) and on again after.
Status ApplyMigration(Database& db, const Migration& migration) {
  if (!migration.rebuilds_tables) return ApplyMigrationSql(db, migration);
  PBA_RETURN_IF_ERROR(db.Exec("PRAGMA foreign_keys=OFF"));
  const Status applied = ApplyMigrationSql(db, migration);
  PBA_RETURN_IF_ERROR(db.Exec("PRAGMA foreign_keys=ON"));
  return applied;
}

}  // namespace

int LatestSchemaVersion() { return kMigrations[std::size(kMigrations) - 1].version; }

Status ReadSchemaVersion(Database& db, int* version) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db.Prepare("SELECT COALESCE(MAX(version), 0) FROM schema_version", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Step(&row));
  *version = row ? static_cast<int>(stmt.ColumnInt(0)) : 0;
  return Status::Ok();
}

Status ApplyMigrations(Database& db, int up_to) {
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
  for (const Migration& migration : kMigrations) {
    if (migration.version <= current) continue;
    if (up_to > 0 && migration.version > up_to) break;
    PBA_RETURN_IF_ERROR(ApplyMigration(db, migration));
  }
  return Status::Ok();
}

}  // namespace pba
