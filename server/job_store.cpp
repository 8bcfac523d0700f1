#include "server/job_store.h"

#include <sqlite3.h>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

// A prepared statement that finalizes itself.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    status_ = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr);
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement& Bind(int i, const std::string& text) {
    if (status_ == SQLITE_OK) {
      status_ =
          sqlite3_bind_blob(stmt_, i, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT);
    }
    return *this;
  }
  Statement& BindText(int i, const std::string& text) {
    if (status_ == SQLITE_OK) {
      status_ =
          sqlite3_bind_text(stmt_, i, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT);
    }
    return *this;
  }
  Statement& Bind(int i, int64_t value) {
    if (status_ == SQLITE_OK) status_ = sqlite3_bind_int64(stmt_, i, value);
    return *this;
  }
  // SQLITE_ROW, SQLITE_DONE or an error code.
  int Step() {
    if (status_ != SQLITE_OK && status_ != SQLITE_ROW) return status_;
    status_ = sqlite3_step(stmt_);
    return status_;
  }
  absl::Status Run() {
    const int rc = Step();
    return rc == SQLITE_DONE || rc == SQLITE_ROW ? absl::OkStatus() : Error();
  }
  absl::Status Error() const {
    return absl::InternalError(absl::StrCat("job store: ", sqlite3_errmsg(db_)));
  }
  std::string Blob(int column) const {
    const void* data = sqlite3_column_blob(stmt_, column);
    return std::string(static_cast<const char*>(data), sqlite3_column_bytes(stmt_, column));
  }
  int64_t Int(int column) const { return sqlite3_column_int64(stmt_, column); }

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  int status_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<JobStore>> JobStore::Open(const std::string& path) {
  sqlite3* db = nullptr;
  const int rc =
      sqlite3_open_v2(path.c_str(), &db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX, nullptr);
  if (rc != SQLITE_OK) {
    std::string message = db ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
    sqlite3_close(db);
    return absl::InternalError(absl::StrCat(path, ": cannot open the job store: ", message));
  }
  std::unique_ptr<JobStore> store(new JobStore(db));
  sqlite3_busy_timeout(db, 5000);
  for (const char* sql : {
           "PRAGMA journal_mode=WAL",
           "PRAGMA synchronous=NORMAL",
           "CREATE TABLE IF NOT EXISTS jobs (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "id TEXT UNIQUE, info BLOB NOT NULL, job BLOB NOT NULL)",
           "CREATE TABLE IF NOT EXISTS job_events (job_id TEXT NOT NULL, sequence INTEGER NOT "
           "NULL, event BLOB NOT NULL, PRIMARY KEY (job_id, sequence))",
           "CREATE TABLE IF NOT EXISTS sites (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "id TEXT UNIQUE, info BLOB NOT NULL, weather_path TEXT NOT NULL)",
           "CREATE TABLE IF NOT EXISTS users (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "name TEXT UNIQUE NOT NULL, token_sha256 BLOB NOT NULL, admin INTEGER NOT NULL, "
           "created_unix_ms INTEGER NOT NULL, revoked_unix_ms INTEGER NOT NULL DEFAULT 0)",
       }) {
    if (absl::Status s = store->Exec(sql); !s.ok()) {
      return absl::InternalError(absl::StrCat(path, ": ", s.message()));
    }
  }
  return store;
}

JobStore::~JobStore() { sqlite3_close(db_); }

absl::Status JobStore::Exec(const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    absl::Status status = absl::InternalError(absl::StrCat("job store: ", error ? error : "?"));
    sqlite3_free(error);
    return status;
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> JobStore::InsertJob(v1::JobInfo& info, const v1::Job& job) {
  std::lock_guard lock(mutex_);
  Statement insert(db_, "INSERT INTO jobs (info, job) VALUES (x'', ?)");
  if (absl::Status s = insert.Bind(1, job.SerializeAsString()).Run(); !s.ok()) return s;
  const int64_t number = sqlite3_last_insert_rowid(db_);
  info.set_id(absl::StrCat("job-", number));
  Statement update(db_, "UPDATE jobs SET id = ?, info = ? WHERE number = ?");
  if (absl::Status s =
          update.BindText(1, info.id()).Bind(2, info.SerializeAsString()).Bind(3, number).Run();
      !s.ok()) {
    return s;
  }
  return info.id();
}

absl::Status JobStore::UpdateJob(const v1::JobInfo& info) {
  std::lock_guard lock(mutex_);
  return Statement(db_, "UPDATE jobs SET info = ? WHERE id = ?")
      .Bind(1, info.SerializeAsString())
      .BindText(2, info.id())
      .Run();
}

absl::Status JobStore::DeleteJob(const std::string& id) {
  std::lock_guard lock(mutex_);
  if (absl::Status s =
          Statement(db_, "DELETE FROM job_events WHERE job_id = ?").BindText(1, id).Run();
      !s.ok()) {
    return s;
  }
  return Statement(db_, "DELETE FROM jobs WHERE id = ?").BindText(1, id).Run();
}

absl::Status JobStore::AppendEvent(const std::string& id, const v1::JobEvent& event) {
  std::lock_guard lock(mutex_);
  return Statement(db_, "INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)")
      .BindText(1, id)
      .Bind(2, event.sequence())
      .Bind(3, event.SerializeAsString())
      .Run();
}

absl::StatusOr<std::vector<JobStore::StoredJob>> JobStore::LoadJobs() {
  std::lock_guard lock(mutex_);
  std::vector<StoredJob> jobs;
  Statement select(db_,
                   "SELECT j.info, j.job, (SELECT MAX(sequence) FROM job_events e WHERE "
                   "e.job_id = j.id) FROM jobs j WHERE j.id IS NOT NULL ORDER BY j.number");
  int rc;
  while ((rc = select.Step()) == SQLITE_ROW) {
    StoredJob job;
    if (!job.info.ParseFromString(select.Blob(0)) || !job.job.ParseFromString(select.Blob(1))) {
      return absl::DataLossError("job store: a job record does not parse");
    }
    job.info.set_last_sequence(std::max(job.info.last_sequence(), select.Int(2)));
    jobs.push_back(std::move(job));
  }
  if (rc != SQLITE_DONE) return select.Error();
  return jobs;
}

absl::StatusOr<std::vector<v1::JobEvent>> JobStore::LoadEvents(const std::string& id) {
  std::lock_guard lock(mutex_);
  std::vector<v1::JobEvent> events;
  Statement select(db_, "SELECT event FROM job_events WHERE job_id = ? ORDER BY sequence");
  select.BindText(1, id);
  int rc;
  while ((rc = select.Step()) == SQLITE_ROW) {
    v1::JobEvent event;
    if (!event.ParseFromString(select.Blob(0))) {
      return absl::DataLossError("job store: an event record does not parse");
    }
    events.push_back(std::move(event));
  }
  if (rc != SQLITE_DONE) return select.Error();
  return events;
}

absl::StatusOr<std::string> JobStore::InsertSite(v1::SiteInfo& info,
                                                 const std::string& weather_path) {
  std::lock_guard lock(mutex_);
  Statement insert(db_, "INSERT INTO sites (info, weather_path) VALUES (x'', ?)");
  if (absl::Status s = insert.BindText(1, weather_path).Run(); !s.ok()) return s;
  const int64_t number = sqlite3_last_insert_rowid(db_);
  info.set_id(absl::StrCat("site-", number));
  Statement update(db_, "UPDATE sites SET id = ?, info = ? WHERE number = ?");
  if (absl::Status s =
          update.BindText(1, info.id()).Bind(2, info.SerializeAsString()).Bind(3, number).Run();
      !s.ok()) {
    return s;
  }
  return info.id();
}

absl::Status JobStore::UpdateSite(const v1::SiteInfo& info) {
  std::lock_guard lock(mutex_);
  return Statement(db_, "UPDATE sites SET info = ? WHERE id = ?")
      .Bind(1, info.SerializeAsString())
      .BindText(2, info.id())
      .Run();
}

absl::Status JobStore::DeleteSite(const std::string& id) {
  std::lock_guard lock(mutex_);
  return Statement(db_, "DELETE FROM sites WHERE id = ?").BindText(1, id).Run();
}

absl::StatusOr<std::vector<JobStore::StoredSite>> JobStore::LoadSites() {
  std::lock_guard lock(mutex_);
  std::vector<StoredSite> sites;
  Statement select(db_,
                   "SELECT info, weather_path FROM sites WHERE id IS NOT NULL ORDER BY number");
  int rc;
  while ((rc = select.Step()) == SQLITE_ROW) {
    StoredSite site;
    if (!site.info.ParseFromString(select.Blob(0))) {
      return absl::DataLossError("job store: a site record does not parse");
    }
    site.weather_path = select.Blob(1);
    sites.push_back(std::move(site));
  }
  if (rc != SQLITE_DONE) return select.Error();
  return sites;
}

absl::Status JobStore::InsertUser(const UserRecord& user) {
  std::lock_guard lock(mutex_);
  Statement insert(db_,
                   "INSERT INTO users (name, token_sha256, admin, created_unix_ms, "
                   "revoked_unix_ms) VALUES (?, ?, ?, ?, ?)");
  const int rc = insert.BindText(1, user.name)
                     .Bind(2, user.token_sha256)
                     .Bind(3, int64_t{user.admin})
                     .Bind(4, user.created_unix_ms)
                     .Bind(5, user.revoked_unix_ms)
                     .Step();
  if (rc == SQLITE_CONSTRAINT) {
    return absl::AlreadyExistsError(absl::StrCat("user '", user.name, "' exists"));
  }
  return rc == SQLITE_DONE ? absl::OkStatus() : insert.Error();
}

absl::StatusOr<std::vector<UserRecord>> JobStore::LoadUsers() {
  std::lock_guard lock(mutex_);
  std::vector<UserRecord> users;
  Statement select(db_,
                   "SELECT name, token_sha256, admin, created_unix_ms, revoked_unix_ms FROM users "
                   "ORDER BY number");
  int rc;
  while ((rc = select.Step()) == SQLITE_ROW) {
    users.push_back(UserRecord{select.Blob(0), select.Blob(1), select.Int(2) != 0, select.Int(3),
                               select.Int(4)});
  }
  if (rc != SQLITE_DONE) return select.Error();
  return users;
}

absl::Status JobStore::RevokeUser(const std::string& name, int64_t unix_ms) {
  std::lock_guard lock(mutex_);
  Statement update(db_,
                   "UPDATE users SET revoked_unix_ms = CASE WHEN revoked_unix_ms = 0 THEN ? ELSE "
                   "revoked_unix_ms END WHERE name = ?");
  if (absl::Status s = update.Bind(1, unix_ms).BindText(2, name).Run(); !s.ok()) return s;
  if (sqlite3_changes(db_) == 0) {
    return absl::NotFoundError(absl::StrCat("no user '", name, "'"));
  }
  return absl::OkStatus();
}

}  // namespace fenestra
