#include "store/atlas_store.h"

#include <chrono>
#include <set>
#include <system_error>

#include "core/sha256.h"
#include "store/atlas_store_internal.h"
#include "store/migrations.h"
#include "store/page_token.h"
#include "store/random_hex.h"
#include "store/transaction.h"

namespace pba {
namespace {

using atlas_internal::CheckGeometry;
using atlas_internal::Describe;
using atlas_internal::ProjectTarget;
using atlas_internal::Quoted;
using atlas_internal::StructureTarget;

// 32 random bytes: guessing a token is as hard as guessing an AES-256 key.
constexpr int kTokenBytes = 32;

int64_t SystemMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The metadata etag names the revision that last changed the metadata. It is
// opaque to clients; the "m" keeps it from being mistaken for a head number.
std::string MetadataEtag(int64_t revision_number) { return "m" + std::to_string(revision_number); }

constexpr char kRevisionColumns[] =
    "r.number, COALESCE(p.number, 0), u.name, r.time_us, r.kind, r.message, r.content_sha256, "
    "r.geometry_format, r.size_bytes, r.material_json, r.colour_r, r.colour_g, r.colour_b, "
    "r.group_path";
constexpr char kRevisionFrom[] =
    " FROM structure_revisions r JOIN users u ON u.id = r.author "
    "LEFT JOIN structure_revisions p ON p.id = r.parent ";

// Reads a row selected with kRevisionColumns.
void ReadRevisionRow(const Statement& stmt, const StructureRef& ref, Revision* revision) {
  revision->project = ref.project;
  revision->structure = ref.structure;
  revision->number = stmt.ColumnInt(0);
  revision->parent = stmt.ColumnInt(1);
  revision->author = stmt.ColumnText(2);
  revision->time_us = stmt.ColumnInt(3);
  revision->kind = stmt.ColumnText(4);
  revision->message = stmt.ColumnText(5);
  revision->content_sha256 = stmt.ColumnText(6);
  ParseStructureFormat(stmt.ColumnText(7), &revision->format);
  revision->size_bytes = stmt.ColumnInt(8);
  revision->metadata.material_json = stmt.ColumnText(9);
  revision->metadata.colour = {static_cast<int>(stmt.ColumnInt(10)),
                               static_cast<int>(stmt.ColumnInt(11)),
                               static_cast<int>(stmt.ColumnInt(12))};
  revision->metadata.group_path = stmt.ColumnText(13);
}

}  // namespace

Status AtlasStore::Open(const std::filesystem::path& data_dir, std::unique_ptr<AtlasStore>* out,
                        MicrosClock clock) {
  std::error_code ec;
  std::filesystem::create_directories(data_dir, ec);
  if (ec) return Status::Io("cannot create " + data_dir.string() + ": " + ec.message());
  std::unique_ptr<Database> db;
  PBA_RETURN_IF_ERROR(Database::Open(data_dir / "pba.db", &db));
  PBA_RETURN_IF_ERROR(ApplyMigrations(*db));
  std::unique_ptr<BlobStore> blobs;
  PBA_RETURN_IF_ERROR(BlobStore::Open(data_dir / "blobs", &blobs));
  if (!clock) clock = SystemMicros;
  out->reset(new AtlasStore(std::move(db), std::move(blobs), std::move(clock)));
  return Status::Ok();
}

// --- helpers (called with mutex_ held) ----------------------------------

Status AtlasStore::Audit(std::optional<int64_t> user, std::optional<int64_t> project,
                         const std::string& action, const std::string& target,
                         std::optional<int64_t> revision, const std::string& detail) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "INSERT INTO audit_log (time_us, user, project, action, target, revision, detail) "
      "VALUES (?, ?, ?, ?, ?, ?, ?)",
      &stmt));
  return stmt.Bind(1, clock_())
      .Bind(2, user)
      .Bind(3, project)
      .Bind(4, action)
      .Bind(5, target)
      .Bind(6, revision)
      .Bind(7, detail)
      .Run();
}

Status AtlasStore::ActingUser(const std::string& name, int64_t* id) {
  PBA_RETURN_IF_ERROR(CheckName("user", name));
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id, disabled FROM users WHERE name = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, name).Step(&row));
  if (!row) return Status::Unauthenticated("unknown user " + Quoted(name));
  if (stmt.ColumnInt(1) != 0) {
    return Status::Unauthenticated("user " + Quoted(name) + " is disabled");
  }
  *id = stmt.ColumnInt(0);
  return Status::Ok();
}

Status AtlasStore::Enter(const std::string& user, const std::string& project, Role minimum,
                         Caller* caller) {
  PBA_RETURN_IF_ERROR(CheckName("project", project));
  PBA_RETURN_IF_ERROR(ActingUser(user, &caller->user));
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id FROM projects WHERE name = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project).Step(&row));
  if (!row) return Status::NotFound("project " + Quoted(project) + " does not exist");
  caller->project = stmt.ColumnInt(0);
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT role FROM members WHERE project = ? AND user = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, caller->project).Bind(2, caller->user).Step(&row));
  if (!row) {
    return Status::PermissionDenied("user " + Quoted(user) + " is not a member of project " +
                                    Quoted(project));
  }
  ParseRole(stmt.ColumnText(0), &caller->role);
  if (caller->role < minimum) {
    return Status::PermissionDenied("user " + Quoted(user) + " is " + RoleName(caller->role) +
                                    " in project " + Quoted(project) + "; this needs " +
                                    RoleName(minimum));
  }
  return Status::Ok();
}

Status AtlasStore::EnterStructure(const std::string& user, const StructureRef& ref, Role minimum,
                                  Caller* caller, StructureRow* structure) {
  PBA_RETURN_IF_ERROR(Enter(user, ref.project, minimum, caller));
  return FindStructure(*caller, ref, structure);
}

Status AtlasStore::CheckWrite(const Caller& caller, const StructureRef& ref,
                              const StructureRow& structure, const std::string& lock_id,
                              int64_t base_revision) {
  PBA_RETURN_IF_ERROR(CheckLockForWrite(caller, ref, structure.id, lock_id));
  if (base_revision != structure.head_number) {
    return Status::Aborted("base revision " + std::to_string(base_revision) + " of " +
                           Describe(ref) + " is not the head: the head is revision " +
                           std::to_string(structure.head_number) + "; rebase on it");
  }
  return Status::Ok();
}

Status AtlasStore::FindStructure(const Caller& caller, const StructureRef& ref,
                                 StructureRow* structure) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT s.id, s.head_revision, r.number, s.metadata_etag FROM structures s "
                   "JOIN structure_revisions r ON r.id = s.head_revision "
                   "WHERE s.project = ? AND s.name = ?",
                   &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, ref.structure).Step(&row));
  if (!row) return Status::NotFound(Describe(ref) + " does not exist");
  structure->id = stmt.ColumnInt(0);
  structure->head_id = stmt.ColumnInt(1);
  structure->head_number = stmt.ColumnInt(2);
  structure->etag = stmt.ColumnText(3);
  return Status::Ok();
}

Status AtlasStore::ReadRevision(const StructureRef& ref, int64_t structure, int64_t number,
                                Revision* revision, bool* found) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(std::string("SELECT ") + kRevisionColumns + kRevisionFrom +
                                       "WHERE r.structure = ? AND r.number = ?",
                                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, structure).Bind(2, number).Step(found));
  if (*found) ReadRevisionRow(stmt, ref, revision);
  return Status::Ok();
}

Status AtlasStore::AppendRevision(const Caller& caller, const StructureRef& ref,
                                  const StructureRow& structure, const std::string& kind,
                                  const std::string& action, const std::string& message,
                                  const Content& content, bool metadata_changed, Revision* revision,
                                  const std::string& request_id) {
  const int64_t number = structure.head_number + 1;
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "INSERT INTO structure_revisions (structure, number, parent, author, time_us, kind, "
      "message, content_sha256, geometry_format, size_bytes, material_json, colour_r, colour_g, "
      "colour_b, group_path, request_id) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
      "RETURNING id",
      &stmt));
  stmt.Bind(1, structure.id).Bind(2, number);
  if (structure.head_id == 0) {
    stmt.BindNull(3);
  } else {
    stmt.Bind(3, structure.head_id);
  }
  stmt.Bind(4, caller.user).Bind(5, clock_()).Bind(6, kind).Bind(7, message);
  stmt.Bind(8, content.sha256).Bind(9, StructureFormatName(content.format));
  stmt.Bind(10, content.size_bytes).Bind(11, content.metadata.material_json);
  stmt.Bind(12, int64_t{content.metadata.colour.r})
      .Bind(13, int64_t{content.metadata.colour.g})
      .Bind(14, int64_t{content.metadata.colour.b})
      .Bind(15, content.metadata.group_path);
  if (request_id.empty()) {
    stmt.BindNull(16);
  } else {
    stmt.Bind(16, request_id);
  }
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Step(&row));
  if (!row) return Status::Internal("INSERT ... RETURNING gave no row");
  const int64_t id = stmt.ColumnInt(0);
  stmt = Statement();

  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE structures SET head_revision = ?, "
                   "metadata_etag = CASE WHEN ? THEN ? ELSE metadata_etag END WHERE id = ?",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id)
                          .Bind(2, int64_t{metadata_changed ? 1 : 0})
                          .Bind(3, MetadataEtag(number))
                          .Bind(4, structure.id)
                          .Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(
      caller.user, caller.project, action, StructureTarget(ref), id,
      "revision " + std::to_string(number) + " (" + StructureFormatName(content.format) + ", " +
          std::to_string(content.size_bytes) + " bytes, " + content.sha256.substr(0, 12) + ")"));
  bool found = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, number, revision, &found));
  if (!found) return Status::Internal("the revision just written cannot be read back");
  return Status::Ok();
}

// --- users and rights ----------------------------------------------------

Status AtlasStore::CreateUser(const std::string& name, std::string* token, bool server_admin) {
  PBA_RETURN_IF_ERROR(CheckName("user", name));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT 1 FROM users WHERE name = ?", &stmt));
  bool taken = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, name).Step(&taken));
  if (taken) return Status::AlreadyExists("user " + Quoted(name) + " already exists");
  std::string secret;
  std::string hash;
  PBA_RETURN_IF_ERROR(RandomHex(kTokenBytes, &secret));
  hash = Sha256Hex(secret);
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO users (name, token_sha256, created_us, server_admin) "
                   "VALUES (?, ?, ?, ?)",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, name)
                          .Bind(2, hash)
                          .Bind(3, clock_())
                          .Bind(4, int64_t{server_admin ? 1 : 0})
                          .Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(std::nullopt, std::nullopt, "user.create", "users/" + name,
                            std::nullopt, server_admin ? "server admin" : ""));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  *token = std::move(secret);
  return Status::Ok();
}

Status AtlasStore::Authenticate(const std::string& token, std::string* user, bool* server_admin) {
  // Tokens have the shape of a SHA-256 hex string (32 random bytes in hex).
  if (!IsSha256Hex(token)) return Status::Unauthenticated("malformed access token");
  const std::string hash = Sha256Hex(token);
  std::lock_guard lock(mutex_);
  // Read on every call, never cached: a user disabled offline (pba-server
  // admin disable-user) is refused from the next call on.
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT name, disabled, server_admin FROM users WHERE token_sha256 = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, hash).Step(&row));
  if (!row) return Status::Unauthenticated("unknown access token");
  if (stmt.ColumnInt(1) != 0) {
    return Status::Unauthenticated("user " + Quoted(stmt.ColumnText(0)) + " is disabled");
  }
  *user = stmt.ColumnText(0);
  if (server_admin != nullptr) *server_admin = stmt.ColumnInt(2) != 0;
  return Status::Ok();
}

Status AtlasStore::CountUsers(int64_t* count) {
  std::lock_guard lock(mutex_);
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT COUNT(*) FROM users", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Step(&row));
  *count = stmt.ColumnInt(0);
  return Status::Ok();
}

Status AtlasStore::SetRole(const std::string& admin, const std::string& project,
                           const std::string& member, Role role) {
  PBA_RETURN_IF_ERROR(CheckName("member", member));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(admin, project, Role::kAdmin, &caller));
  int64_t member_id = 0;
  std::string old_role;
  PBA_RETURN_IF_ERROR(FindMember(caller.project, member, &member_id, &old_role));
  if (old_role.empty()) old_role = "(none)";
  if (old_role == "admin" && role != Role::kAdmin) {
    int64_t admins = 0;
    PBA_RETURN_IF_ERROR(CountAdmins(caller.project, &admins));
    if (admins <= 1) {
      return Status::FailedPrecondition(Quoted(member) + " is the last admin of project " +
                                        Quoted(project) + "; make another member admin first");
    }
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO members (project, user, role) VALUES (?, ?, ?) "
                   "ON CONFLICT (project, user) DO UPDATE SET role = excluded.role",
                   &stmt));
  PBA_RETURN_IF_ERROR(
      stmt.Bind(1, caller.project).Bind(2, member_id).Bind(3, RoleName(role)).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, "member.set_role",
                            ProjectTarget(project) + "/members/" + member, std::nullopt,
                            member + ": " + old_role + " -> " + RoleName(role)));
  return transaction.Commit();
}

Status AtlasStore::RoleOf(const std::string& project, const std::string& user, Role* role,
                          bool* is_member) {
  PBA_RETURN_IF_ERROR(CheckName("project", project));
  PBA_RETURN_IF_ERROR(CheckName("user", user));
  std::lock_guard lock(mutex_);
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT (SELECT id FROM projects WHERE name = ?), (SELECT id FROM users WHERE name = ?)",
      &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project).Bind(2, user).Step(&row));
  if (stmt.ColumnIsNull(0)) {
    return Status::NotFound("project " + Quoted(project) + " does not exist");
  }
  if (stmt.ColumnIsNull(1)) return Status::NotFound("user " + Quoted(user) + " does not exist");
  const int64_t project_id = stmt.ColumnInt(0);
  const int64_t user_id = stmt.ColumnInt(1);
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT role FROM members WHERE project = ? AND user = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project_id).Bind(2, user_id).Step(is_member));
  if (*is_member) ParseRole(stmt.ColumnText(0), role);
  return Status::Ok();
}

Status AtlasStore::ListProjects(const std::string& user, int page_size,
                                const std::string& page_token, std::vector<ProjectInfo>* projects,
                                std::string* next_page_token) {
  PBA_RETURN_IF_ERROR(NormalisePageSize(page_size, &page_size));
  projects->clear();
  // Copied first: a caller may pass the same string as token in and out.
  const std::string token = page_token;
  next_page_token->clear();
  std::lock_guard lock(mutex_);
  int64_t user_id = 0;
  PBA_RETURN_IF_ERROR(ActingUser(user, &user_id));
  int64_t after = 0;
  if (!token.empty()) {
    PBA_RETURN_IF_ERROR(DecodePageToken(token, "projects", user_id, &after));
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT p.id, p.name, p.created_us, u.name, m.role FROM members m "
                   "JOIN projects p ON p.id = m.project JOIN users u ON u.id = p.created_by "
                   "WHERE m.user = ? AND p.id > ? ORDER BY p.id LIMIT ?",
                   &stmt));
  // One row more than asked tells whether another page follows.
  stmt.Bind(1, user_id).Bind(2, after).Bind(3, int64_t{page_size} + 1);
  std::vector<int64_t> ids;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ProjectInfo& project = projects->emplace_back();
    ids.push_back(stmt.ColumnInt(0));
    project.name = stmt.ColumnText(1);
    project.created_us = stmt.ColumnInt(2);
    project.created_by = stmt.ColumnText(3);
    ParseRole(stmt.ColumnText(4), &project.role);
  }
  if (static_cast<int>(projects->size()) > page_size) {
    projects->pop_back();
    *next_page_token = EncodePageToken("projects", user_id, ids[page_size - 1]);
  }
  return Status::Ok();
}

// --- structures (creation: atlas_store_creates.cc) ---------------------

Status AtlasStore::GetStructure(const std::string& user, const StructureRef& ref,
                                StructureInfo* info) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  std::lock_guard lock(mutex_);
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kViewer, &caller, &structure));
  Revision head;
  bool found = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, structure.head_number, &head, &found));
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT created_us FROM structures WHERE id = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, structure.id).Step(&found));
  info->project = ref.project;
  info->name = ref.structure;
  info->head = structure.head_number;
  info->metadata_etag = structure.etag;
  info->metadata = head.metadata;
  info->created_us = stmt.ColumnInt(0);
  stmt = Statement();
  return PublicLock(ref, structure.id, &info->lock);
}

Status AtlasStore::ListStructures(const std::string& user, const std::string& project,
                                  int page_size, const std::string& page_token,
                                  std::vector<StructureInfo>* structures,
                                  std::string* next_page_token) {
  PBA_RETURN_IF_ERROR(NormalisePageSize(page_size, &page_size));
  structures->clear();
  // Copied first: a caller may pass the same string as token in and out.
  const std::string token = page_token;
  next_page_token->clear();
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kViewer, &caller));
  // The token carries the id of the last structure listed; structures are
  // never deleted or renamed, so the id names the same name for good.
  int64_t after_id = 0;
  if (!token.empty()) {
    PBA_RETURN_IF_ERROR(DecodePageToken(token, "structures", caller.project, &after_id));
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT s.id, s.name, r.number, s.metadata_etag, s.created_us, r.material_json, "
      "r.colour_r, r.colour_g, r.colour_b, r.group_path FROM structures s "
      "JOIN structure_revisions r ON r.id = s.head_revision "
      "WHERE s.project = ? AND s.name > COALESCE((SELECT name FROM structures WHERE id = ? AND "
      "project = ?), '') ORDER BY s.name LIMIT ?",
      &stmt));
  stmt.Bind(1, caller.project)
      .Bind(2, after_id)
      .Bind(3, caller.project)
      .Bind(4, int64_t{page_size} + 1);
  std::vector<int64_t> ids;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    StructureInfo& info = structures->emplace_back();
    ids.push_back(stmt.ColumnInt(0));
    info.project = project;
    info.name = stmt.ColumnText(1);
    info.head = stmt.ColumnInt(2);
    info.metadata_etag = stmt.ColumnText(3);
    info.created_us = stmt.ColumnInt(4);
    info.metadata.material_json = stmt.ColumnText(5);
    info.metadata.colour = {static_cast<int>(stmt.ColumnInt(6)),
                            static_cast<int>(stmt.ColumnInt(7)),
                            static_cast<int>(stmt.ColumnInt(8))};
    info.metadata.group_path = stmt.ColumnText(9);
  }
  stmt = Statement();
  if (static_cast<int>(structures->size()) > page_size) {
    structures->pop_back();
    ids.pop_back();
    *next_page_token = EncodePageToken("structures", caller.project, ids.back());
  }
  for (size_t i = 0; i < structures->size(); ++i) {
    StructureInfo& info = (*structures)[i];
    PBA_RETURN_IF_ERROR(PublicLock({project, info.name}, ids[i], &info.lock));
  }
  return Status::Ok();
}

// --- revisions -----------------------------------------------------------

Status AtlasStore::Commit(const std::string& user, const CommitRequest& request, Revision* revision,
                          bool* replayed) {
  if (replayed != nullptr) *replayed = false;
  const StructureRef& ref = request.structure;
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  PBA_RETURN_IF_ERROR(CheckGeometry(request.geometry));
  if (request.material_json) {
    PBA_RETURN_IF_ERROR(CheckMaterialJson("material_json", *request.material_json));
  }
  PBA_RETURN_IF_ERROR(CheckMessage("message", request.message));
  PBA_RETURN_IF_ERROR(atlas_internal::CheckRequestId(request.request_id));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kEditor, &caller, &structure));
  // A retry of a commit that landed: its revision, nothing written.
  bool earlier = false;
  PBA_RETURN_IF_ERROR(
      FindCommitRequest(caller, ref, structure.id, request.request_id, revision, &earlier));
  if (earlier) {
    if (replayed != nullptr) *replayed = true;
    return Status::Ok();
  }
  PBA_RETURN_IF_ERROR(CheckWrite(caller, ref, structure, request.lock_id, request.base_revision));
  Revision head;
  bool found = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, structure.head_number, &head, &found));
  Content content;
  content.metadata = head.metadata;
  bool metadata_changed = false;
  if (request.material_json && *request.material_json != head.metadata.material_json) {
    content.metadata.material_json = *request.material_json;
    metadata_changed = true;
  }
  // The blob before the row that names it.
  PBA_RETURN_IF_ERROR(StoreGeometry(request.geometry, request.geometry_file, &content.sha256));
  content.format = request.format;
  content.size_bytes = static_cast<int64_t>(request.geometry.size());
  PBA_RETURN_IF_ERROR(AppendRevision(caller, ref, structure, "commit", "revision.commit",
                                     request.message, content, metadata_changed, revision,
                                     request.request_id));
  return transaction.Commit();
}

Status AtlasStore::UpdateMetadata(const std::string& user, const StructureRef& ref,
                                  const std::string& etag, const MetadataUpdate& update,
                                  const std::string& message, Revision* revision,
                                  std::string* new_etag) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  if (!update.colour && !update.group_path && !update.material_json) {
    return Status::InvalidArgument("update", "names no field to change");
  }
  if (update.colour) PBA_RETURN_IF_ERROR(CheckColour("colour", *update.colour));
  if (update.group_path) PBA_RETURN_IF_ERROR(CheckGroupPath("group_path", *update.group_path));
  if (update.material_json) {
    PBA_RETURN_IF_ERROR(CheckMaterialJson("material_json", *update.material_json));
  }
  PBA_RETURN_IF_ERROR(CheckMessage("message", message));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kEditor, &caller, &structure));
  if (etag != structure.etag) {
    return Status::Aborted("metadata etag " + Quoted(etag) + " of " + Describe(ref) +
                           " is stale: the current etag is " + Quoted(structure.etag) +
                           "; re-read the metadata and retry");
  }
  Revision head;
  bool found = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, structure.head_number, &head, &found));
  Content content;
  content.sha256 = head.content_sha256;
  content.format = head.format;
  content.size_bytes = head.size_bytes;
  content.metadata = head.metadata;
  if (update.colour) content.metadata.colour = *update.colour;
  if (update.group_path) content.metadata.group_path = *update.group_path;
  if (update.material_json) content.metadata.material_json = *update.material_json;
  if (content.metadata == head.metadata) {
    // Nothing changes, so nothing is recorded: no empty revisions in history.
    *revision = head;
    *new_etag = structure.etag;
    return Status::Ok();
  }
  PBA_RETURN_IF_ERROR(AppendRevision(caller, ref, structure, "metadata", "revision.metadata",
                                     message.empty() ? "metadata" : message, content, true,
                                     revision));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  *new_etag = MetadataEtag(revision->number);
  return Status::Ok();
}

Status AtlasStore::History(const std::string& user, const StructureRef& ref, int page_size,
                           const std::string& page_token, std::vector<Revision>* revisions,
                           std::string* next_page_token) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  PBA_RETURN_IF_ERROR(NormalisePageSize(page_size, &page_size));
  revisions->clear();
  // Copied first: a caller may pass the same string as token in and out.
  const std::string token = page_token;
  next_page_token->clear();
  std::lock_guard lock(mutex_);
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kViewer, &caller, &structure));
  int64_t before = INT64_MAX;
  if (!token.empty()) {
    PBA_RETURN_IF_ERROR(DecodePageToken(token, "history", structure.id, &before));
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(std::string("SELECT ") + kRevisionColumns + kRevisionFrom +
                                       "WHERE r.structure = ? AND r.number < ? "
                                       "ORDER BY r.number DESC LIMIT ?",
                                   &stmt));
  stmt.Bind(1, structure.id).Bind(2, before).Bind(3, int64_t{page_size} + 1);
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ReadRevisionRow(stmt, ref, &revisions->emplace_back());
  }
  if (static_cast<int>(revisions->size()) > page_size) {
    revisions->pop_back();
    *next_page_token = EncodePageToken("history", structure.id, revisions->back().number);
  }
  return Status::Ok();
}

Status AtlasStore::GetRevision(const std::string& user, const StructureRef& ref, int64_t number,
                               Revision* revision, std::string* geometry) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  if (number <= 0) return Status::InvalidArgument("revision", "must be 1 or more");
  std::lock_guard lock(mutex_);
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kViewer, &caller, &structure));
  bool found = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, number, revision, &found));
  if (!found) {
    return Status::NotFound(Describe(ref) + " has no revision " + std::to_string(number) +
                            "; the head is revision " + std::to_string(structure.head_number));
  }
  if (geometry != nullptr) PBA_RETURN_IF_ERROR(blobs_->Get(revision->content_sha256, geometry));
  return Status::Ok();
}

Status AtlasStore::Revert(const std::string& user, const StructureRef& ref,
                          const std::string& lock_id, int64_t base_revision, int64_t to_revision,
                          const std::string& message, Revision* revision) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  if (to_revision <= 0) return Status::InvalidArgument("to_revision", "must be 1 or more");
  PBA_RETURN_IF_ERROR(CheckMessage("message", message));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kEditor, &caller, &structure));
  PBA_RETURN_IF_ERROR(CheckWrite(caller, ref, structure, lock_id, base_revision));
  Revision old;
  bool found = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, to_revision, &old, &found));
  if (!found) {
    return Status::NotFound(Describe(ref) + " has no revision " + std::to_string(to_revision) +
                            "; the head is revision " + std::to_string(structure.head_number));
  }
  Revision head;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, structure.head_number, &head, &found));
  // A row must never name a missing blob, even one copied from history.
  bool has = false;
  PBA_RETURN_IF_ERROR(blobs_->Has(old.content_sha256, &has));
  if (!has) {
    return Status::Io("the geometry blob " + old.content_sha256 + " of revision " +
                      std::to_string(to_revision) + " is missing");
  }
  Content content;
  content.sha256 = old.content_sha256;
  content.format = old.format;
  content.size_bytes = old.size_bytes;
  content.metadata = old.metadata;
  PBA_RETURN_IF_ERROR(AppendRevision(
      caller, ref, structure, "revert", "revision.revert",
      message.empty() ? "revert to revision " + std::to_string(to_revision) : message, content,
      old.metadata != head.metadata, revision));
  return transaction.Commit();
}

// --- maintenance ---------------------------------------------------------

Status AtlasStore::SweepBlobs(BlobSweepReport* report) {
  // Under mutex_: every Put happens under it too, so no blob of an
  // uncommitted revision can be in flight while the references are read.
  std::lock_guard lock(mutex_);
  std::set<std::string> referenced;
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT DISTINCT content_sha256 FROM structure_revisions", &stmt));
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    referenced.insert(stmt.ColumnText(0));
  }
  stmt = Statement();
  return blobs_->Sweep(referenced, report);
}

}  // namespace pba
