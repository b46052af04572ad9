// AtlasStore's snapshots, tags and audit listing.
#include <string>

#include "store/atlas_store.h"
#include "store/atlas_store_internal.h"
#include "store/page_token.h"
#include "store/transaction.h"

namespace pba {
namespace {

using atlas_internal::AllDigits;
using atlas_internal::ProjectTarget;
using atlas_internal::Quoted;

}  // namespace

Status AtlasStore::LoadSnapshot(const std::string& project, int64_t project_id, int64_t id,
                                bool with_members, SnapshotInfo* snapshot, bool* found) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT s.name, u.name, s.created_us FROM snapshots s "
                   "JOIN users u ON u.id = s.author WHERE s.id = ? AND s.project = ?",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, id).Bind(2, project_id).Step(found));
  if (!*found) return Status::Ok();
  *snapshot = SnapshotInfo();
  snapshot->id = id;
  snapshot->project = project;
  snapshot->name = stmt.ColumnText(0);
  snapshot->author = stmt.ColumnText(1);
  snapshot->created_us = stmt.ColumnInt(2);
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT tag FROM snapshot_tags WHERE snapshot = ? ORDER BY tag", &stmt));
  stmt.Bind(1, id);
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    snapshot->tags.push_back(stmt.ColumnText(0));
  }
  if (!with_members) return Status::Ok();
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT st.name, r.number FROM snapshot_members m "
                   "JOIN structures st ON st.id = m.structure "
                   "JOIN structure_revisions r ON r.id = m.revision WHERE m.snapshot = ?",
                   &stmt));
  stmt.Bind(1, id);
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    snapshot->revisions[stmt.ColumnText(0)] = stmt.ColumnInt(1);
  }
  return Status::Ok();
}

Status AtlasStore::CreateSnapshot(const std::string& user, const std::string& project,
                                  const std::string& name, SnapshotInfo* snapshot,
                                  const std::string& request_id, bool* replayed) {
  if (replayed != nullptr) *replayed = false;
  if (!name.empty()) PBA_RETURN_IF_ERROR(CheckName("name", name));
  PBA_RETURN_IF_ERROR(atlas_internal::CheckRequestId(request_id));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kEditor, &caller));
  // The name as asked for (empty included): a retry that leaves the name to
  // the server must match, though the time it would be named by has moved.
  const std::string fingerprint = atlas_internal::CreateFingerprint({project, name});
  CreateRequestRow earlier;
  bool found = false;
  PBA_RETURN_IF_ERROR(
      FindCreateRequest(caller.user, request_id, "snapshot", fingerprint, &earlier, &found));
  if (found) {
    if (replayed != nullptr) *replayed = true;
    PBA_RETURN_IF_ERROR(
        LoadSnapshot(project, caller.project, earlier.snapshot, true, snapshot, &found));
    if (!found) return Status::Internal("the snapshot a create made cannot be read back");
    return Status::Ok();
  }
  // Unnamed: named by its time, which is how people tell snapshots apart.
  const std::string named =
      name.empty() ? "snapshot " + atlas_internal::FormatSnapshotTime(clock_()) : name;
  int64_t id = 0;
  PBA_RETURN_IF_ERROR(PinSnapshot(caller, project, named, "", &id));
  PBA_RETURN_IF_ERROR(
      RecordCreateRequest(caller.user, request_id, "snapshot", fingerprint, caller.project, 0, id));
  PBA_RETURN_IF_ERROR(LoadSnapshot(project, caller.project, id, true, snapshot, &found));
  return transaction.Commit();
}

Status AtlasStore::PinSnapshot(const Caller& caller, const std::string& project,
                               const std::string& name, const std::string& import_job,
                               int64_t* id) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO snapshots (project, name, created_us, author, import_job) "
                   "VALUES (?, ?, ?, ?, ?) RETURNING id",
                   &stmt));
  stmt.Bind(1, caller.project).Bind(2, name).Bind(3, clock_()).Bind(4, caller.user);
  if (import_job.empty()) {
    stmt.BindNull(5);
  } else {
    stmt.Bind(5, import_job);
  }
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Step(&row));
  *id = stmt.ColumnInt(0);
  stmt = Statement();
  // One statement inside the transaction: every head is read at the same instant.
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO snapshot_members (snapshot, structure, revision) "
                   "SELECT ?, id, head_revision FROM structures WHERE project = ?",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, *id).Bind(2, caller.project).Run());
  const int pinned = db_->Changes();
  stmt = Statement();
  return Audit(caller.user, caller.project, "snapshot.create",
               ProjectTarget(project) + "/snapshots/" + std::to_string(*id), std::nullopt,
               name + ": " + std::to_string(pinned) + " structures" +
                   (import_job.empty() ? "" : ", made by import job " + import_job));
}

Status AtlasStore::Tag(const std::string& user, const std::string& project, int64_t snapshot_id,
                       const std::string& tag) {
  PBA_RETURN_IF_ERROR(CheckName("tag", tag));
  if (AllDigits(tag)) {
    return Status::InvalidArgument("tag", "must not be all digits: it would read as a snapshot id");
  }
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kEditor, &caller));
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT 1 FROM snapshots WHERE id = ? AND project = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, snapshot_id).Bind(2, caller.project).Step(&row));
  if (!row) {
    return Status::NotFound("project " + Quoted(project) + " has no snapshot " +
                            std::to_string(snapshot_id));
  }
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT snapshot FROM snapshot_tags WHERE project = ? AND tag = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, tag).Step(&row));
  if (row) {
    return Status::AlreadyExists("tag " + Quoted(tag) + " already names snapshot " +
                                 std::to_string(stmt.ColumnInt(0)) + " of project " +
                                 Quoted(project));
  }
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO snapshot_tags (project, tag, snapshot) VALUES (?, ?, ?)", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, tag).Bind(3, snapshot_id).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, "snapshot.tag",
                            ProjectTarget(project) + "/snapshots/" + std::to_string(snapshot_id),
                            std::nullopt, tag));
  return transaction.Commit();
}

Status AtlasStore::ListSnapshots(const std::string& user, const std::string& project, int page_size,
                                 const std::string& page_token,
                                 std::vector<SnapshotInfo>* snapshots,
                                 std::string* next_page_token) {
  PBA_RETURN_IF_ERROR(NormalisePageSize(page_size, &page_size));
  snapshots->clear();
  // Copied first: a caller may pass the same string as token in and out.
  const std::string token = page_token;
  next_page_token->clear();
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kViewer, &caller));
  int64_t before = INT64_MAX;
  if (!token.empty()) {
    PBA_RETURN_IF_ERROR(DecodePageToken(token, "snapshots", caller.project, &before));
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT id FROM snapshots WHERE project = ? AND id < ? ORDER BY id DESC LIMIT ?", &stmt));
  stmt.Bind(1, caller.project).Bind(2, before).Bind(3, int64_t{page_size} + 1);
  std::vector<int64_t> ids;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ids.push_back(stmt.ColumnInt(0));
  }
  stmt = Statement();
  if (static_cast<int>(ids.size()) > page_size) {
    ids.pop_back();
    *next_page_token = EncodePageToken("snapshots", caller.project, ids.back());
  }
  for (int64_t id : ids) {
    bool found = false;
    PBA_RETURN_IF_ERROR(
        LoadSnapshot(project, caller.project, id, false, &snapshots->emplace_back(), &found));
  }
  return Status::Ok();
}

Status AtlasStore::SnapshotNamed(int64_t project_id, const std::string& project,
                                 const std::string& name, int64_t* id) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT id FROM snapshots WHERE project = ? AND name = ? ORDER BY id LIMIT 6", &stmt));
  stmt.Bind(1, project_id).Bind(2, name);
  std::vector<int64_t> ids;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    ids.push_back(stmt.ColumnInt(0));
  }
  if (ids.size() == 1) *id = ids[0];
  if (ids.size() > 1) {
    std::string list;
    for (std::size_t i = 0; i < ids.size() && i < 5; ++i) {
      list += (i > 0 ? ", " : "") + std::to_string(ids[i]);
    }
    return Status::InvalidArgument("snapshot", "several snapshots of project " + Quoted(project) +
                                                   " are named " + Quoted(name) + " (" + list +
                                                   (ids.size() > 5 ? ", ..." : "") +
                                                   "): name one by its id or a tag");
  }
  return Status::Ok();
}

Status AtlasStore::ResolveSnapshot(const std::string& user, const std::string& project,
                                   const std::string& tag_or_id, SnapshotInfo* snapshot) {
  PBA_RETURN_IF_ERROR(CheckName("snapshot", tag_or_id));
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kViewer, &caller));
  int64_t id = 0;
  if (AllDigits(tag_or_id)) {
    // Tags are never all digits, so this cannot shadow a tag.
    if (tag_or_id.size() <= 18) id = std::stoll(tag_or_id);
  } else {
    Statement stmt;
    PBA_RETURN_IF_ERROR(
        db_->Prepare("SELECT snapshot FROM snapshot_tags WHERE project = ? AND tag = ?", &stmt));
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, tag_or_id).Step(&row));
    if (row) id = stmt.ColumnInt(0);
    stmt = Statement();
    // Not a tag: the snapshot of that name, if one alone has it.
    if (id == 0) PBA_RETURN_IF_ERROR(SnapshotNamed(caller.project, project, tag_or_id, &id));
  }
  bool found = false;
  if (id > 0) {
    PBA_RETURN_IF_ERROR(LoadSnapshot(project, caller.project, id, true, snapshot, &found));
  }
  if (!found) {
    return Status::NotFound("project " + Quoted(project) +
                            " has no snapshot tagged, numbered or named " + Quoted(tag_or_id));
  }
  return Status::Ok();
}

// --- audit ---------------------------------------------------------------

Status AtlasStore::ListAudit(const std::string& user, const std::string& project, int page_size,
                             const std::string& page_token, std::vector<AuditEntry>* entries,
                             std::string* next_page_token) {
  PBA_RETURN_IF_ERROR(NormalisePageSize(page_size, &page_size));
  entries->clear();
  // Copied first: a caller may pass the same string as token in and out.
  const std::string token = page_token;
  next_page_token->clear();
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kViewer, &caller));
  int64_t before = INT64_MAX;
  if (!token.empty()) {
    PBA_RETURN_IF_ERROR(DecodePageToken(token, "audit", caller.project, &before));
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT a.seq, a.time_us, COALESCE(u.name, ''), a.action, a.target, COALESCE(r.number, 0), "
      "a.detail FROM audit_log a LEFT JOIN users u ON u.id = a.user "
      "LEFT JOIN structure_revisions r ON r.id = a.revision "
      "WHERE a.project = ? AND a.seq < ? ORDER BY a.seq DESC LIMIT ?",
      &stmt));
  stmt.Bind(1, caller.project).Bind(2, before).Bind(3, int64_t{page_size} + 1);
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    AuditEntry& entry = entries->emplace_back();
    entry.seq = stmt.ColumnInt(0);
    entry.time_us = stmt.ColumnInt(1);
    entry.user = stmt.ColumnText(2);
    entry.action = stmt.ColumnText(3);
    entry.target = stmt.ColumnText(4);
    entry.revision = stmt.ColumnInt(5);
    entry.detail = stmt.ColumnText(6);
  }
  if (static_cast<int>(entries->size()) > page_size) {
    entries->pop_back();
    *next_page_token = EncodePageToken("audit", caller.project, entries->back().seq);
  }
  return Status::Ok();
}

}  // namespace pba
