// Store: opening a store, its transactions and the fence of claimed writes, and the
// admission checks the job and site files share. The rest of Store: store_jobs.cpp,
// store_leases.cpp, store_sites.cpp, store_users.cpp and store_copy.cpp.
#include "server/store/store.h"

#include <filesystem>
#include <thread>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "server/store/migrations.h"
#include "server/store/postgres_database.h"
#include "server/store/sqlite_database.h"
#include "server/store/store_internal.h"

namespace fenestra {

bool IsUnparsableRecord(const absl::Status& status) {
  return status.code() == absl::StatusCode::kDataLoss &&
         status.GetPayload(kUnparsableRecordUrl).has_value();
}

bool IsPostgresUrl(const std::string& url) {
  return absl::StartsWith(url, "postgresql://") || absl::StartsWith(url, "postgres://");
}

absl::StatusOr<std::unique_ptr<Store>> OpenStoreUrl(const std::string& url, int connections) {
  if (IsPostgresUrl(url)) {
    FENESTRA_ASSIGN_OR_RETURN(db, PostgresDatabase::Open(url, connections));
    return Store::Open(std::move(db));
  }
  if (absl::StartsWith(url, "sqlite:")) {
    const std::filesystem::path path = std::filesystem::path(url.substr(7)) / "fenestra.db";
    FENESTRA_ASSIGN_OR_RETURN(
        db, SqliteDatabase::Open(path.string(), SqliteDatabase::Sharing::kShared));
    return Store::Open(std::move(db));
  }
  return absl::InvalidArgumentError(absl::StrCat(
      "store '", RedactPostgresUrl(url),
      "': give postgresql://user@host:port/database, or sqlite:DIR for a data directory"));
}

absl::StatusOr<std::unique_ptr<Store>> Store::Open(std::unique_ptr<Database> db,
                                                   UploadStore* weather_files) {
  FENESTRA_RETURN_IF_ERROR(Migrate(*db));
  return std::unique_ptr<Store>(new Store(std::move(db), weather_files));
}

Store::~Store() = default;

absl::Status Store::Transact(const std::function<absl::Status(SqlSession&)>& body, bool durable,
                             bool write) {
  return db_->Transact(TransactionOptions{.write = write, .durable = durable}, body);
}

absl::Status Store::Fenced(const absl::StatusOr<SqlResult>& result, const Lease& lease) {
  if (!result.ok()) return result.status();
  if (result->rows.empty() && result->changed == 0) {
    return absl::AbortedError(
        absl::StrCat(lease.id, ": its lease was lost (another replica took it over)"));
  }
  return absl::OkStatus();
}

bool Store::AwaitAnswer(std::chrono::milliseconds poll, const std::function<bool()>& stop) {
  const TransactionOptions read{.write = false, .durable = false};
  while (true) {
    std::this_thread::sleep_for(poll);
    if (stop()) return false;
    const absl::Status answer =
        db_->Transact(read, [](SqlSession& session) { return session.Run("SELECT 1").status(); });
    if (answer.ok()) return true;
  }
}

namespace store_internal {
namespace {

// The uploads `owner` holds: weather files of its sites and queued or running jobs [bytes].
absl::StatusOr<int64_t> UploadBytes(SqlSession& s, const std::string& owner) {
  FENESTRA_ASSIGN_OR_RETURN(
      held, s.Run("SELECT CAST(COALESCE(SUM(upload_bytes), 0) AS BIGINT) FROM jobs WHERE owner "
                  "= ? AND state IN (?, ?)",
                  {owner, kQueued, kRunning}));
  FENESTRA_ASSIGN_OR_RETURN(
      sites, s.Run("SELECT CAST(COALESCE(SUM(upload_bytes), 0) AS BIGINT) FROM sites WHERE owner "
                   "= ?",
                   {owner}));
  return held.rows[0].Int(0) + sites.rows[0].Int(0);
}

}  // namespace

absl::Status CheckUploadQuota(SqlSession& s, const std::string& owner, int64_t bytes,
                              const v1::Limits& limits) {
  if (bytes <= 0) return absl::OkStatus();
  FENESTRA_ASSIGN_OR_RETURN(held, UploadBytes(s, owner));
  if (held + bytes > limits.max_upload_bytes_per_user()) {
    return absl::ResourceExhaustedError(
        absl::StrCat("limits.max_upload_bytes_per_user (", limits.max_upload_bytes_per_user(),
                     ") reached: your sites and queued or running jobs hold ", held,
                     " bytes of weather files and this request brings ", bytes,
                     " more; delete a site, or wait until a job ends"));
  }
  return absl::OkStatus();
}

absl::StatusOr<int64_t> NextCounter(SqlSession& s, const char* name) {
  FENESTRA_ASSIGN_OR_RETURN(
      next, s.Run("UPDATE counters SET value = value + 1 WHERE name = ? RETURNING value", {name}));
  if (next.rows.empty()) return absl::InternalError(absl::StrCat("no counter ", name));
  return next.rows[0].Int(0);
}

}  // namespace store_internal

}  // namespace fenestra
