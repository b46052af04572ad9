// Read-only queries on a server's pba.db from integration tests, beside the
// running server's own connection (WAL allows it).
#pragma once

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <string>
#include <vector>

namespace pba::testing {

using Rows = std::vector<std::vector<std::string>>;

// Runs `sql` on <data>/pba.db through a read-only connection of its own
// (beside the running server's, which WAL allows) and returns every row as
// text; NULL reads as "NULL". A failure is a test failure.
inline Rows Query(const std::filesystem::path& data_dir, const std::string& sql) {
  Rows rows;
  sqlite3* db = nullptr;
  const std::filesystem::path path = data_dir / "pba.db";
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << "cannot open " << path << ": " << sqlite3_errmsg(db);
    sqlite3_close(db);
    return rows;
  }
  sqlite3_busy_timeout(db, 5000);
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) != SQLITE_OK) {
    ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db);
    sqlite3_close(db);
    return rows;
  }
  int rc;
  while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
    std::vector<std::string> row;
    for (int i = 0; i < sqlite3_column_count(stmt); ++i) {
      const auto* text = sqlite3_column_text(stmt, i);
      row.push_back(text == nullptr ? "NULL" : reinterpret_cast<const char*>(text));
    }
    rows.push_back(std::move(row));
  }
  if (rc != SQLITE_DONE) ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db);
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return rows;
}

inline std::string QueryOne(const std::filesystem::path& data_dir, const std::string& sql) {
  const Rows rows = Query(data_dir, sql);
  return rows.empty() || rows[0].empty() ? "" : rows[0][0];
}

}  // namespace pba::testing
