// AtlasStore's creates of projects and structures, and the request ids that
// make every create idempotent (atlas_store.h, "Idempotent creates").
#include <string>

#include "store/atlas_store.h"
#include "store/atlas_store_internal.h"
#include "store/transaction.h"

namespace pba {
namespace {

using atlas_internal::CheckGeometry;
using atlas_internal::CheckRequestId;
using atlas_internal::CreateFingerprint;
using atlas_internal::Describe;
using atlas_internal::ProjectTarget;
using atlas_internal::Quoted;

std::string StructureFingerprint(const NewStructure& request) {
  const StructureMetadata& m = request.metadata;
  return CreateFingerprint({request.structure.project, request.structure.structure,
                            StructureFormatName(request.format), std::to_string(m.colour.r),
                            std::to_string(m.colour.g), std::to_string(m.colour.b), m.group_path,
                            m.material_json, request.message});
}

}  // namespace

// --- request ids (called with mutex_ held, inside the create's transaction) --

Status AtlasStore::FindCreateRequest(int64_t user, const std::string& request_id,
                                     const std::string& kind, const std::string& fingerprint,
                                     CreateRequestRow* row, bool* found) {
  *found = false;
  if (request_id.empty()) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT kind, arguments_sha256, project, COALESCE(structure, 0), COALESCE(snapshot, 0) "
      "FROM create_requests WHERE user = ? AND request_id = ?",
      &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, user).Bind(2, request_id).Step(found));
  if (!*found) return Status::Ok();
  row->kind = stmt.ColumnText(0);
  row->arguments_sha256 = stmt.ColumnText(1);
  row->project = stmt.ColumnInt(2);
  row->structure = stmt.ColumnInt(3);
  row->snapshot = stmt.ColumnInt(4);
  if (row->kind != kind) {
    return Status::InvalidArgument("request_id", "you already used it to create a " + row->kind +
                                                     ", not a " + kind +
                                                     "; a new request needs a new id");
  }
  if (row->arguments_sha256 != fingerprint) {
    return Status::InvalidArgument("request_id", "you already used it to create a " + kind +
                                                     " with other arguments; a new request "
                                                     "needs a new id");
  }
  return Status::Ok();
}

Status AtlasStore::RecordCreateRequest(int64_t user, const std::string& request_id,
                                       const std::string& kind, const std::string& fingerprint,
                                       int64_t project, int64_t structure, int64_t snapshot) {
  if (request_id.empty()) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "INSERT INTO create_requests (user, request_id, kind, arguments_sha256, project, "
      "structure, snapshot, time_us) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
      &stmt));
  const auto id_or_null = [](int64_t id) {
    return id == 0 ? std::nullopt : std::optional<int64_t>(id);
  };
  return stmt.Bind(1, user)
      .Bind(2, request_id)
      .Bind(3, kind)
      .Bind(4, fingerprint)
      .Bind(5, project)
      .Bind(6, id_or_null(structure))
      .Bind(7, id_or_null(snapshot))
      .Bind(8, clock_())
      .Run();
}

Status AtlasStore::StoreGeometry(std::string_view geometry, const MappedFile* file,
                                 std::string* sha256) {
  if (file == nullptr) return blobs_->Put(geometry, sha256);
  if (file->bytes().data() != geometry.data() || file->size() != geometry.size()) {
    return Status::Internal("the geometry is not the geometry file's content");
  }
  return blobs_->PutFile(*file, sha256);
}

// --- projects --------------------------------------------------------------

Status AtlasStore::CreateProject(const std::string& user, const std::string& project,
                                 const std::string& request_id, bool* replayed) {
  if (replayed != nullptr) *replayed = false;
  PBA_RETURN_IF_ERROR(CheckName("project", project));
  PBA_RETURN_IF_ERROR(CheckRequestId(request_id));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  int64_t user_id = 0;
  PBA_RETURN_IF_ERROR(ActingUser(user, &user_id));
  const std::string fingerprint = CreateFingerprint({project});
  CreateRequestRow earlier;
  bool found = false;
  PBA_RETURN_IF_ERROR(
      FindCreateRequest(user_id, request_id, "project", fingerprint, &earlier, &found));
  if (found) {
    if (replayed != nullptr) *replayed = true;
    return Status::Ok();
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT 1 FROM projects WHERE name = ?", &stmt));
  bool taken = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project).Step(&taken));
  if (taken) return Status::AlreadyExists("project " + Quoted(project) + " already exists");
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "INSERT INTO projects (name, created_us, created_by) VALUES (?, ?, ?) RETURNING id", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project).Bind(2, clock_()).Bind(3, user_id).Step(&row));
  const int64_t project_id = stmt.ColumnInt(0);
  stmt = Statement();
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO members (project, user, role) VALUES (?, ?, 'admin')", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project_id).Bind(2, user_id).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(user_id, project_id, "project.create", ProjectTarget(project),
                            std::nullopt, user + " is admin"));
  PBA_RETURN_IF_ERROR(
      RecordCreateRequest(user_id, request_id, "project", fingerprint, project_id, 0, 0));
  return transaction.Commit();
}

// --- structures ------------------------------------------------------------

Status AtlasStore::CreateStructure(const std::string& user, const StructureRef& ref,
                                   const StructureMetadata& metadata, StructureFormat format,
                                   std::string_view geometry, Revision* revision,
                                   const std::string& message) {
  NewStructure request;
  request.structure = ref;
  request.metadata = metadata;
  request.format = format;
  request.geometry = geometry;
  request.message = message;
  return CreateStructure(user, request, revision);
}

Status AtlasStore::FindCreatedStructure(const std::string& user, const NewStructure& request,
                                        Revision* revision, bool* found) {
  *found = false;
  const StructureRef& ref = request.structure;
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  PBA_RETURN_IF_ERROR(CheckRequestId(request.request_id));
  if (request.request_id.empty()) return Status::Ok();
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, ref.project, Role::kEditor, &caller));
  CreateRequestRow earlier;
  PBA_RETURN_IF_ERROR(FindCreateRequest(caller.user, request.request_id, "structure",
                                        StructureFingerprint(request), &earlier, found));
  if (!*found) return Status::Ok();
  bool read = false;
  PBA_RETURN_IF_ERROR(ReadRevision(ref, earlier.structure, 1, revision, &read));
  if (!read) return Status::Internal("the revision a create made cannot be read back");
  return Status::Ok();
}

Status AtlasStore::CreateStructure(const std::string& user, const NewStructure& request,
                                   Revision* revision, bool* replayed) {
  if (replayed != nullptr) *replayed = false;
  const StructureRef& ref = request.structure;
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  PBA_RETURN_IF_ERROR(CheckMessage("message", request.message));
  PBA_RETURN_IF_ERROR(CheckMetadata(request.metadata));
  PBA_RETURN_IF_ERROR(CheckGeometry(request.geometry));
  PBA_RETURN_IF_ERROR(CheckRequestId(request.request_id));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, ref.project, Role::kEditor, &caller));
  const std::string fingerprint = StructureFingerprint(request);
  CreateRequestRow earlier;
  bool found = false;
  PBA_RETURN_IF_ERROR(FindCreateRequest(caller.user, request.request_id, "structure", fingerprint,
                                        &earlier, &found));
  if (found) {
    // A retry of a create that landed: its revision 1, nothing written.
    if (replayed != nullptr) *replayed = true;
    bool read = false;
    PBA_RETURN_IF_ERROR(ReadRevision(ref, earlier.structure, 1, revision, &read));
    if (!read) return Status::Internal("the revision a create made cannot be read back");
    return Status::Ok();
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT 1 FROM structures WHERE project = ? AND name = ?", &stmt));
  bool taken = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, ref.structure).Step(&taken));
  if (taken) return Status::AlreadyExists(Describe(ref) + " already exists");

  // The blob before any row that names it.
  Content content;
  PBA_RETURN_IF_ERROR(StoreGeometry(request.geometry, request.geometry_file, &content.sha256));
  content.format = request.format;
  content.size_bytes = static_cast<int64_t>(request.geometry.size());
  content.metadata = request.metadata;

  stmt = Statement();
  StructureRow structure;
  PBA_RETURN_IF_ERROR(InsertStructure(caller, ref.structure, &structure.id));
  PBA_RETURN_IF_ERROR(AppendRevision(caller, ref, structure, "create", "structure.create",
                                     request.message.empty() ? "created" : request.message, content,
                                     true, revision));
  PBA_RETURN_IF_ERROR(RecordCreateRequest(caller.user, request.request_id, "structure", fingerprint,
                                          caller.project, structure.id, 0));
  return transaction.Commit();
}

Status AtlasStore::InsertStructure(const Caller& caller, const std::string& name, int64_t* id) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "INSERT INTO structures (project, name, head_revision, metadata_etag, created_us, "
      "created_by) VALUES (?, ?, NULL, '', ?, ?) RETURNING id",
      &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(
      stmt.Bind(1, caller.project).Bind(2, name).Bind(3, clock_()).Bind(4, caller.user).Step(&row));
  *id = stmt.ColumnInt(0);
  return Status::Ok();
}

}  // namespace pba
