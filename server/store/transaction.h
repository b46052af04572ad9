// Transaction: BEGIN IMMEDIATE on construction, ROLLBACK on destruction unless
// Commit() succeeded, so an early return never leaves half a change behind.
// IMMEDIATE takes the write lock up front: a read-then-write transaction can
// then not fail with SQLITE_BUSY half way through.
#pragma once

#include "pba/status.h"
#include "store/database.h"

namespace pba {

class Transaction {
 public:
  explicit Transaction(Database& db);
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction();

  // Whether BEGIN succeeded; check before doing work.
  const Status& status() const { return begin_status_; }
  Status Commit();

 private:
  Database& db_;
  Status begin_status_;
  bool open_ = false;
};

}  // namespace pba
