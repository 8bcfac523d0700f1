#pragma once

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"
#include "server/store/database.h"

struct pg_conn;

namespace fenestra {

// A PostgreSQL database through libpq: a pool of connections for transactions (READ
// COMMITTED; rows are locked where the store needs them) and one more that LISTENs, so
// that a Notify in any process wakes this one's waiters within milliseconds. A lost
// connection is opened again at its next use; while the server cannot be reached, every
// transaction fails at once with Unavailable, and the listener tries again every half
// second. Parameters and results travel in binary.
class PostgresDatabase final : public Database {
 public:
  // Connects to `url` (postgresql://user@host:port/db; libpq's other settings and
  // environment apply) with `connections` pooled connections. Unavailable when the
  // server cannot be reached, naming the URL without its password.
  static absl::StatusOr<std::unique_ptr<PostgresDatabase>> Open(const std::string& url,
                                                                int connections);
  ~PostgresDatabase() override;

  Dialect dialect() const override { return Dialect::kPostgres; }
  absl::Status Transact(const TransactionOptions& options,
                        const std::function<absl::Status(SqlSession&)>& body) override;
  std::string Describe() const override { return described_; }

  // Whether every connection is up as far as this process knows: false from a failed
  // transaction until one succeeds.
  bool reachable() const { return reachable_; }

 private:
  explicit PostgresDatabase(std::string url);
  // A pooled connection, waiting for one to be free; null when the server cannot be
  // reached.
  pg_conn* Acquire(absl::Status& failure);
  void Release(pg_conn* conn);
  // Closes the idle pooled connections: the server dropped one, so it dropped them all.
  void DropIdle();
  // Opens a connection; null (and `failure`) when it cannot.
  pg_conn* Connect(absl::Status& failure) const;
  // Logs the first failure of a run of them and the recovery after it.
  void NoteReachable(bool reachable, const absl::Status& failure);
  void Listen();

  const std::string url_;
  const std::string described_;
  std::mutex pool_mutex_;
  std::condition_variable pool_free_;
  std::vector<pg_conn*> free_;  // null entries: connections to open at their next use
  std::atomic<bool> reachable_{true};
  std::atomic<bool> stop_{false};
  std::thread listener_;
};

// `url` with its password, if any, replaced by "***".
std::string RedactPostgresUrl(const std::string& url);

}  // namespace fenestra
