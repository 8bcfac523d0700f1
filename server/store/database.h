#pragma once

// The SQL databases the store runs on: SQLite (one file, one process) and PostgreSQL (a
// server shared by any number of fenestrad replicas), behind one small interface. The
// store writes its SQL once; the few places where the dialects differ are spelled as
// {placeholders} that Database::Sql fills in, and parameters are bound to `?`.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fenestra {

enum class Dialect { kSqlite, kPostgres };

// Bytes bound as a BLOB (SQLite) or bytea (PostgreSQL); not copied, so they must outlive
// the statement.
struct SqlBlob {
  std::string_view bytes;
};
// A value bound to one `?`: NULL, an integer, text (not copied) or bytes.
using SqlParam = std::variant<std::nullptr_t, int64_t, std::string_view, SqlBlob>;

// One row of a result: each column NULL, an integer or bytes (text and blobs alike).
class SqlRow {
 public:
  using Cell = std::variant<std::monostate, int64_t, std::string>;
  explicit SqlRow(std::vector<Cell> cells) : cells_(std::move(cells)) {}
  bool IsNull(size_t column) const {
    return std::holds_alternative<std::monostate>(cells_[column]);
  }
  // The column as an integer (0 when NULL).
  int64_t Int(size_t column) const;
  // The column's bytes ("" when NULL; an integer in decimal).
  std::string Bytes(size_t column) const;
  // The column's bytes, moved out of the row.
  std::string TakeBytes(size_t column);

 private:
  std::vector<Cell> cells_;
};

// What a statement returned: its rows, and how many rows it changed.
struct SqlResult {
  std::vector<SqlRow> rows;
  int64_t changed = 0;
};

// One connection inside a transaction.
class SqlSession {
 public:
  virtual ~SqlSession() = default;
  // Runs one statement (SQL with {placeholders} filled, `?` for parameters).
  virtual absl::StatusOr<SqlResult> Run(std::string_view sql, std::span<const SqlParam> params) = 0;
  absl::StatusOr<SqlResult> Run(std::string_view sql, std::initializer_list<SqlParam> params = {}) {
    return Run(sql, std::span<const SqlParam>(params.begin(), params.size()));
  }
  // Holds the lock `key` until the transaction ends, against every other session of
  // every process on the database (PostgreSQL: an advisory lock; SQLite: a write
  // transaction already holds the whole file).
  virtual absl::Status Lock(int64_t key) = 0;
  // Wakes the waiters on this database, in every process, once the transaction commits.
  virtual absl::Status Notify() = 0;
};

// How a transaction runs.
struct TransactionOptions {
  // Takes the write lock at once (SQLite BEGIN IMMEDIATE), so reads and the writes that
  // depend on them see one state.
  bool write = true;
  // Synced to disk before Transact returns; false for progress, which a crash may lose.
  bool durable = true;
};

// A database. Thread-safe. Errors carry no paths or host names: a full disk is
// StorageFullError (RESOURCE_EXHAUSTED), a database that cannot be reached Unavailable,
// a unique key taken AlreadyExists, anything else Internal; the details are logged.
class Database {
 public:
  virtual ~Database() = default;
  virtual Dialect dialect() const = 0;
  // Runs `body` in one transaction: committed when it returns OK, rolled back otherwise.
  // A transaction that lost a deadlock or a serialization race is run again.
  virtual absl::Status Transact(const TransactionOptions& options,
                                const std::function<absl::Status(SqlSession&)>& body) = 0;
  // What the store names this database in logs (a PostgreSQL URL without its password).
  virtual std::string Describe() const = 0;

  // `sql` with the dialect's spelling of {now} (milliseconds since the Unix epoch, the
  // database's clock), {blob}, {int}, {serial} (an integer key that grows, never reused),
  // {for_update} (locks the rows read until the transaction ends) and {claim_lock} (locks
  // the rows read of the table aliased `c`, skipping those another transaction holds).
  // SQLite needs no row locks: a write transaction holds the whole file.
  std::string Sql(std::string_view sql) const;

  // Changes: a count that grows when a transaction that called Notify commits, here or
  // in another process (PostgreSQL LISTEN/NOTIFY).
  uint64_t ChangeCount() const;
  // Waits until ChangeCount() passes `seen`, or `timeout`; true when it did.
  bool WaitForChange(uint64_t seen, std::chrono::milliseconds timeout) const;
  // Wakes every waiter, as a change would (a process that stops).
  void WakeWaiters() { Changed(); }

 protected:
  void Changed();

 private:
  mutable std::mutex change_mutex_;
  mutable std::condition_variable change_cv_;
  uint64_t changes_ = 0;
};

}  // namespace fenestra
