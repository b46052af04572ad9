// AtlasStore: an atlas import's structures and snapshot, the files of a
// snapshot for a job run against it, and the locked neighbours a commit is
// checked against.
#include "store/atlas_store.h"
#include "store/atlas_store_internal.h"
#include "store/mapped_file.h"
#include "store/transaction.h"

namespace pba {
using namespace atlas_internal;

Status AtlasStore::SnapshotFiles(const std::string& user, const std::string& project,
                                 int64_t snapshot_id, std::vector<SnapshotFile>* files) {
  files->clear();
  SnapshotInfo snapshot;
  PBA_RETURN_IF_ERROR(ResolveSnapshot(user, project, std::to_string(snapshot_id), &snapshot));
  std::lock_guard lock(mutex_);
  for (const auto& [name, number] : snapshot.revisions) {
    const StructureRef ref{project, name};
    Caller caller;
    StructureRow structure;
    PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kViewer, &caller, &structure));
    SnapshotFile file;
    bool found = false;
    PBA_RETURN_IF_ERROR(ReadRevision(ref, structure.id, number, &file.revision, &found));
    if (!found) {
      return Status::Internal(Describe(ref) + " has no revision " + std::to_string(number) +
                              " although snapshot " + std::to_string(snapshot_id) + " pins it");
    }
    // Read through once: a damaged blob is an error here, not a wrong atlas.
    std::string bytes;
    PBA_RETURN_IF_ERROR(blobs_->Get(file.revision.content_sha256, &bytes));
    file.blob = blobs_->PathOf(file.revision.content_sha256);
    files->push_back(std::move(file));
  }
  return Status::Ok();
}

Status AtlasStore::LockedNeighbours(const std::string& user, const std::string& project,
                                    const std::string& except,
                                    std::vector<LockedNeighbour>* neighbours) {
  neighbours->clear();
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kViewer, &caller));
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT s.id, s.name, h.number, u.name FROM locks l JOIN structures s ON s.id = l.structure "
      "JOIN structure_revisions h ON h.id = s.head_revision JOIN users u ON u.id = l.owner "
      "WHERE s.project = ? AND s.name <> ? AND l.owner <> ? AND l.lease_expiry_us > ? "
      "ORDER BY s.name",
      &stmt));
  stmt.Bind(1, caller.project).Bind(2, except).Bind(3, caller.user).Bind(4, clock_());
  struct Row {
    int64_t id, number;
    std::string name, holder;
  };
  std::vector<Row> rows;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    rows.push_back({stmt.ColumnInt(0), stmt.ColumnInt(2), stmt.ColumnText(1), stmt.ColumnText(3)});
  }
  stmt = Statement();
  for (const Row& r : rows) {
    LockedNeighbour neighbour;
    bool found = false;
    PBA_RETURN_IF_ERROR(ReadRevision({project, r.name}, r.id, r.number, &neighbour.head, &found));
    if (!found) continue;
    neighbour.blob = blobs_->PathOf(neighbour.head.content_sha256);
    neighbour.holder = r.holder;
    neighbours->push_back(std::move(neighbour));
  }
  return Status::Ok();
}

Status AtlasStore::RevisionFile(const std::string& user, const StructureRef& ref, int64_t number,
                                SnapshotFile* file) {
  PBA_RETURN_IF_ERROR(GetRevision(user, ref, number, &file->revision, nullptr));
  file->blob = blobs_->PathOf(file->revision.content_sha256);
  return Status::Ok();
}

Status AtlasStore::Heads(const std::string& user, const std::string& project,
                         std::vector<SnapshotFile>* heads) {
  heads->clear();
  std::lock_guard lock(mutex_);
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kViewer, &caller));
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT s.id, s.name, h.number FROM structures s "
                   "JOIN structure_revisions h ON h.id = s.head_revision "
                   "WHERE s.project = ? ORDER BY s.name",
                   &stmt));
  stmt.Bind(1, caller.project);
  struct Row {
    int64_t id, number;
    std::string name;
  };
  std::vector<Row> rows;
  while (true) {
    bool row = false;
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    rows.push_back({stmt.ColumnInt(0), stmt.ColumnInt(2), stmt.ColumnText(1)});
  }
  stmt = Statement();
  for (const Row& r : rows) {
    SnapshotFile head;
    bool found = false;
    PBA_RETURN_IF_ERROR(ReadRevision({project, r.name}, r.id, r.number, &head.revision, &found));
    if (!found) return Status::Internal("the head of '" + r.name + "' is missing");
    head.blob = blobs_->PathOf(head.revision.content_sha256);
    heads->push_back(std::move(head));
  }
  return Status::Ok();
}

Status AtlasStore::Import(const std::string& user, const std::string& project,
                          const std::string& job_id,
                          const std::vector<ImportedStructure>& structures,
                          const std::string& snapshot_name, const std::string& message,
                          SnapshotInfo* snapshot, bool* replayed) {
  *replayed = false;
  if (job_id.empty()) return Status::InvalidArgument("job", "required");
  if (structures.empty()) return Status::InvalidArgument("structures", "the import has none");
  PBA_RETURN_IF_ERROR(CheckName("snapshot_name", snapshot_name));
  PBA_RETURN_IF_ERROR(CheckMessage("message", message));
  for (const ImportedStructure& s : structures) {
    PBA_RETURN_IF_ERROR(CheckName("structure", s.name));
    PBA_RETURN_IF_ERROR(CheckMetadata(s.metadata));
  }
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, project, Role::kEditor, &caller));
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id FROM snapshots WHERE import_job = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, job_id).Step(&row));
  if (row) {
    const int64_t id = stmt.ColumnInt(0);
    stmt = Statement();
    *replayed = true;
    bool found = false;
    return LoadSnapshot(project, caller.project, id, true, snapshot, &found);
  }
  std::string taken;
  int taken_count = 0;
  for (const ImportedStructure& s : structures) {
    PBA_RETURN_IF_ERROR(
        db_->Prepare("SELECT 1 FROM structures WHERE project = ? AND name = ?", &stmt));
    bool exists = false;
    PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, s.name).Step(&exists));
    if (exists && ++taken_count <= 10) taken += (taken.empty() ? "" : ", ") + Quoted(s.name);
  }
  stmt = Statement();
  if (taken_count > 0) {
    return Status::FailedPrecondition(
        "project " + Quoted(project) + " already has " + std::to_string(taken_count) +
        " of the imported structures (" + taken + (taken_count > 10 ? ", ..." : "") +
        "); import into another project, or edit them with checkout and commit");
  }
  for (const ImportedStructure& s : structures) {
    // Mapped, not copied onto the heap: a label mask may be large.
    std::unique_ptr<MappedFile> mapped;
    PBA_RETURN_IF_ERROR(MappedFile::Open(s.file, &mapped));
    const std::string_view bytes = mapped->bytes();
    PBA_RETURN_IF_ERROR(CheckGeometry(bytes));
    // The blob before any row that names it.
    Content content;
    PBA_RETURN_IF_ERROR(blobs_->Put(bytes, &content.sha256));
    content.format = s.format;
    content.size_bytes = static_cast<int64_t>(bytes.size());
    content.metadata = s.metadata;
    StructureRow structure;
    PBA_RETURN_IF_ERROR(InsertStructure(caller, s.name, &structure.id));
    Revision revision;
    PBA_RETURN_IF_ERROR(AppendRevision(caller, StructureRef{project, s.name}, structure, "create",
                                       "structure.import", message, content, true, &revision));
  }
  int64_t id = 0;
  PBA_RETURN_IF_ERROR(PinSnapshot(caller, project, snapshot_name, job_id, &id));
  bool found = false;
  PBA_RETURN_IF_ERROR(LoadSnapshot(project, caller.project, id, true, snapshot, &found));
  return transaction.Commit();
}

}  // namespace pba
