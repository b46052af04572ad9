// Database: one SQLite connection with the settings every PBA database uses
// (WAL, foreign keys, a busy timeout) and a cache of prepared statements.
// Not thread-safe: the owner serialises access (JobStore holds a mutex).
#pragma once

#include <sqlite3.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "pba/status.h"
#include "store/statement.h"

namespace pba {

class Database {
 public:
  // Opens (creating if absent) the database file at `path`.
  static Status Open(const std::filesystem::path& path, std::unique_ptr<Database>* out);

  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;
  ~Database();

  // Runs one or more statements without parameters (DDL, PRAGMA, BEGIN).
  Status Exec(const std::string& sql);
  // Borrows the cached prepared statement for `sql` (preparing it once).
  Status Prepare(const std::string& sql, Statement* out);
  // Rows changed by the last INSERT/UPDATE/DELETE.
  int Changes() const { return sqlite3_changes(db_); }

 private:
  explicit Database(sqlite3* db) : db_(db) {}
  sqlite3* db_;
  std::map<std::string, sqlite3_stmt*> statements_;
};

}  // namespace pba
