#include "store/database.h"

namespace pba {
namespace {

// Long enough to ride out a checkpoint or another process's short write.
constexpr int kBusyTimeoutMs = 5000;

}  // namespace

Status Database::Open(const std::filesystem::path& path, std::unique_ptr<Database>* out) {
  sqlite3* raw = nullptr;
  const int rc =
      sqlite3_open_v2(path.c_str(), &raw,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX, nullptr);
  std::unique_ptr<Database> db(new Database(raw));
  if (rc != SQLITE_OK) {
    return Status::Io("cannot open " + path.string() + ": " +
                      (raw != nullptr ? sqlite3_errmsg(raw) : sqlite3_errstr(rc)));
  }
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, kBusyTimeoutMs);
  // WAL lets readers run beside the one writer; synchronous=NORMAL is safe
  // with WAL (a power cut may lose the last commits, never corrupt the file).
  PBA_RETURN_IF_ERROR(db->Exec("PRAGMA journal_mode=WAL;"));
  PBA_RETURN_IF_ERROR(db->Exec("PRAGMA synchronous=NORMAL; PRAGMA foreign_keys=ON;"));
  *out = std::move(db);
  return Status::Ok();
}

Database::~Database() {
  for (auto& [sql, stmt] : statements_) sqlite3_finalize(stmt);
  if (db_ != nullptr) sqlite3_close(db_);
}

Status Database::Exec(const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    std::string message = error != nullptr ? error : sqlite3_errmsg(db_);
    sqlite3_free(error);
    return Status::Io("sqlite: " + message);
  }
  return Status::Ok();
}

Status Database::Prepare(const std::string& sql, Statement* out) {
  auto it = statements_.find(sql);
  if (it == statements_.end()) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v3(db_, sql.c_str(), -1, SQLITE_PREPARE_PERSISTENT, &stmt, nullptr) !=
        SQLITE_OK) {
      return Status::Internal("sqlite: " + std::string(sqlite3_errmsg(db_)) + " (in: " + sql + ")");
    }
    it = statements_.emplace(sql, stmt).first;
  }
  *out = Statement(it->second);
  return Status::Ok();
}

}  // namespace pba
