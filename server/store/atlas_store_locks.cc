// AtlasStore's edit locks: acquire, renew, release and break, and the lock
// check of Commit and Revert. A lock is a row in `locks`; its lease lapses at
// lease_expiry_us by the store's clock, after which the lock no longer
// protects anything and anyone may take it over.
#include <string>

#include "store/atlas_store.h"
#include "store/atlas_store_internal.h"
#include "store/random_hex.h"
#include "store/transaction.h"

namespace pba {
namespace {

using atlas_internal::Describe;
using atlas_internal::FormatTime;
using atlas_internal::Quoted;
using atlas_internal::StructureTarget;

// Lock ids are bearer secrets too, but only for the lease's lifetime.
constexpr int kLockIdBytes = 16;

// The lock `lock_id` with its structure and project, for Renew and Release.
struct HeldLock {
  int64_t structure = 0;
  int64_t owner = 0;
  int64_t project = 0;
  int64_t acquired_us = 0;
  int64_t lease_expiry_us = 0;
  StructureRef ref;
};

Status FindLockById(Database& db, const std::string& lock_id, HeldLock* held) {
  if (lock_id.empty()) return Status::InvalidArgument("lock_id", "must not be empty");
  Statement stmt;
  PBA_RETURN_IF_ERROR(db.Prepare(
      "SELECT l.structure, l.owner, s.project, l.acquired_us, l.lease_expiry_us, s.name, p.name "
      "FROM locks l JOIN structures s ON s.id = l.structure JOIN projects p ON p.id = s.project "
      "WHERE l.lock_id = ?",
      &stmt));
  bool row = false;
  PBA_RETURN_IF_ERROR(stmt.Bind(1, lock_id).Step(&row));
  if (!row) {
    return Status::FailedPrecondition(
        "that lock is no longer held: it was released, broken by an admin, or taken over after "
        "its lease lapsed");
  }
  held->structure = stmt.ColumnInt(0);
  held->owner = stmt.ColumnInt(1);
  held->project = stmt.ColumnInt(2);
  held->acquired_us = stmt.ColumnInt(3);
  held->lease_expiry_us = stmt.ColumnInt(4);
  held->ref = {stmt.ColumnText(6), stmt.ColumnText(5)};
  return Status::Ok();
}

}  // namespace

Status AtlasStore::FindLock(int64_t structure, LockRow* lock, bool* found) {
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare(
      "SELECT l.owner, u.name, l.lock_id, l.acquired_us, l.lease_expiry_us FROM locks l "
      "JOIN users u ON u.id = l.owner WHERE l.structure = ?",
      &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, structure).Step(found));
  if (*found) {
    lock->owner = stmt.ColumnInt(0);
    lock->owner_name = stmt.ColumnText(1);
    lock->lock_id = stmt.ColumnText(2);
    lock->acquired_us = stmt.ColumnInt(3);
    lock->lease_expiry_us = stmt.ColumnInt(4);
  }
  return Status::Ok();
}

Status AtlasStore::PublicLock(const StructureRef& ref, int64_t structure,
                              std::optional<LockInfo>* lock) {
  LockRow row;
  bool found = false;
  PBA_RETURN_IF_ERROR(FindLock(structure, &row, &found));
  lock->reset();
  if (!found) return Status::Ok();
  LockInfo& info = lock->emplace();
  info.owner = row.owner_name;
  info.acquired_us = row.acquired_us;
  info.lease_expiry_us = row.lease_expiry_us;
  info.structure = ref;
  return Status::Ok();
}

Status AtlasStore::CheckLockForWrite(const Caller& caller, const StructureRef& ref,
                                     int64_t structure, const std::string& lock_id) {
  LockRow lock;
  bool found = false;
  PBA_RETURN_IF_ERROR(FindLock(structure, &lock, &found));
  const int64_t now = clock_();
  if (!found) {
    return Status::FailedPrecondition(Describe(ref) +
                                      " is not locked; acquire its lock before changing it");
  }
  if (lock.owner != caller.user) {
    const bool lapsed = now >= lock.lease_expiry_us;
    return Status::FailedPrecondition(Describe(ref) + " is locked by " + Quoted(lock.owner_name) +
                                      (lapsed ? ", whose lease lapsed at " : " until ") +
                                      FormatTime(lock.lease_expiry_us) +
                                      (lapsed ? "; acquire the lock to take it over" : ""));
  }
  if (lock.lock_id != lock_id) {
    return Status::FailedPrecondition("the lock id given is not your current lock on " +
                                      Describe(ref) +
                                      " (it may have been replaced by a newer one)");
  }
  if (now >= lock.lease_expiry_us) {
    return Status::FailedPrecondition("your lease on " + Describe(ref) + " lapsed at " +
                                      FormatTime(lock.lease_expiry_us) +
                                      "; acquire the lock again");
  }
  return Status::Ok();
}

Status AtlasStore::CheckLease(int64_t lease_us) const {
  if (lease_us <= 0) return Status::InvalidArgument("lease", "must be positive");
  if (lease_us > kMaxLeaseMicros) {
    return Status::InvalidArgument("lease", "is longer than the " +
                                                std::to_string(kMaxLeaseMicros / 1000000) +
                                                " s limit; renew the lock instead");
  }
  return Status::Ok();
}

Status AtlasStore::AcquireLock(const std::string& user, const StructureRef& ref, int64_t lease_us,
                               LockInfo* info) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  PBA_RETURN_IF_ERROR(CheckLease(lease_us));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(user, ref, Role::kEditor, &caller, &structure));
  const int64_t now = clock_();
  LockRow held;
  bool found = false;
  PBA_RETURN_IF_ERROR(FindLock(structure.id, &held, &found));
  std::string detail;
  Statement stmt;
  *info = LockInfo();
  if (found) {
    if (now < held.lease_expiry_us) {
      return Status::FailedPrecondition(
          Describe(ref) + " is locked by " + Quoted(held.owner_name) +
          (held.owner == caller.user ? " (you, in another session)" : "") + " until " +
          FormatTime(held.lease_expiry_us));
    }
    info->took_over_from = held.owner_name;
    detail = "took over from " + held.owner_name + ", whose lease lapsed at " +
             FormatTime(held.lease_expiry_us) + "; ";
    PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM locks WHERE structure = ?", &stmt));
    PBA_RETURN_IF_ERROR(stmt.Bind(1, structure.id).Run());
  }
  std::string lock_id;
  PBA_RETURN_IF_ERROR(RandomHex(kLockIdBytes, &lock_id));
  PBA_RETURN_IF_ERROR(
      db_->Prepare("INSERT INTO locks (structure, owner, lock_id, acquired_us, lease_expiry_us) "
                   "VALUES (?, ?, ?, ?, ?)",
                   &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, structure.id)
                          .Bind(2, caller.user)
                          .Bind(3, lock_id)
                          .Bind(4, now)
                          .Bind(5, now + lease_us)
                          .Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, found ? "lock.takeover" : "lock.acquire",
                            StructureTarget(ref), std::nullopt,
                            detail + "lease until " + FormatTime(now + lease_us)));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  info->lock_id = std::move(lock_id);
  info->owner = user;
  info->acquired_us = now;
  info->lease_expiry_us = now + lease_us;
  info->structure = ref;
  return Status::Ok();
}

Status AtlasStore::RenewLock(const std::string& user, const std::string& lock_id, int64_t lease_us,
                             LockInfo* info) {
  PBA_RETURN_IF_ERROR(CheckLease(lease_us));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  HeldLock held;
  PBA_RETURN_IF_ERROR(FindLockById(*db_, lock_id, &held));
  Caller caller;
  PBA_RETURN_IF_ERROR(Enter(user, held.ref.project, Role::kEditor, &caller));
  if (held.owner != caller.user) {
    return Status::FailedPrecondition("that lock on " + Describe(held.ref) +
                                      " belongs to another user");
  }
  const int64_t now = clock_();
  if (now >= held.lease_expiry_us) {
    return Status::FailedPrecondition("your lease on " + Describe(held.ref) + " lapsed at " +
                                      FormatTime(held.lease_expiry_us) +
                                      "; acquire the lock again");
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(
      db_->Prepare("UPDATE locks SET lease_expiry_us = ? WHERE structure = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, now + lease_us).Bind(2, held.structure).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, "lock.renew", StructureTarget(held.ref),
                            std::nullopt, "lease until " + FormatTime(now + lease_us)));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  *info = LockInfo();
  info->lock_id = lock_id;
  info->owner = user;
  info->acquired_us = held.acquired_us;
  info->lease_expiry_us = now + lease_us;
  info->structure = held.ref;
  return Status::Ok();
}

Status AtlasStore::ReleaseLock(const std::string& user, const std::string& lock_id,
                               StructureRef* released) {
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  HeldLock held;
  PBA_RETURN_IF_ERROR(FindLockById(*db_, lock_id, &held));
  int64_t user_id = 0;
  PBA_RETURN_IF_ERROR(ActingUser(user, &user_id));
  if (held.owner != user_id) {
    return Status::FailedPrecondition("that lock on " + Describe(held.ref) +
                                      " belongs to another user");
  }
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM locks WHERE structure = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, held.structure).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(
      Audit(user_id, held.project, "lock.release", StructureTarget(held.ref), std::nullopt, ""));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  if (released != nullptr) *released = held.ref;
  return Status::Ok();
}

Status AtlasStore::BreakLock(const std::string& admin, const StructureRef& ref,
                             const std::string& reason, std::string* holder) {
  PBA_RETURN_IF_ERROR(CheckName("structure", ref.structure));
  if (reason.empty()) {
    return Status::InvalidArgument("reason", "must say why the lock is broken (it is audited)");
  }
  PBA_RETURN_IF_ERROR(CheckMessage("reason", reason));
  std::lock_guard lock(mutex_);
  Transaction transaction(*db_);
  PBA_RETURN_IF_ERROR(transaction.status());
  Caller caller;
  StructureRow structure;
  PBA_RETURN_IF_ERROR(EnterStructure(admin, ref, Role::kAdmin, &caller, &structure));
  LockRow held;
  bool found = false;
  PBA_RETURN_IF_ERROR(FindLock(structure.id, &held, &found));
  if (!found) return Status::FailedPrecondition(Describe(ref) + " is not locked");
  Statement stmt;
  PBA_RETURN_IF_ERROR(db_->Prepare("DELETE FROM locks WHERE structure = ?", &stmt));
  PBA_RETURN_IF_ERROR(stmt.Bind(1, structure.id).Run());
  stmt = Statement();
  PBA_RETURN_IF_ERROR(Audit(caller.user, caller.project, "lock.break", StructureTarget(ref),
                            std::nullopt,
                            "lock of " + held.owner_name + " (lease until " +
                                FormatTime(held.lease_expiry_us) + ") broken: " + reason));
  PBA_RETURN_IF_ERROR(transaction.Commit());
  if (holder != nullptr) *holder = held.owner_name;
  return Status::Ok();
}

}  // namespace pba
