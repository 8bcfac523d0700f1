// Store: copying everything into another store (fenestrad migrate).
#include <optional>
#include <span>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/status_macros.h"
#include "server/store/migrations.h"
#include "server/store/store.h"
#include "server/store/store_internal.h"

namespace fenestra {

// ---- Copying

namespace {

using store_internal::kQueued;
using store_internal::kRunning;
using store_internal::Placeholders;

// A table as CopyTo copies it: its columns ('i' integer, 't' text, 'b' bytes) and the
// leading columns that order its rows (unique together).
struct CopiedTable {
  const char* name;
  std::vector<std::pair<const char*, char>> columns;
  size_t key_columns;
};

const std::vector<CopiedTable>& CopiedTables() {
  static const std::vector<CopiedTable> tables = {
      {"users",
       {{"number", 'i'},
        {"name", 't'},
        {"token_sha256", 'b'},
        {"admin", 'i'},
        {"created_unix_ms", 'i'},
        {"revoked_unix_ms", 'i'}},
       1},
      {"sites",
       {{"number", 'i'},
        {"id", 't'},
        {"info", 'b'},
        {"weather_path", 't'},
        {"scene", 'b'},
        {"owner", 't'},
        {"state", 'i'},
        {"outdoor_key", 't'},
        {"weather", 't'},
        {"upload_bytes", 'i'},
        {"queue_order", 'i'},
        {"lease_owner", 't'},
        {"lease_expires_unix_ms", 'i'},
        {"run", 'i'}},
       1},
      {"jobs",
       {{"number", 'i'},
        {"id", 't'},
        {"info", 'b'},
        {"result", 'b'},
        {"job", 'b'},
        {"owner", 't'},
        {"state", 'i'},
        {"outdoor_key", 't'},
        {"weather", 't'},
        {"upload_bytes", 'i'},
        {"queue_order", 'i'},
        {"lease_owner", 't'},
        {"lease_expires_unix_ms", 'i'},
        {"run", 'i'},
        {"cancel_requested", 'i'},
        {"checkpoint", 'b'}},
       1},
      {"job_events", {{"job_id", 't'}, {"sequence", 'i'}, {"event", 'b'}}, 2},
      {"quarantine",
       {{"number", 'i'},
        {"source", 't'},
        {"id", 't'},
        {"reason", 't'},
        {"info", 'b'},
        {"result", 'b'},
        {"body", 'b'},
        {"weather_path", 't'},
        {"quarantined_unix_ms", 'i'}},
       1},
      {"turns", {{"owner", 't'}, {"last_taken", 'i'}}, 1},
      {"outdoor_matrices",
       {{"matrix_key", 't'}, {"bytes", 'b'}, {"sha256", 'b'}, {"created_unix_ms", 'i'}},
       1},
  };
  return tables;
}

// A cell read from one database as a parameter for the other.
SqlParam AsParam(const SqlRow& row, size_t column, char type, std::vector<std::string>& keep) {
  if (row.IsNull(column)) return nullptr;
  if (type == 'i') return row.Int(column);
  keep.push_back(row.Bytes(column));
  if (type == 't') return std::string_view(keep.back());
  return SqlBlob{keep.back()};
}

}  // namespace

absl::StatusOr<bool> Store::Empty() {
  bool empty = false;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT (SELECT COUNT(*) FROM users) + (SELECT COUNT(*) FROM jobs) + "
                       "(SELECT COUNT(*) FROM sites)"));
        empty = row.rows[0].Int(0) == 0;
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return empty;
}

namespace {

// Reads rows of `db` with one statement, in a transaction of their own.
absl::StatusOr<SqlResult> Read(Database& db, const std::string& sql,
                               std::span<const SqlParam> params = {}) {
  SqlResult rows;
  FENESTRA_RETURN_IF_ERROR(
      db.Transact({.write = false, .durable = false}, [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(read, s.Run(sql, params));
        rows = std::move(read);
        return absl::OkStatus();
      }));
  return rows;
}

// Copies `table` of `from` into the transaction `to`, in key order, a batch at a time; the
// rows copied.
absl::StatusOr<int64_t> CopyRows(Database& from, SqlSession& to, const CopiedTable& table) {
  std::vector<std::string> names;
  for (const auto& [name, type] : table.columns) names.push_back(name);
  const std::string columns = absl::StrJoin(names, ", ");
  const std::string key = absl::StrJoin(names.begin(), names.begin() + table.key_columns, ", ");
  const std::string insert = absl::StrCat("INSERT INTO ", table.name, " (", columns, ") VALUES ",
                                          Placeholders(names.size()));
  int64_t copied = 0;
  std::optional<SqlRow> last;
  while (true) {
    // The next rows after the last one copied
    std::vector<std::string> keep;
    std::vector<SqlParam> params;
    std::string select = absl::StrCat("SELECT ", columns, " FROM ", table.name);
    if (last) {
      absl::StrAppend(&select, " WHERE (", key, ") > ", Placeholders(table.key_columns));
      for (size_t c = 0; c < table.key_columns; ++c) {
        params.push_back(AsParam(*last, c, table.columns[c].second, keep));
      }
    }
    absl::StrAppend(&select, " ORDER BY ", key, " LIMIT ?");
    params.push_back(kRowsPerRead);
    FENESTRA_ASSIGN_OR_RETURN(rows, Read(from, select, params));
    if (rows.rows.empty()) return copied;
    for (const SqlRow& row : rows.rows) {
      std::vector<std::string> cells;
      cells.reserve(table.columns.size());
      std::vector<SqlParam> values;
      for (size_t c = 0; c < table.columns.size(); ++c) {
        values.push_back(AsParam(row, c, table.columns[c].second, cells));
      }
      FENESTRA_RETURN_IF_ERROR(to.Run(insert, values).status());
      ++copied;
    }
    last = std::move(rows.rows.back());
  }
}

// After the rows: the counters, PostgreSQL's sequences past the ids copied, and the leases
// ended, so that what was running is taken over by the target's replicas at once.
absl::Status FinishCopy(Database& from, const Database& to_db, SqlSession& to) {
  FENESTRA_ASSIGN_OR_RETURN(counters, Read(from, "SELECT name, value FROM counters"));
  for (const SqlRow& row : counters.rows) {
    FENESTRA_RETURN_IF_ERROR(to.Run("INSERT INTO counters (name, value) VALUES (?, ?) ON CONFLICT "
                                    "(name) DO UPDATE SET value = excluded.value",
                                    {row.Bytes(0), row.Int(1)})
                                 .status());
  }
  if (to_db.dialect() == Dialect::kPostgres) {
    for (const char* table : {"users", "sites", "jobs", "quarantine"}) {
      FENESTRA_RETURN_IF_ERROR(
          to.Run(absl::StrCat("SELECT setval(pg_get_serial_sequence('", table,
                              "', 'number'), (SELECT COALESCE(MAX(number), 0) + 1 FROM ", table,
                              "), false)"))
              .status());
    }
  }
  FENESTRA_RETURN_IF_ERROR(to.Run("UPDATE jobs SET lease_expires_unix_ms = 0").status());
  return to.Run("UPDATE sites SET lease_expires_unix_ms = 0").status();
}

}  // namespace

absl::Status Store::CopyTo(Store& target, bool overwrite,
                           const std::function<void(const std::string&)>& progress) {
  if (target.weather_files_) {
    return absl::FailedPreconditionError("copies go into a PostgreSQL store, not into SQLite");
  }
  FENESTRA_ASSIGN_OR_RETURN(empty, target.Empty());
  if (!empty && !overwrite) {
    return absl::FailedPreconditionError(
        "the target store already holds users, jobs or sites; copy into an empty database, or "
        "give --overwrite to replace what it holds");
  }
  // The weather files sites and unfinished jobs use (terminal jobs' files are gone)
  FENESTRA_ASSIGN_OR_RETURN(
      weather, Read(*db_, absl::StrCat("SELECT weather FROM sites WHERE weather <> '' UNION SELECT "
                                       "weather FROM jobs WHERE weather <> '' AND state IN (",
                                       kQueued, ", ", kRunning, ")")));
  return target.Transact([&](SqlSession& t) -> absl::Status {
    if (overwrite) {
      for (const char* table : {"job_events", "jobs", "sites", "users", "quarantine", "turns",
                                "weather", "outdoor_matrices"}) {
        FENESTRA_RETURN_IF_ERROR(t.Run(absl::StrCat("DELETE FROM ", table)).status());
      }
      FENESTRA_RETURN_IF_ERROR(t.Run("UPDATE counters SET value = 0").status());
    }
    for (const CopiedTable& table : CopiedTables()) {
      FENESTRA_ASSIGN_OR_RETURN(copied, CopyRows(*db_, t, table));
      if (progress) progress(absl::StrCat(table.name, ": ", copied, " rows"));
    }
    FENESTRA_RETURN_IF_ERROR(FinishCopy(*db_, *target.db_, t));
    for (const SqlRow& row : weather.rows) {
      FENESTRA_ASSIGN_OR_RETURN(bytes, ReadWeather(row.Bytes(0)));
      FENESTRA_RETURN_IF_ERROR(target.PutWeather(t, bytes).status());
    }
    if (progress) progress(absl::StrCat("weather: ", weather.rows.size(), " files"));
    return t.Notify();
  });
}

}  // namespace fenestra
