#include "server/store/sqlite_database.h"

#include <spdlog/spdlog.h>
#include <sqlite3.h>

#include "absl/strings/str_cat.h"
#include "server/data_dir.h"

namespace fenestra {
namespace {

// How long a call waits for another connection's lock on a shared file [ms]: briefly while
// the open finds out whether another process holds the file, then longer, so that a
// transaction under load waits for another's lock rather than fail
constexpr int kOpenBusyMs = 500;
constexpr int kSqliteBusyMs = 5000;

// What a failed SQLite call means for a client: a full disk, a unique key taken, or an
// internal failure.
absl::Status Error(sqlite3* db) {
  const int code = sqlite3_extended_errcode(db);
  if ((code & 0xff) == SQLITE_FULL ||
      ((code & 0xff) == SQLITE_IOERR && IsStorageFullErrno(sqlite3_system_errno(db)))) {
    return StorageFullError();
  }
  if ((code & 0xff) == SQLITE_CONSTRAINT) {
    return absl::AlreadyExistsError(absl::StrCat("a stored key is taken: ", sqlite3_errmsg(db)));
  }
  return absl::InternalError(absl::StrCat("the server's job store failed: ", sqlite3_errmsg(db)));
}

class SqliteSession final : public SqlSession {
 public:
  explicit SqliteSession(sqlite3* db) : db_(db) {}

  using SqlSession::Run;
  absl::StatusOr<SqlResult> Run(std::string_view sql, std::span<const SqlParam> params) override {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db_, sql.data(), static_cast<int>(sql.size()), &stmt, nullptr) !=
        SQLITE_OK) {
      return Error(db_);
    }
    absl::StatusOr<SqlResult> result = Step(stmt, params);
    sqlite3_finalize(stmt);
    return result;
  }
  absl::Status Lock(int64_t) override { return absl::OkStatus(); }
  absl::Status Notify() override {
    notified_ = true;
    return absl::OkStatus();
  }
  bool notified() const { return notified_; }

 private:
  absl::StatusOr<SqlResult> Step(sqlite3_stmt* stmt, std::span<const SqlParam> params) {
    int rc = SQLITE_OK;
    for (size_t i = 0; i < params.size() && rc == SQLITE_OK; ++i) {
      const int at = static_cast<int>(i) + 1;
      const SqlParam& p = params[i];
      if (const int64_t* value = std::get_if<int64_t>(&p)) {
        rc = sqlite3_bind_int64(stmt, at, *value);
      } else if (const std::string_view* text = std::get_if<std::string_view>(&p)) {
        rc = sqlite3_bind_text64(stmt, at, text->data(), text->size(), SQLITE_STATIC, SQLITE_UTF8);
      } else if (const SqlBlob* blob = std::get_if<SqlBlob>(&p)) {
        rc = sqlite3_bind_blob64(stmt, at, blob->bytes.data(), blob->bytes.size(), SQLITE_STATIC);
      } else {
        rc = sqlite3_bind_null(stmt, at);
      }
    }
    if (rc != SQLITE_OK) return Error(db_);
    SqlResult result;
    while ((rc = sqlite3_step(stmt)) == SQLITE_ROW) {
      const int columns = sqlite3_column_count(stmt);
      std::vector<SqlRow::Cell> cells(columns);
      for (int c = 0; c < columns; ++c) {
        switch (sqlite3_column_type(stmt, c)) {
          case SQLITE_NULL:
            break;
          case SQLITE_INTEGER:
            cells[c] = static_cast<int64_t>(sqlite3_column_int64(stmt, c));
            break;
          default: {
            const void* data = sqlite3_column_blob(stmt, c);
            cells[c] = std::string(static_cast<const char*>(data),
                                   static_cast<size_t>(sqlite3_column_bytes(stmt, c)));
          }
        }
      }
      result.rows.emplace_back(std::move(cells));
    }
    if (rc != SQLITE_DONE) return Error(db_);
    result.changed = sqlite3_changes(db_);
    return result;
  }

  sqlite3* db_;
  bool notified_ = false;
};

}  // namespace

absl::StatusOr<std::unique_ptr<SqliteDatabase>> SqliteDatabase::Open(const std::string& path,
                                                                     Sharing sharing) {
  sqlite3* db = nullptr;
  const int rc =
      sqlite3_open_v2(path.c_str(), &db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    std::string message = db ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
    sqlite3_close(db);
    return absl::FailedPreconditionError(
        absl::StrCat(path, ": cannot open the job store: ", message));
  }
  std::unique_ptr<SqliteDatabase> database(new SqliteDatabase(db, path));
  sqlite3_extended_result_codes(db, 1);
  if (sqlite3_db_readonly(db, "main") == 1) {
    return absl::FailedPreconditionError(
        absl::StrCat(path, ": the job store is read-only (not writable)"));
  }
  sqlite3_busy_timeout(db, kOpenBusyMs);
  // Exclusive: a lock held from the first access keeps other processes out and the WAL
  // index in memory (no -shm file, so a full disk still lets it read)
  std::lock_guard lock(database->mutex_);
  for (const char* sql : {sharing == Sharing::kExclusive ? "PRAGMA locking_mode=EXCLUSIVE"
                                                         : "PRAGMA locking_mode=NORMAL",
                          "PRAGMA journal_mode=WAL", "PRAGMA synchronous=NORMAL",
                          // The first access: takes the exclusive lock
                          "SELECT COUNT(*) FROM sqlite_master"}) {
    if (absl::Status s = database->Exec(sql); !s.ok()) {
      if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_BUSY) {
        return absl::FailedPreconditionError(
            absl::StrCat(path,
                         ": the job store is in use by another process (another fenestrad "
                         "on this data directory?)"));
      }
      return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
    }
  }
  sqlite3_busy_timeout(db, kSqliteBusyMs);
  return database;
}

SqliteDatabase::~SqliteDatabase() { sqlite3_close(db_); }

absl::Status SqliteDatabase::Exec(const char* sql) {
  return sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) == SQLITE_OK ? absl::OkStatus()
                                                                        : Error(db_);
}

absl::Status SqliteDatabase::Transact(const TransactionOptions& options,
                                      const std::function<absl::Status(SqlSession&)>& body) {
  SqliteSession session(db_);
  absl::Status status;
  {
    std::lock_guard lock(mutex_);
    if (options.durable) (void)Exec("PRAGMA synchronous=FULL");
    status = Exec(options.write ? "BEGIN IMMEDIATE" : "BEGIN");
    if (status.ok()) status = body(session);
    if (status.ok()) status = Exec("COMMIT");
    if (!status.ok() && !sqlite3_get_autocommit(db_)) (void)Exec("ROLLBACK");
    if (options.durable) (void)Exec("PRAGMA synchronous=NORMAL");
  }
  if (status.ok() && session.notified()) Changed();
  return status;
}

}  // namespace fenestra
