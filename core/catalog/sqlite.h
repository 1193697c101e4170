#pragma once
// Minimal RAII over the SQLite C API: a connection and prepared statements. Data only ever
// goes through bound parameters (no SQL text is built from values). Errors throw
// std::runtime_error with SQLite's message and the statement.
#include <sqlite3.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace idrig {

class SqliteStatement;

class SqliteDatabase {
 public:
  // Opens (creating if needed, unless read_only) and sets busy_timeout.
  explicit SqliteDatabase(const std::string& path, bool read_only = false);
  ~SqliteDatabase();
  SqliteDatabase(const SqliteDatabase&) = delete;
  SqliteDatabase& operator=(const SqliteDatabase&) = delete;

  // Runs constant SQL (schema, pragmas, BEGIN/COMMIT): never pass values here.
  void Exec(const std::string& constant_sql);
  int UserVersion();
  // Applies migrations[v] for v >= user_version, each in a transaction that also sets
  // user_version = v + 1. Returns the number applied.
  int Migrate(const std::vector<std::string>& migrations);
  int64_t LastInsertRowId() const { return sqlite3_last_insert_rowid(db_); }
  int Changes() const { return sqlite3_changes(db_); }
  sqlite3* handle() { return db_; }
  const std::string& path() const { return path_; }

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
};

class SqliteStatement {
 public:
  SqliteStatement(SqliteDatabase& db, const char* sql);
  ~SqliteStatement();
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  // 1-based parameter index, as in SQLite. Return *this for chaining.
  SqliteStatement& Bind(int index, int64_t value);
  SqliteStatement& Bind(int index, int value) { return Bind(index, static_cast<int64_t>(value)); }
  SqliteStatement& Bind(int index, double value);
  SqliteStatement& Bind(int index, const std::string& value);
  SqliteStatement& BindBlob(int index, const void* data, size_t size);
  SqliteStatement& BindNull(int index);
  // true: a row is available; false: done. Throws on error.
  bool Step();
  // Resets and clears bindings for the next use.
  void Reset();
  // Step() until done, then Reset(); for INSERT/UPDATE.
  void Run();

  int64_t Int(int column) const { return sqlite3_column_int64(stmt_, column); }
  double Double(int column) const { return sqlite3_column_double(stmt_, column); }
  bool IsNull(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
  std::string Text(int column) const;
  std::vector<uint8_t> Blob(int column) const;

 private:
  SqliteDatabase& db_;
  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

// Reads the current row of a statement column by column, left to right, into typed fields:
//   SqliteRow(s) >> e.rig_id >> e.experiment_id >> e.sample_rate_hz;
// A NULL read into a double gives NaN (an absent measure, e.g. fit_percent).
class SqliteRow {
 public:
  explicit SqliteRow(const SqliteStatement& s, int first_column = 0)
      : s_(s), column_(first_column) {}
  SqliteRow& operator>>(int64_t& v) {
    v = s_.Int(column_++);
    return *this;
  }
  SqliteRow& operator>>(int& v) {
    v = static_cast<int>(s_.Int(column_++));
    return *this;
  }
  SqliteRow& operator>>(bool& v) {
    v = s_.Int(column_++) != 0;
    return *this;
  }
  SqliteRow& operator>>(double& v) {
    v = s_.IsNull(column_) ? std::nan("") : s_.Double(column_);
    ++column_;
    return *this;
  }
  SqliteRow& operator>>(std::string& v) {
    v = s_.Text(column_++);
    return *this;
  }
  SqliteRow& operator>>(std::vector<uint8_t>& v) {
    v = s_.Blob(column_++);
    return *this;
  }

 private:
  const SqliteStatement& s_;
  int column_;
};

// BEGIN IMMEDIATE … COMMIT, rolled back if destroyed without Commit().
class SqliteTransaction {
 public:
  explicit SqliteTransaction(SqliteDatabase& db);
  ~SqliteTransaction();
  void Commit();

 private:
  SqliteDatabase& db_;
  bool done_ = false;
};

}  // namespace idrig
