#include "server/store/migrations.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>

#include "absl/strings/str_cat.h"
#include "fenestra/v1/job.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/store/store_internal.h"
#include "server/users.h"

namespace fenestra {
namespace {

// The lock replicas take while one of them migrates
constexpr int64_t kMigrationLock = 0x46454e4553545241;  // "FENESTRA"
// SQLite files written before scenes had their own column keep them inside info.
absl::Status AddSceneColumn(const Database& db, SqlSession& s) {
  if (db.dialect() != Dialect::kSqlite) return absl::OkStatus();
  absl::StatusOr<SqlResult> columns = s.Run("PRAGMA table_info(sites)");
  if (!columns.ok()) return columns.status();
  for (const SqlRow& row : columns->rows) {
    if (row.Bytes(1) == "scene") return absl::OkStatus();
  }
  return s.Run("ALTER TABLE sites ADD COLUMN scene BLOB").status();
}

// Calls `each` on every row of `table` (its number, then `columns`), in order of number, a
// page of kRowsPerRead rows at a time.
absl::Status ForEachRow(SqlSession& s, const char* table, const char* columns,
                        const std::function<absl::Status(const SqlRow&)>& each) {
  const std::string sql = absl::StrCat("SELECT number, ", columns, " FROM ", table,
                                       " WHERE number > ? ORDER BY number LIMIT ?");
  for (int64_t after = 0;;) {
    absl::StatusOr<SqlResult> rows = s.Run(sql, {after, kRowsPerRead});
    if (!rows.ok()) return rows.status();
    if (rows->rows.empty()) return absl::OkStatus();
    for (const SqlRow& row : rows->rows) {
      after = row.Int(0);
      if (absl::Status st = each(row); !st.ok()) return st;
    }
  }
}

// Fills the columns version 2 added from each job's and site's stored protobufs; rows
// that do not parse keep the defaults (state 0: never claimed) and are quarantined at the
// next start.
absl::Status FillReplicaColumns(const Database&, SqlSession& s) {
  absl::Status jobs = ForEachRow(s, "jobs", "info, job", [&](const SqlRow& row) {
    v1::JobInfo info;
    if (!info.ParseFromString(row.Bytes(1))) return absl::OkStatus();
    v1::Job job;
    const std::string weather =
        job.ParseFromString(row.Bytes(2)) ? WeatherOfPath(job.weather_file()) : "";
    const std::string owner = info.owner().empty() ? kLocalUser : info.owner();
    return s
        .Run(
            "UPDATE jobs SET owner = ?, state = ?, outdoor_key = ?, upload_bytes = ?, "
            "weather = ?, queue_order = number WHERE number = ?",
            {owner, int64_t{info.state()}, info.outdoor_key(), info.upload_bytes(), weather,
             row.Int(0)})
        .status();
  });
  if (!jobs.ok()) return jobs;
  absl::Status sites = ForEachRow(s, "sites", "info, weather_path", [&](const SqlRow& row) {
    v1::SiteInfo info;
    if (!info.ParseFromString(row.Bytes(1))) return absl::OkStatus();
    const std::string owner = info.owner().empty() ? kLocalUser : info.owner();
    return s
        .Run(
            "UPDATE sites SET owner = ?, state = ?, outdoor_key = ?, upload_bytes = ?, "
            "weather = ?, queue_order = number WHERE number = ?",
            {owner, int64_t{info.state()}, info.outdoor_key(), info.upload_bytes(),
             WeatherOfPath(row.Bytes(2)), row.Int(0)})
        .status();
  });
  if (!sites.ok()) return sites;
  return s
      .Run(
          "INSERT INTO counters (name, value) SELECT 'queue', CAST(COALESCE(MAX(n), 0) AS "
          "BIGINT) FROM (SELECT MAX(number) AS n FROM jobs UNION ALL SELECT MAX(number) FROM "
          "sites) AS numbers")
      .status();
}

// Moves each finished job's result out of its info into the result column version 3 added
// (store_internal::ColumnsOf); rows that do not parse stay as they are and are quarantined at
// the next start.
absl::Status MoveResults(const Database&, SqlSession& s) {
  return ForEachRow(s, "jobs", "info", [&](const SqlRow& row) {
    v1::JobInfo info;
    if (!info.ParseFromString(row.Bytes(1)) || !info.has_result()) return absl::OkStatus();
    const store_internal::JobInfoColumns columns = store_internal::ColumnsOf(info);
    return s
        .Run("UPDATE jobs SET info = ?, result = ? WHERE number = ?",
             {columns.Info(), columns.Result(), row.Int(0)})
        .status();
  });
}

}  // namespace

std::string WeatherOfPath(const std::string& path) {
  return std::filesystem::path(path).stem().string();
}

const std::vector<Migration>& Migrations() {
  static const std::vector<Migration> migrations = {
      {1,
       "jobs, their events, sites, users, quarantine",
       {
           "CREATE TABLE IF NOT EXISTS jobs (number {serial}, id TEXT UNIQUE, info {blob} NOT "
           "NULL, job {blob} NOT NULL)",
           "CREATE TABLE IF NOT EXISTS job_events (job_id TEXT NOT NULL, sequence {int} NOT "
           "NULL, event {blob} NOT NULL, PRIMARY KEY (job_id, sequence))",
           "CREATE TABLE IF NOT EXISTS sites (number {serial}, id TEXT UNIQUE, info {blob} NOT "
           "NULL, weather_path TEXT NOT NULL, scene {blob})",
           "CREATE TABLE IF NOT EXISTS users (number {serial}, name TEXT UNIQUE NOT NULL, "
           "token_sha256 {blob} NOT NULL, admin {int} NOT NULL, created_unix_ms {int} NOT NULL, "
           "revoked_unix_ms {int} NOT NULL DEFAULT 0)",
           "CREATE TABLE IF NOT EXISTS quarantine (number {serial}, source TEXT NOT NULL, id "
           "TEXT, reason TEXT NOT NULL, info {blob}, body {blob}, weather_path TEXT, "
           "quarantined_unix_ms {int} NOT NULL)",
       },
       AddSceneColumn},
      {2,
       "replicas: owners, states, leases, checkpoints, turns, weather files and matrices in "
       "the database",
       {
           "ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE jobs ADD COLUMN state {int} NOT NULL DEFAULT 0",
           "ALTER TABLE jobs ADD COLUMN outdoor_key TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE jobs ADD COLUMN weather TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE jobs ADD COLUMN upload_bytes {int} NOT NULL DEFAULT 0",
           "ALTER TABLE jobs ADD COLUMN queue_order {int} NOT NULL DEFAULT 0",
           "ALTER TABLE jobs ADD COLUMN lease_owner TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE jobs ADD COLUMN lease_expires_unix_ms {int} NOT NULL DEFAULT 0",
           "ALTER TABLE jobs ADD COLUMN run {int} NOT NULL DEFAULT 0",
           "ALTER TABLE jobs ADD COLUMN cancel_requested {int} NOT NULL DEFAULT 0",
           "ALTER TABLE jobs ADD COLUMN checkpoint {blob}",
           "ALTER TABLE jobs ADD COLUMN events_expire_unix_ms {int} NOT NULL DEFAULT 0",
           "ALTER TABLE sites ADD COLUMN owner TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE sites ADD COLUMN state {int} NOT NULL DEFAULT 0",
           "ALTER TABLE sites ADD COLUMN outdoor_key TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE sites ADD COLUMN weather TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE sites ADD COLUMN upload_bytes {int} NOT NULL DEFAULT 0",
           "ALTER TABLE sites ADD COLUMN queue_order {int} NOT NULL DEFAULT 0",
           "ALTER TABLE sites ADD COLUMN lease_owner TEXT NOT NULL DEFAULT ''",
           "ALTER TABLE sites ADD COLUMN lease_expires_unix_ms {int} NOT NULL DEFAULT 0",
           "ALTER TABLE sites ADD COLUMN run {int} NOT NULL DEFAULT 0",
           "CREATE INDEX jobs_by_state ON jobs (state, queue_order)",
           "CREATE INDEX jobs_by_owner ON jobs (owner, number)",
           "CREATE INDEX sites_by_state ON sites (state, queue_order)",
           "CREATE INDEX jobs_by_events_expiry ON jobs (events_expire_unix_ms)",
           "CREATE TABLE turns (owner TEXT PRIMARY KEY, last_taken {int} NOT NULL)",
           "CREATE TABLE counters (name TEXT PRIMARY KEY, value {int} NOT NULL)",
           "INSERT INTO counters (name, value) VALUES ('turn', 0)",
           "CREATE TABLE weather (sha256 TEXT PRIMARY KEY, bytes {blob} NOT NULL)",
           "CREATE TABLE outdoor_matrices (matrix_key TEXT PRIMARY KEY, bytes {blob} NOT NULL, "
           "sha256 {blob} NOT NULL, created_unix_ms {int} NOT NULL)",
       },
       FillReplicaColumns},
      {3,
       "finished jobs' results in a column of their own, which listings do not read",
       {
           "ALTER TABLE jobs ADD COLUMN result {blob}",
           "ALTER TABLE quarantine ADD COLUMN result {blob}",
       },
       MoveResults},
  };
  return migrations;
}

absl::Status Migrate(Database& db, int* from, int* to) {
  const int newest = Migrations().back().version;
  int found = 0;
  absl::Status status = db.Transact({}, [&](SqlSession& s) -> absl::Status {
    if (absl::Status st = s.Lock(kMigrationLock); !st.ok()) return st;
    if (absl::Status st =
            s.Run(db.Sql("CREATE TABLE IF NOT EXISTS schema_version (version {int} NOT NULL)"))
                .status();
        !st.ok()) {
      return st;
    }
    absl::StatusOr<SqlResult> version =
        s.Run("SELECT CAST(COALESCE(MAX(version), 0) AS BIGINT) FROM schema_version");
    if (!version.ok()) return version.status();
    found = static_cast<int>(version->rows[0].Int(0));
    if (found > newest) {
      return absl::FailedPreconditionError(absl::StrCat(
          "the store's schema is version ", found, ", newer than this fenestrad knows (", newest,
          "): a newer fenestrad wrote it; run that version, or a newer one"));
    }
    for (const Migration& m : Migrations()) {
      if (m.version <= found) continue;
      for (const char* statement : m.statements) {
        if (absl::Status st = s.Run(db.Sql(statement)).status(); !st.ok()) return st;
      }
      if (m.code) {
        if (absl::Status st = m.code(db, s); !st.ok()) return st;
      }
      spdlog::info("store {}: schema version {} ({})", db.Describe(), m.version, m.what);
    }
    if (found == newest) return absl::OkStatus();
    if (absl::Status st = s.Run("DELETE FROM schema_version").status(); !st.ok()) return st;
    return s.Run("INSERT INTO schema_version (version) VALUES (?)", {int64_t{newest}}).status();
  });
  if (from) *from = found;
  if (to) *to = status.ok() ? newest : found;
  return status;
}

}  // namespace fenestra
