// AtlasStore: the shared, versioned repository of atlas structures (users,
// projects and roles, structures and their immutable revisions, edit locks
// with leases, snapshots with tags, and an audit log) in pba.db, with the
// geometry in a BlobStore under <data>/blobs.
//
// Every change is one SQLite transaction that includes its audit_log row, so
// the log has a row for exactly the changes that happened. A refused
// operation changes nothing and logs nothing; reads log nothing.
//
// The acting user comes first in every call; it is the name Authenticate()
// returned for the caller's token. Rights are checked per project:
//   viewer  reads (structures, history, revisions, snapshots, audit)
//   editor  also creates structures, locks, commits, edits metadata,
//           reverts, snapshots and tags
//   admin   also sets roles, removes members and breaks locks
// The creator of a project is its first admin.
//
// Users: a user is created with a token (CreateUser), may be disabled and
// enabled again by the operator (SetUserDisabled; offline, through
// pba-server admin), and may be a server admin: not a project role but a
// server-wide one, which sees and cancels every job (job_service.h). The
// store does not act on it: no project right follows from it.
//
// Editing rules (docs ARCHITECTURE "Collaboration rules"):
// - Geometry changes (Commit, Revert) need the structure's lock, held with an
//   unexpired lease, and a base revision equal to the head. A stale base is
//   kAborted naming the head; a missing, foreign or lapsed lock is
//   kFailedPrecondition naming why (and the holder).
// - Metadata changes (UpdateMetadata) need no lock but the current metadata
//   etag (optimistic concurrency). They are versioned like geometry: each one
//   is a new revision that keeps the head's geometry. We chose this over
//   unversioned metadata on the structure row because jobs run against
//   snapshots, and a snapshot must pin the material parameters a result was
//   computed with, not just the shape. The price: a metadata edit moves the
//   head, so a lock holder's next commit is refused (kAborted, head named)
//   and must be rebased on the new head, which also keeps a commit from
//   silently overwriting the metadata edit.
//
// Thread-safe: one connection behind a mutex. The blob of a new revision is
// written before its row, inside the same critical section, so a crash leaves
// at worst an unreferenced blob (SweepBlobs removes it), never a row naming a
// missing blob.
//
// Idempotent creates: CreateProject, CreateStructure and CreateSnapshot take
// an optional request id (at most 200 characters), as Commit does. A create
// whose request id `user` already used for a create with the same arguments
// returns what that one made (*replayed set; nothing written, nothing
// audited), even if, say, the name is taken by now (by it). The same id with
// other arguments (another kind, name, metadata, ...) is kInvalidArgument
// naming request_id: a client bug, which no retry fixes. Keys are per user:
// another user's key never collides. The geometry is not compared (a retry
// may come after its upload was consumed), only the other arguments.
//
// Implemented in six files: atlas_store.cc (users, roles, structures,
// revisions), atlas_store_creates.cc (projects, structures, request ids),
// atlas_store_locks.cc, atlas_store_snapshots.cc (snapshots, tags, the
// audit listing), atlas_store_import.cc and atlas_store_users.cc (disabling
// users, removing members, role checks, commits by request id).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pba/status.h"
#include "store/atlas_types.h"
#include "store/blob_store.h"
#include "store/database.h"
#include "store/mapped_file.h"

namespace pba {

// The wall clock in microseconds since the Unix epoch; tests inject their own.
using MicrosClock = std::function<int64_t()>;

// One structure of Import().
struct ImportedStructure {
  std::string name;
  StructureMetadata metadata;
  StructureFormat format = StructureFormat::kContours;
  std::filesystem::path file;  // its geometry, already checked
};

// A snapshot member with where its geometry lies (SnapshotFiles()).
struct SnapshotFile {
  Revision revision;
  std::filesystem::path blob;  // read-only, content-addressed
};

// A structure someone holds locked, with its head (LockedNeighbours()).
struct LockedNeighbour {
  Revision head;
  std::filesystem::path blob;  // the head's geometry, read-only
  std::string holder;
};

// Commit() arguments. `geometry` is borrowed for the call.
struct CommitRequest {
  StructureRef structure;
  std::string lock_id;
  int64_t base_revision = 0;
  StructureFormat format = StructureFormat::kContours;
  std::string_view geometry;
  // When set, `geometry` is this file's content (a verified upload), and the
  // file becomes the blob by rename instead of being copied
  // (BlobStore::PutFile): once the blob is stored the file's old path is
  // gone. A call refused before that (lock, base, rights) leaves it alone.
  const MappedFile* geometry_file = nullptr;
  // Set to change the material with the geometry; otherwise the head's is kept.
  std::optional<std::string> material_json;
  std::string message;
  // The client's key for this commit (at most 200 characters; empty: none).
  // A commit whose request_id this user already used on this structure
  // returns the revision it made then, whatever the lock and head are now;
  // another user's is kAlreadyExists.
  std::string request_id;
};

// CreateStructure() arguments; `geometry` and `geometry_file` as in
// CommitRequest.
struct NewStructure {
  StructureRef structure;
  StructureMetadata metadata;
  StructureFormat format = StructureFormat::kContours;
  std::string_view geometry;
  const MappedFile* geometry_file = nullptr;
  std::string message;     // the revision's ("created" when empty)
  std::string request_id;  // see "Idempotent creates" above; empty: none
};

// UpdateMetadata() arguments: the fields to change (at least one).
struct MetadataUpdate {
  std::optional<Colour> colour;
  std::optional<std::string> group_path;
  std::optional<std::string> material_json;
};

class AtlasStore {
 public:
  // Leases longer than this are refused: a vanished client must not keep a
  // structure locked for long. Clients renew instead.
  static constexpr int64_t kMaxLeaseMicros = 3600LL * 1000 * 1000;
  static constexpr size_t kMaxGeometryBytes = size_t{1} << 30;

  // Opens (creating if absent) <data_dir>/pba.db, migrating it, and
  // <data_dir>/blobs. `clock` defaults to the system clock.
  static Status Open(const std::filesystem::path& data_dir, std::unique_ptr<AtlasStore>* out,
                     MicrosClock clock = nullptr);

  // --- users and rights ---------------------------------------------------
  // Creates a user and sets *token to its access token (64 hex characters).
  // The token is returned only here: the store keeps only its SHA-256.
  // `server_admin`: see "Users" above.
  Status CreateUser(const std::string& name, std::string* token, bool server_admin = false);
  // The user a token belongs to, and (when `server_admin` is given) whether
  // they are a server admin; kUnauthenticated for an unknown token or a
  // disabled user (the message never echoes the token). Reads the database
  // on every call (no cache), so a user disabled by another process is
  // refused from their next call on.
  Status Authenticate(const std::string& token, std::string* user, bool* server_admin = nullptr);
  // Disables `name` (their token is refused, as is every call naming them as
  // the acting user) or enables them again; kNotFound for an unknown user.
  // Their memberships, revisions and jobs stay; locks they hold stay until
  // their lease lapses or a project admin breaks them. Audited when it
  // changes anything (*changed, when given, says whether it did).
  Status SetUserDisabled(const std::string& name, bool disabled, bool* changed = nullptr);
  // Whether `name` is disabled now (read from the database, as
  // Authenticate); kNotFound for an unknown user. The job queue asks it
  // before a job starts: a disabled user's queued jobs do not run.
  Status IsUserDisabled(const std::string& name, bool* disabled);
  // How many users exist (disabled ones included): the server creates its
  // first admin when there are none.
  Status CountUsers(int64_t* count);
  // Creates a project with `user` as its admin. `request_id` as above.
  Status CreateProject(const std::string& user, const std::string& project,
                       const std::string& request_id = "", bool* replayed = nullptr);
  // Sets `member`'s role in `project`; `admin` must be an admin there. The
  // last admin cannot be demoted (the project would have no one to manage it).
  Status SetRole(const std::string& admin, const std::string& project, const std::string& member,
                 Role role);
  // Removes `member` from `project`; `admin` must be an admin there.
  // kNotFound when they are not a member; the last admin cannot be removed
  // (kFailedPrecondition, as SetRole). Locks `member` holds on the
  // project's structures are released in the same transaction (each audited
  // as lock.break); *released_locks names their structures.
  Status RemoveMember(const std::string& admin, const std::string& project,
                      const std::string& member, std::vector<std::string>* released_locks);
  // OK when `user` (enabled) has at least `minimum` in `project`; otherwise
  // what Enter() says (kPermissionDenied naming the role needed, kNotFound
  // for no such project). Changes nothing: for a service to refuse a call
  // before it reads or parses what the call uploaded.
  Status CheckRole(const std::string& user, const std::string& project, Role minimum);
  // `user`'s role in `project`; *is_member false (and *role untouched) if none.
  Status RoleOf(const std::string& project, const std::string& user, Role* role, bool* is_member);
  // The projects `user` is a member of, by creation. Paging as JobStore:
  // page_size 0 -> 50, capped at 1000, negative kInvalidArgument.
  // `page_token` and `*next_page_token` may be the same string.
  Status ListProjects(const std::string& user, int page_size, const std::string& page_token,
                      std::vector<ProjectInfo>* projects, std::string* next_page_token);

  // --- structures ---------------------------------------------------------
  // Creates a structure with revision 1 holding `geometry`; `message` is the
  // revision's ("created" when empty).
  Status CreateStructure(const std::string& user, const StructureRef& ref,
                         const StructureMetadata& metadata, StructureFormat format,
                         std::string_view geometry, Revision* revision,
                         const std::string& message = "");
  // The same with a request id and a geometry file (NewStructure).
  Status CreateStructure(const std::string& user, const NewStructure& request, Revision* revision,
                         bool* replayed = nullptr);
  // The revision 1 an earlier create with request.request_id made, if
  // `user` made one with the same arguments (*found); kInvalidArgument as
  // CreateStructure for other arguments. Lets the service answer a retry
  // without its upload, which the first create consumed.
  Status FindCreatedStructure(const std::string& user, const NewStructure& request,
                              Revision* revision, bool* found);
  Status GetStructure(const std::string& user, const StructureRef& ref, StructureInfo* info);
  // The project's structures by name (byte order); viewers may list. Paging
  // as ListProjects.
  Status ListStructures(const std::string& user, const std::string& project, int page_size,
                        const std::string& page_token, std::vector<StructureInfo>* structures,
                        std::string* next_page_token);

  // --- locks --------------------------------------------------------------
  // Locks `ref` for `user` for `lease_us` microseconds from now. A lock whose
  // lease has lapsed is taken over (info->took_over_from names the old
  // holder, and the audit log says so); an unexpired one, even the caller's
  // own, is kFailedPrecondition naming the holder and the expiry.
  Status AcquireLock(const std::string& user, const StructureRef& ref, int64_t lease_us,
                     LockInfo* info);
  // Extends an unexpired lease to now + lease_us. A lapsed lease cannot be
  // renewed (someone may have read it as free): acquire again.
  Status RenewLock(const std::string& user, const std::string& lock_id, int64_t lease_us,
                   LockInfo* info);
  // Releases the caller's lock (lapsed or not, as long as no one took it over).
  // With `released` non-null, sets it to the structure that was locked.
  Status ReleaseLock(const std::string& user, const std::string& lock_id,
                     StructureRef* released = nullptr);
  // Removes whoever's lock is on `ref`; project admins only. `reason` is
  // audited. With `holder` non-null, sets it to the user whose lock it was.
  Status BreakLock(const std::string& admin, const StructureRef& ref, const std::string& reason,
                   std::string* holder = nullptr);

  // --- revisions ----------------------------------------------------------
  // Stores a new revision with the given geometry (and material, if set);
  // colour and group are kept from the head. See the editing rules above.
  // *replayed (when given) says whether the revision is an earlier one
  // returned for a repeated request_id (nothing was written).
  Status Commit(const std::string& user, const CommitRequest& request, Revision* revision,
                bool* replayed = nullptr);
  // The revision an earlier Commit() by `user` with `request_id` made on
  // `ref` (*found), checked as Commit checks rights (editor); another
  // user's is kAlreadyExists. Lets the service answer a retried commit
  // without its upload, which the first commit consumed. An empty
  // request_id finds nothing.
  Status FindCommit(const std::string& user, const StructureRef& ref, const std::string& request_id,
                    Revision* revision, bool* found);
  // Changes metadata if `etag` is the structure's current metadata etag
  // (else kAborted naming the current one). *new_etag is the etag after.
  Status UpdateMetadata(const std::string& user, const StructureRef& ref, const std::string& etag,
                        const MetadataUpdate& update, const std::string& message,
                        Revision* revision, std::string* new_etag);
  // Newest first; paging as ListProjects.
  Status History(const std::string& user, const StructureRef& ref, int page_size,
                 const std::string& page_token, std::vector<Revision>* revisions,
                 std::string* next_page_token);
  // Revision `number`; with `geometry` non-null also its verified blob.
  Status GetRevision(const std::string& user, const StructureRef& ref, int64_t number,
                     Revision* revision, std::string* geometry);
  // A new revision with the geometry and metadata of `to_revision`, under the
  // same rules as Commit. History is never rewritten.
  Status Revert(const std::string& user, const StructureRef& ref, const std::string& lock_id,
                int64_t base_revision, int64_t to_revision, const std::string& message,
                Revision* revision);

  // --- snapshots ----------------------------------------------------------
  // Pins the head revision of every structure in `project` at one instant.
  // An empty `name` names it by its UTC time ("snapshot 2026-01-01
  // 00.00.00 UTC"). `request_id` as above (an empty name is compared as
  // empty, so a retry without a name replays).
  Status CreateSnapshot(const std::string& user, const std::string& project,
                        const std::string& name, SnapshotInfo* snapshot,
                        const std::string& request_id = "", bool* replayed = nullptr);
  // Names snapshot `snapshot_id` by `tag`, unique within the project
  // (kAlreadyExists otherwise). Tags are never all digits: those read as ids.
  Status Tag(const std::string& user, const std::string& project, int64_t snapshot_id,
             const std::string& tag);
  // Newest first; members are not loaded (revisions left empty).
  Status ListSnapshots(const std::string& user, const std::string& project, int page_size,
                       const std::string& page_token, std::vector<SnapshotInfo>* snapshots,
                       std::string* next_page_token);
  // `tag_or_id` is a tag, a decimal snapshot id, or the name given at
  // snapshot or import time when one snapshot alone has it (a name several
  // share is refused, listing their ids); members are loaded.
  Status ResolveSnapshot(const std::string& user, const std::string& project,
                         const std::string& tag_or_id, SnapshotInfo* snapshot);

  // The geometry files of a snapshot's members, for a job run against it;
  // viewers may read. Every blob is verified against its hash first.
  Status SnapshotFiles(const std::string& user, const std::string& project, int64_t snapshot_id,
                       std::vector<SnapshotFile>* files);

  // Revision `number` (>= 1) of a structure with its geometry file
  // (read-only); viewers may read. The file is what a snapshot's member
  // would be: the surfaces of one revision alone (DownloadSurfaces).
  Status RevisionFile(const std::string& user, const StructureRef& ref, int64_t number,
                      SnapshotFile* file);

  // Every structure of `project` with its head revision and the head's
  // geometry file (read-only), by name; viewers may read. What a commit of
  // a derived structure is checked against (derived_check.h).
  Status Heads(const std::string& user, const std::string& project,
               std::vector<SnapshotFile>* heads);

  // The structures of `project` other than `except` that someone other than
  // `user` holds locked with an unexpired lease, with their heads: what a
  // commit by `user` must not grow into. Viewers may ask.
  Status LockedNeighbours(const std::string& user, const std::string& project,
                          const std::string& except, std::vector<LockedNeighbour>* neighbours);

  // --- atlas import (a job's last step) ------------------------------------
  // Creates every structure (revision 1, kind "create", `message`) and then
  // a snapshot of the project named `snapshot_name`, in one transaction that
  // records `job_id` on the snapshot; editors only. Called again with the
  // same job id it returns the snapshot made then and writes nothing
  // (*replayed), so a job finished again after a crash does not import
  // twice. A structure that exists already is kFailedPrecondition naming
  // it (and up to nine more); nothing is written then.
  Status Import(const std::string& user, const std::string& project, const std::string& job_id,
                const std::vector<ImportedStructure>& structures, const std::string& snapshot_name,
                const std::string& message, SnapshotInfo* snapshot, bool* replayed);

  // --- audit and maintenance ----------------------------------------------
  // The project's audit rows, newest first; paging as ListProjects.
  Status ListAudit(const std::string& user, const std::string& project, int page_size,
                   const std::string& page_token, std::vector<AuditEntry>* entries,
                   std::string* next_page_token);
  // Removes blobs no revision references, and leftover temporary files. It
  // knows only the atlas store's references: anything else kept under
  // <data>/blobs must add its own before this runs (nothing does yet).
  Status SweepBlobs(BlobSweepReport* report);

 private:
  // What an operation knows about its caller once checked.
  struct Caller {
    int64_t user = 0;
    int64_t project = 0;
    Role role = Role::kViewer;
  };
  struct StructureRow {
    int64_t id = 0;
    int64_t head_id = 0;
    int64_t head_number = 0;
    std::string etag;
  };
  struct LockRow {
    int64_t owner = 0;
    std::string owner_name;
    std::string lock_id;
    int64_t acquired_us = 0;
    int64_t lease_expiry_us = 0;
  };
  // A revision's stored content, for building the next one.
  struct Content {
    std::string sha256;
    StructureFormat format = StructureFormat::kContours;
    int64_t size_bytes = 0;
    StructureMetadata metadata;
  };

  AtlasStore(std::unique_ptr<Database> db, std::unique_ptr<BlobStore> blobs, MicrosClock clock)
      : db_(std::move(db)), blobs_(std::move(blobs)), clock_(std::move(clock)) {}

  // The id of the enabled user `name`; kUnauthenticated otherwise.
  Status ActingUser(const std::string& name, int64_t* id);
  // Checks `user`'s role in `project` is at least `minimum`.
  Status Enter(const std::string& user, const std::string& project, Role minimum, Caller* caller);
  // `member`'s user id and role name in `project` ("" when not a member);
  // kNotFound when there is no such user. SetRole and RemoveMember.
  Status FindMember(int64_t project, const std::string& member, int64_t* member_id,
                    std::string* role);
  // How many admins `project` has (the last one stays).
  Status CountAdmins(int64_t project, int64_t* count);
  Status FindStructure(const Caller& caller, const StructureRef& ref, StructureRow* row);
  // Enter() into ref.project, then FindStructure(): every per-structure call
  // starts so.
  Status EnterStructure(const std::string& user, const StructureRef& ref, Role minimum,
                        Caller* caller, StructureRow* row);
  Status FindLock(int64_t structure, LockRow* lock, bool* found);
  // The lock rules of Commit and Revert.
  Status CheckLockForWrite(const Caller& caller, const StructureRef& ref, int64_t structure,
                           const std::string& lock_id);
  // CheckLockForWrite, then the base revision must be the head (kAborted
  // naming the head otherwise).
  Status CheckWrite(const Caller& caller, const StructureRef& ref, const StructureRow& structure,
                    const std::string& lock_id, int64_t base_revision);
  // The revision the caller's commit with `request_id` made on `structure`
  // (*found); another user's is kAlreadyExists; empty finds nothing.
  Status FindCommitRequest(const Caller& caller, const StructureRef& ref, int64_t structure,
                           const std::string& request_id, Revision* revision, bool* found);
  // A create's request id row, when `user` has one for `request_id`.
  struct CreateRequestRow {
    std::string kind;  // project, structure, snapshot
    std::string arguments_sha256;
    int64_t project = 0;
    int64_t structure = 0;
    int64_t snapshot = 0;
  };
  // Looks up (user, request_id). With a row found: *found true, and
  // kInvalidArgument naming request_id unless kind and fingerprint match.
  Status FindCreateRequest(int64_t user, const std::string& request_id, const std::string& kind,
                           const std::string& fingerprint, CreateRequestRow* row, bool* found);
  // Records what the create with `request_id` made (nothing when empty).
  Status RecordCreateRequest(int64_t user, const std::string& request_id, const std::string& kind,
                             const std::string& fingerprint, int64_t project, int64_t structure,
                             int64_t snapshot);
  // The blob of new geometry: the file moved into place when given, else a
  // copy of `geometry`.
  Status StoreGeometry(std::string_view geometry, const MappedFile* file, std::string* sha256);
  // Appends revision head + 1 of `kind`, moves the head (and the metadata
  // etag when `metadata_changed`) and audits it as `action`.
  Status AppendRevision(const Caller& caller, const StructureRef& ref, const StructureRow& row,
                        const std::string& kind, const std::string& action,
                        const std::string& message, const Content& content, bool metadata_changed,
                        Revision* revision, const std::string& request_id = "");
  Status ReadRevision(const StructureRef& ref, int64_t structure, int64_t number,
                      Revision* revision, bool* found);
  // The lock on `structure`, without its id, if any.
  Status PublicLock(const StructureRef& ref, int64_t structure, std::optional<LockInfo>* lock);
  // The id of the one snapshot of the project named `name` (0: none);
  // kInvalidArgument when several are. Under mutex_.
  Status SnapshotNamed(int64_t project_id, const std::string& project, const std::string& name,
                       int64_t* id);
  Status LoadSnapshot(const std::string& project, int64_t project_id, int64_t id, bool with_members,
                      SnapshotInfo* snapshot, bool* found);
  Status Audit(std::optional<int64_t> user, std::optional<int64_t> project,
               const std::string& action, const std::string& target,
               std::optional<int64_t> revision, const std::string& detail);
  Status CheckLease(int64_t lease_us) const;
  // The row of a new structure (head NULL until its first revision).
  Status InsertStructure(const Caller& caller, const std::string& name, int64_t* id);
  // A snapshot of every head of the caller's project, audited; `import_job`
  // non-empty records the import that made it.
  Status PinSnapshot(const Caller& caller, const std::string& project, const std::string& name,
                     const std::string& import_job, int64_t* id);

  std::mutex mutex_;
  std::unique_ptr<Database> db_;
  std::unique_ptr<BlobStore> blobs_;
  MicrosClock clock_;
};

}  // namespace pba
