// AtlasStore's administration of users and members: disabling users,
// removing project members, the role check that comes before expensive
// work, and finding a commit by its request id (atlas_store.h).
#include <string>
#include <vector>

#include "store/atlas_store.h"
#include "store/atlas_store_internal.h"
#include "store/transaction.h"

namespace pba {
namespace {

using atlas_internal::Describe;
using atlas_internal::FormatTime;
using atlas_internal::ProjectTarget;
using atlas_internal::Quoted;
using atlas_internal::StructureTarget;

}  // namespace

Status AtlasStore::SetUserDisabled(const std::string& name, bool disabled, bool* changed) {
  PBA_RETURN_IF_ERROR(CheckName("user", name));
  if (changed != nullptr) *changed = false;
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id, disabled FROM users WHERE name = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, name).Step(&row));
  if (!row) return Status::NotFound("user " + Quoted(name) + " does not exist");
  const int64_t id = stmt.ColumnInt(0);
  if ((stmt.ColumnInt(1) != 0) == disabled) return Status::Ok();
  PBA_RETURN_IF_ERROR(db_->Prepare("UPDATE users SET disabled = ? WHERE id = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, int64_t{disabled ? 1 : 0}).Bind(2, id).Run());
  stmt = Statement();
  // Done offline by the operator, not by a user: no acting user.
  PBA_RETURN_IF_ERROR(Audit(std::nullopt, std::nullopt, disabled ? "user.disable" : "user.enable",
                            "users/" + name, std::nullopt, ""));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  if (changed != nullptr) *changed = true;
  return Status::Ok();
}

Status AtlasStore::IsUserDisabled(const std::string& name, bool* disabled) {
  PBA_RETURN_IF_ERROR(CheckName("user", name));
  std::lock_guard lock(mutex_);
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT disabled FROM users WHERE name = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, name).Step(&row));
  if (!row) return Status::NotFound("user " + Quoted(name) + " does not exist");
  *disabled = stmt.ColumnInt(0) != 0;
  return Status::Ok();
}

Status AtlasStore::CheckRole(const std::string& user, const std::string& project, Role minimum) {
  std::lock_guard lock(mutex_);
  Caller caller;
  return Enter(user, project, minimum, &caller);
}

Status AtlasStore::FindMember(int64_t project, const std::string& member, int64_t* member_id,
                              std::string* role) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("SELECT id FROM users WHERE name = ?", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, member).Step(&row));
  if (!row) return Status::NotFound("user " + Quoted(member) + " does not exist");
  *member_id = stmt.ColumnInt(0);
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT role FROM members WHERE project = ? AND user = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project).Bind(2, *member_id).Step(&row));
  *role = row ? stmt.ColumnText(0) : "";
  return Status::Ok();
}

Status AtlasStore::CountAdmins(int64_t project, int64_t* count) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT COUNT(*) FROM members WHERE project = ? AND role = 'admin'", &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, project).Step(&row));
  *count = stmt.ColumnInt(0);
  return Status::Ok();
}

Status AtlasStore::RemoveMember(const std::string& admin, const std::string& project,
                                const std::string& member,
                                std::vector<std::string>* released_locks) {
  PBA_RETURN_IF_ERROR(CheckName("member", member));
  released_locks->clear();
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(admin, project, Role::kAdmin, &caller));
  int64_t member_id = 0;
  std::string old_role;
  PBA_RETURN_IF_ERROR(FindMember(caller.project, member, &member_id, &old_role));
  if (old_role.empty()) {
    return Status::NotFound("user " + Quoted(member) + " is not a member of project " +
                            Quoted(project));
  }
  if (old_role == "admin") {
    // As SetRole: a project must keep someone who can manage it.
    int64_t admins = 0;
    PBA_RETURN_IF_ERROR(CountAdmins(caller.project, &admins));
    if (admins <= 1) {
      return Status::FailedPrecondition(Quoted(member) + " is the last admin of project " +
                                        Quoted(project) +
                                        "; make another member admin before removing them");
    }
  }
  // Their locks go with them: they can no longer commit under them, and an
  // unexpired lease would keep the structure from everyone else for up to
  // an hour. Each release is audited as a broken lock, as BreakLock does.
  struct Held {
    int64_t structure;
    std::string name;
    int64_t lease_expiry_us;
  };
  std::vector<Held> held;
  Statement stmt;
  bool row = false;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("SELECT s.id, s.name, l.lease_expiry_us FROM locks l "
                   "JOIN structures s ON s.id = l.structure "
                   "WHERE s.project = ? AND l.owner = ? ORDER BY s.name",
                   &stmt));
  stmt.Bind(1, caller.project).Bind(2, member_id);
  while (true) {
    PBA_RETURN_IF_ERROR(stmt.Step(&row));
    if (!row) break;
    held.push_back({stmt.ColumnInt(0), stmt.ColumnText(1), stmt.ColumnInt(2)});
  }
  stmt = Statement();
  for (const Held& lock_row : held) {
    PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM locks WHERE structure = ?", &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, lock_row.structure).Run());
    stmt = Statement();
    PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, "lock.break",
                              StructureTarget({project, lock_row.name}), std::nullopt,
                              "lock of " + member + " (lease until " +
                                  FormatTime(lock_row.lease_expiry_us) +
                                  ") released: they were removed from the project"));
    released_locks->push_back(lock_row.name);
  }
  PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM members WHERE project = ? AND user = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, caller.project).Bind(2, member_id).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, "member.remove",
                            ProjectTarget(project) + "/members/" + member, std::nullopt,
                            member + ": " + old_role + " -> (none)"));
  return transaction.Commit();
}

Status AtlasStore::FindCommitRequest(const Caller& caller, const StructureRef& ref,
                                     int64_t structure, const std::string& request_id,
                                     Revision* revision, bool* found) {
  *found = false;
  if (request_id.empty()) return Status::Ok();
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT number, author FROM structure_revisions WHERE structure = ? AND request_id = ?",
      &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, structure).Bind(2, request_id).Step(&row));
  if (!row) return Status::Ok();
  const int64_t number = stmt.ColumnInt(0);
  const int64_t author = stmt.ColumnInt(1);
  stmt = Statement();
  if (author != caller.user) {
    return Status::AlreadyExists("request_id: another user's commit of " + Describe(ref) +
                                 " carried this request id");
  }
  PBA_RETURN_IF_ERROR(ReadRevision(ref, structure, number, revision, found));
  if (!*found) return Status::Internal("the revision a commit made cannot be read back");
  return Status::Ok();
}

Status AtlasStore::FindCommit(const std::string& user, const StructureRef& ref,
                              const std::string& request_id, Revision* revision, bool* found) {
  *found = false;
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  PBA_RETURN_IF_ERROR(atlas_internal::CheckRequestId(request_id));
  std::lock_guard lock(mutex_);
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kEditor, &caller, &structure));
  return FindCommitRequest(caller, ref, structure.id, request_id, revision, found);
}

}  // namespace pba
