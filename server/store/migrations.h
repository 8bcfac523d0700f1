#pragma once

// The store's schema, as one list of versioned migrations for both databases: each is SQL
// with the dialects' differences as Database::Sql placeholders, and, where rows must be
// rewritten from their stored protobufs, code. The version reached is kept in the
// schema_version table.
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "server/store/database.h"

namespace fenestra {

struct Migration {
  int version;
  const char* what;  // one line, for the log
  std::vector<const char*> statements;
  // Run after the statements in the same transaction, or null.
  absl::Status (*code)(const Database& db, SqlSession& session);
};

// Rows the store reads at once when it scans or rewrites a table.
inline constexpr int64_t kRowsPerRead = 64;

// The stored weather reference of a path of the data directory's weather folder
// (".../weather/<sha256>.epw"): its name without extension, the content's SHA-256 ("" for
// an empty path).
std::string WeatherOfPath(const std::string& path);

// Every migration, oldest first; the last one's version is the schema this binary writes.
const std::vector<Migration>& Migrations();

// Brings `db` to the newest schema in one transaction (PostgreSQL: under a lock, so
// replicas starting together migrate once): a file or database without a schema_version
// table is version 0 (or, SQLite, the tables of fenestrad before versions: version 1's
// CREATE TABLE IF NOT EXISTS keeps them). FailedPrecondition naming both versions when
// the database's schema is newer than this binary knows. `from` and `to` get the versions.
absl::Status Migrate(Database& db, int* from = nullptr, int* to = nullptr);

}  // namespace fenestra
