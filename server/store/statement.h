// Statement: a prepared SQLite statement owned by a Database's cache and
// borrowed for one use. Binding is 1-based, columns are 0-based (as in the
// SQLite C API); the statement is reset and its bindings cleared when the
// borrower drops it, so the next borrower starts clean.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "pba/status.h"

namespace pba {

class Statement {
 public:
  Statement() = default;
  explicit Statement(sqlite3_stmt* stmt) : stmt_(stmt) {}
  Statement(Statement&& other) noexcept : stmt_(other.stmt_) { other.stmt_ = nullptr; }
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement();

  bool valid() const { return stmt_ != nullptr; }

  Statement& Bind(int index, int64_t value);
  Statement& Bind(int index, double value);
  Statement& Bind(int index, std::string_view text);
  Statement& Bind(int index, const char* text) { return Bind(index, std::string_view(text)); }
  Statement& BindBlob(int index, std::string_view bytes);
  Statement& BindNull(int index);
  // Binds NULL for an empty optional.
  Statement& Bind(int index, const std::optional<int64_t>& value);

  // Steps once. *row is true when a row is available, false when done.
  Status Step(bool* row);
  // Steps a statement that returns no rows (INSERT, UPDATE, DELETE).
  Status Run();

  int64_t ColumnInt(int column) const;
  double ColumnDouble(int column) const;
  std::string ColumnText(int column) const;
  std::string ColumnBlob(int column) const;
  bool ColumnIsNull(int column) const;

 private:
  sqlite3_stmt* stmt_ = nullptr;
};

}  // namespace pba
