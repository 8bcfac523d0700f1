#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "absl/status/statusor.h"
#include "server/store/database.h"

struct sqlite3;

namespace fenestra {

// A SQLite file (WAL journal) on one connection, its transactions taken in turn.
class SqliteDatabase final : public Database {
 public:
  // Who else may open the file while this process has it open.
  enum class Sharing {
    // Other processes too (`fenestrad user` beside a running daemon); the WAL index lives
    // in a -shm file next to the database.
    kShared,
    // This process alone (another gets FailedPrecondition); the WAL index lives in
    // memory, so a store on a full disk, where no -shm file can be made, still opens.
    kExclusive,
  };
  // Opens or creates the file. FailedPrecondition naming it when it is read-only or,
  // kExclusive, another process holds it.
  static absl::StatusOr<std::unique_ptr<SqliteDatabase>> Open(const std::string& path,
                                                              Sharing sharing);
  ~SqliteDatabase() override;

  Dialect dialect() const override { return Dialect::kSqlite; }
  absl::Status Transact(const TransactionOptions& options,
                        const std::function<absl::Status(SqlSession&)>& body) override;
  std::string Describe() const override { return path_; }

 private:
  SqliteDatabase(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
  // Runs SQL without parameters or results (mutex_ held).
  absl::Status Exec(const char* sql);

  std::mutex mutex_;
  sqlite3* db_;
  const std::string path_;
};

}  // namespace fenestra
