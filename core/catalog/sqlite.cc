#include "core/catalog/sqlite.h"

#include <stdexcept>

namespace idrig {

SqliteDatabase::SqliteDatabase(const std::string& path, bool read_only) : path_(path) {
  const int flags = read_only ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  if (sqlite3_open_v2(path.c_str(), &db_, flags | SQLITE_OPEN_FULLMUTEX, nullptr) != SQLITE_OK) {
    std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error("cannot open SQLite database '" + path + "': " + message);
  }
  sqlite3_busy_timeout(db_, 5000);
}

SqliteDatabase::~SqliteDatabase() { sqlite3_close_v2(db_); }

void SqliteDatabase::Exec(const std::string& constant_sql) {
  char* error = nullptr;
  if (sqlite3_exec(db_, constant_sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    std::string message = error ? error : "unknown error";
    sqlite3_free(error);
    throw std::runtime_error("SQLite error in '" + path_ + "': " + message +
                             " (in: " + constant_sql.substr(0, 80) + ")");
  }
}

int SqliteDatabase::UserVersion() {
  SqliteStatement s(*this, "PRAGMA user_version");
  s.Step();
  return static_cast<int>(s.Int(0));
}

int SqliteDatabase::Migrate(const std::vector<std::string>& migrations) {
  int applied = 0;
  for (int v = UserVersion(); v < static_cast<int>(migrations.size()); ++v) {
    SqliteTransaction tx(*this);
    Exec(migrations[v]);
    // PRAGMA takes no bound parameters; the value is our own loop counter.
    Exec("PRAGMA user_version = " + std::to_string(v + 1));
    tx.Commit();
    ++applied;
  }
  return applied;
}

SqliteStatement::SqliteStatement(SqliteDatabase& db, const char* sql) : db_(db), sql_(sql) {
  if (sqlite3_prepare_v2(db.handle(), sql, -1, &stmt_, nullptr) != SQLITE_OK)
    throw std::runtime_error("SQLite cannot prepare '" + sql_ +
                             "': " + sqlite3_errmsg(db.handle()));
}

SqliteStatement::~SqliteStatement() { sqlite3_finalize(stmt_); }

namespace {
void Check(int rc, sqlite3* db, const std::string& sql) {
  if (rc != SQLITE_OK)
    throw std::runtime_error("SQLite bind failed in '" + sql + "': " + sqlite3_errmsg(db));
}
}  // namespace

SqliteStatement& SqliteStatement::Bind(int index, int64_t value) {
  Check(sqlite3_bind_int64(stmt_, index, value), db_.handle(), sql_);
  return *this;
}
SqliteStatement& SqliteStatement::Bind(int index, double value) {
  Check(sqlite3_bind_double(stmt_, index, value), db_.handle(), sql_);
  return *this;
}
SqliteStatement& SqliteStatement::Bind(int index, const std::string& value) {
  Check(sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()),
                          SQLITE_TRANSIENT),
        db_.handle(), sql_);
  return *this;
}
SqliteStatement& SqliteStatement::BindBlob(int index, const void* data, size_t size) {
  Check(sqlite3_bind_blob(stmt_, index, data, static_cast<int>(size), SQLITE_TRANSIENT),
        db_.handle(), sql_);
  return *this;
}
SqliteStatement& SqliteStatement::BindNull(int index) {
  Check(sqlite3_bind_null(stmt_, index), db_.handle(), sql_);
  return *this;
}

bool SqliteStatement::Step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const std::string message = sqlite3_errmsg(db_.handle());
  sqlite3_reset(stmt_);
  throw std::runtime_error("SQLite error running '" + sql_ + "': " + message);
}

void SqliteStatement::Reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

void SqliteStatement::Run() {
  while (Step()) {
  }
  Reset();
}

std::string SqliteStatement::Text(int column) const {
  const unsigned char* text = sqlite3_column_text(stmt_, column);
  if (!text) return "";
  return std::string(reinterpret_cast<const char*>(text), sqlite3_column_bytes(stmt_, column));
}

std::vector<uint8_t> SqliteStatement::Blob(int column) const {
  const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(stmt_, column));
  const int size = sqlite3_column_bytes(stmt_, column);
  return data ? std::vector<uint8_t>(data, data + size) : std::vector<uint8_t>();
}

SqliteTransaction::SqliteTransaction(SqliteDatabase& db) : db_(db) { db_.Exec("BEGIN IMMEDIATE"); }
SqliteTransaction::~SqliteTransaction() {
  if (!done_) {
    try {
      db_.Exec("ROLLBACK");
    } catch (...) {
    }
  }
}
void SqliteTransaction::Commit() {
  db_.Exec("COMMIT");
  done_ = true;
}

}  // namespace idrig
