#include "server/job_store.h"

#include <sqlite3.h>

#include <chrono>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "server/data_dir.h"

namespace fenestra {
namespace {

// What a failed SQLite call means for a client: a full disk, or an internal failure.
absl::Status StoreError(sqlite3* db) {
  const int code = sqlite3_extended_errcode(db);
  if ((code & 0xff) == SQLITE_FULL ||
      ((code & 0xff) == SQLITE_IOERR && IsStorageFullErrno(sqlite3_system_errno(db)))) {
    return StorageFullError();
  }
  return absl::InternalError(absl::StrCat("the server's job store failed: ", sqlite3_errmsg(db)));
}

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A prepared statement that finalizes itself. Bound text and blobs are not copied: they
// must outlive the statement's steps.
class Statement {
 public:
  Statement(sqlite3* db, const char* sql) : db_(db) {
    status_ = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr);
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement& Bind(int i, std::string_view blob) {
    if (status_ == SQLITE_OK) {
      status_ = sqlite3_bind_blob64(stmt_, i, blob.data(), blob.size(), SQLITE_STATIC);
    }
    return *this;
  }
  Statement& BindText(int i, std::string_view text) {
    if (status_ == SQLITE_OK) {
      status_ = sqlite3_bind_text64(stmt_, i, text.data(), text.size(), SQLITE_STATIC, SQLITE_UTF8);
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
    return rc == SQLITE_DONE || rc == SQLITE_ROW ? absl::OkStatus() : StoreError(db_);
  }
  absl::Status Error() const { return StoreError(db_); }
  // A column's bytes, valid until the next step.
  std::string_view Blob(int column) const {
    const void* data = sqlite3_column_blob(stmt_, column);
    return {static_cast<const char*>(data),
            static_cast<size_t>(sqlite3_column_bytes(stmt_, column))};
  }
  std::string Text(int column) const { return std::string(Blob(column)); }
  int64_t Int(int column) const { return sqlite3_column_int64(stmt_, column); }

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  int status_;
};

template <typename Message>
bool Parse(Message& message, std::string_view bytes) {
  return message.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
}

}  // namespace

absl::StatusOr<std::unique_ptr<JobStore>> JobStore::Open(const std::string& path, Sharing sharing) {
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
  std::unique_ptr<JobStore> store(new JobStore(db));
  sqlite3_extended_result_codes(db, 1);
  if (sqlite3_db_readonly(db, "main") == 1) {
    return absl::FailedPreconditionError(
        absl::StrCat(path, ": the job store is read-only (not writable)"));
  }
  sqlite3_busy_timeout(db, 500);
  // Exclusive: a lock held from the first access keeps other processes out and the WAL
  // index in memory (no -shm file, so a full disk still lets it read)
  for (const char* sql : {
           sharing == Sharing::kExclusive ? "PRAGMA locking_mode=EXCLUSIVE"
                                          : "PRAGMA locking_mode=NORMAL",
           "PRAGMA journal_mode=WAL",
           "PRAGMA synchronous=NORMAL",
           "CREATE TABLE IF NOT EXISTS jobs (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "id TEXT UNIQUE, info BLOB NOT NULL, job BLOB NOT NULL)",
           "CREATE TABLE IF NOT EXISTS job_events (job_id TEXT NOT NULL, sequence INTEGER NOT "
           "NULL, event BLOB NOT NULL, PRIMARY KEY (job_id, sequence))",
           "CREATE TABLE IF NOT EXISTS sites (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "id TEXT UNIQUE, info BLOB NOT NULL, weather_path TEXT NOT NULL, scene BLOB)",
           "CREATE TABLE IF NOT EXISTS users (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "name TEXT UNIQUE NOT NULL, token_sha256 BLOB NOT NULL, admin INTEGER NOT NULL, "
           "created_unix_ms INTEGER NOT NULL, revoked_unix_ms INTEGER NOT NULL DEFAULT 0)",
           "CREATE TABLE IF NOT EXISTS quarantine (number INTEGER PRIMARY KEY AUTOINCREMENT, "
           "source TEXT NOT NULL, id TEXT, reason TEXT NOT NULL, info BLOB, body BLOB, "
           "weather_path TEXT, quarantined_unix_ms INTEGER NOT NULL)",
       }) {
    std::lock_guard lock(store->mutex_);
    if (absl::Status s = store->Exec(sql); !s.ok()) {
      if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_BUSY) {
        return absl::FailedPreconditionError(
            absl::StrCat(path,
                         ": the job store is in use by another process (another fenestrad "
                         "on this data directory?)"));
      }
      return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
    }
  }
  // Sites stored before scenes had their own column keep them inside info
  std::lock_guard lock(store->mutex_);
  if (Statement(db, "SELECT scene FROM sites LIMIT 0").Step() != SQLITE_DONE) {
    if (absl::Status s = store->Exec("ALTER TABLE sites ADD COLUMN scene BLOB"); !s.ok()) {
      return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
    }
  }
  return store;
}

JobStore::~JobStore() { sqlite3_close(db_); }

absl::Status JobStore::Exec(const char* sql) {
  return sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) == SQLITE_OK ? absl::OkStatus()
                                                                        : StoreError(db_);
}

template <typename Body>
absl::Status JobStore::Transaction(bool durable, Body&& body) {
  if (durable) (void)Exec("PRAGMA synchronous=FULL");
  absl::Status status = Exec("BEGIN IMMEDIATE");
  if (status.ok()) status = body();
  if (status.ok()) status = Exec("COMMIT");
  if (!status.ok() && !sqlite3_get_autocommit(db_)) (void)Exec("ROLLBACK");
  if (durable) (void)Exec("PRAGMA synchronous=NORMAL");
  return status;
}

absl::StatusOr<std::string> JobStore::InsertJob(v1::JobInfo& info, const v1::Job& job,
                                                const v1::JobEvent* first_event) {
  std::lock_guard lock(mutex_);
  const std::string job_bytes = job.SerializeAsString();
  v1::JobInfo stored = info;
  absl::Status status = Transaction(/*durable=*/true, [&]() -> absl::Status {
    if (absl::Status s =
            Statement(db_, "INSERT INTO jobs (info, job) VALUES (x'', ?)").Bind(1, job_bytes).Run();
        !s.ok()) {
      return s;
    }
    const int64_t number = sqlite3_last_insert_rowid(db_);
    stored.set_id(absl::StrCat("job-", number));
    const std::string info_bytes = stored.SerializeAsString();
    if (absl::Status s = Statement(db_, "UPDATE jobs SET id = ?, info = ? WHERE number = ?")
                             .BindText(1, stored.id())
                             .Bind(2, info_bytes)
                             .Bind(3, number)
                             .Run();
        !s.ok() || !first_event) {
      return s;
    }
    const std::string event_bytes = first_event->SerializeAsString();
    return Statement(db_, "INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)")
        .BindText(1, stored.id())
        .Bind(2, first_event->sequence())
        .Bind(3, event_bytes)
        .Run();
  });
  if (!status.ok()) return status;
  info.set_id(stored.id());
  return info.id();
}

absl::Status JobStore::UpdateJob(const v1::JobInfo& info, const v1::JobEvent* event, bool durable) {
  std::lock_guard lock(mutex_);
  const std::string info_bytes = info.SerializeAsString();
  const std::string event_bytes = event ? event->SerializeAsString() : "";
  return Transaction(durable, [&]() -> absl::Status {
    if (absl::Status s = Statement(db_, "UPDATE jobs SET info = ? WHERE id = ?")
                             .Bind(1, info_bytes)
                             .BindText(2, info.id())
                             .Run();
        !s.ok() || !event) {
      return s;
    }
    return Statement(db_, "INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)")
        .BindText(1, info.id())
        .Bind(2, event->sequence())
        .Bind(3, event_bytes)
        .Run();
  });
}

absl::Status JobStore::FinishJob(const v1::JobInfo& info, const v1::JobEvent& event) {
  std::lock_guard lock(mutex_);
  const std::string info_bytes = info.SerializeAsString();
  const std::string event_bytes = event.SerializeAsString();
  return Transaction(/*durable=*/true, [&]() -> absl::Status {
    if (absl::Status s = Statement(db_, "UPDATE jobs SET info = ? WHERE id = ?")
                             .Bind(1, info_bytes)
                             .BindText(2, info.id())
                             .Run();
        !s.ok()) {
      return s;
    }
    if (absl::Status s =
            Statement(db_, "DELETE FROM job_events WHERE job_id = ?").BindText(1, info.id()).Run();
        !s.ok()) {
      return s;
    }
    return Statement(db_, "INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)")
        .BindText(1, info.id())
        .Bind(2, event.sequence())
        .Bind(3, event_bytes)
        .Run();
  });
}

absl::Status JobStore::DeleteJob(const std::string& id) {
  std::lock_guard lock(mutex_);
  return Transaction(/*durable=*/true, [&]() -> absl::Status {
    if (absl::Status s =
            Statement(db_, "DELETE FROM job_events WHERE job_id = ?").BindText(1, id).Run();
        !s.ok()) {
      return s;
    }
    return Statement(db_, "DELETE FROM jobs WHERE id = ?").BindText(1, id).Run();
  });
}

absl::Status JobStore::AppendEvent(const std::string& id, const v1::JobEvent& event) {
  std::lock_guard lock(mutex_);
  const std::string event_bytes = event.SerializeAsString();
  return Statement(db_, "INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)")
      .BindText(1, id)
      .Bind(2, event.sequence())
      .Bind(3, event_bytes)
      .Run();
}

absl::StatusOr<JobStore::StoredJobs> JobStore::LoadJobs() {
  std::lock_guard lock(mutex_);
  StoredJobs stored;
  std::vector<std::pair<int64_t, Quarantined>> bad;
  {
    Statement select(db_,
                     "SELECT j.number, j.id, j.info, (SELECT MAX(sequence) FROM job_events e "
                     "WHERE e.job_id = j.id) FROM jobs j WHERE j.id IS NOT NULL ORDER BY j.number");
    int rc;
    while ((rc = select.Step()) == SQLITE_ROW) {
      v1::JobInfo info;
      const std::string id = select.Text(1);
      if (!Parse(info, select.Blob(2))) {
        bad.push_back({select.Int(0), {id, "its JobInfo does not parse"}});
        continue;
      }
      if (info.id() != id) {
        bad.push_back({select.Int(0), {id, absl::StrCat("its JobInfo names another job")}});
        continue;
      }
      info.set_last_sequence(std::max(info.last_sequence(), select.Int(3)));
      stored.jobs.push_back(std::move(info));
    }
    if (rc != SQLITE_DONE) return select.Error();
  }
  for (auto& [number, record] : bad) {
    if (absl::Status s = QuarantineLocked("jobs", number, record.reason); !s.ok()) {
      absl::StrAppend(&record.reason, " (left in place: ", s.message(), ")");
    }
    stored.quarantined.push_back(std::move(record));
  }
  return stored;
}

absl::StatusOr<v1::Job> JobStore::LoadJob(const std::string& id) {
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT job FROM jobs WHERE id = ?");
  select.BindText(1, id);
  const int rc = select.Step();
  if (rc == SQLITE_DONE) return absl::NotFoundError(absl::StrCat("no job '", id, "' is stored"));
  if (rc != SQLITE_ROW) return select.Error();
  v1::Job job;
  if (!Parse(job, select.Blob(0))) {
    return absl::DataLossError(absl::StrCat("the stored job ", id, " does not parse"));
  }
  return job;
}

absl::StatusOr<std::vector<v1::JobEvent>> JobStore::LoadEvents(const std::string& id) {
  std::lock_guard lock(mutex_);
  std::vector<v1::JobEvent> events;
  Statement select(db_, "SELECT event FROM job_events WHERE job_id = ? ORDER BY sequence");
  select.BindText(1, id);
  int rc;
  while ((rc = select.Step()) == SQLITE_ROW) {
    v1::JobEvent event;
    if (Parse(event, select.Blob(0))) events.push_back(std::move(event));
  }
  if (rc != SQLITE_DONE) return select.Error();
  return events;
}

absl::StatusOr<std::string> JobStore::InsertSite(v1::SiteInfo& info,
                                                 const std::string& weather_path,
                                                 const v1::Scene& scene) {
  std::lock_guard lock(mutex_);
  const std::string scene_bytes = scene.SerializeAsString();
  v1::SiteInfo stored = info;
  stored.clear_scene();
  absl::Status status = Transaction(/*durable=*/true, [&]() -> absl::Status {
    if (absl::Status s =
            Statement(db_, "INSERT INTO sites (info, weather_path, scene) VALUES (x'', ?, ?)")
                .BindText(1, weather_path)
                .Bind(2, scene_bytes)
                .Run();
        !s.ok()) {
      return s;
    }
    const int64_t number = sqlite3_last_insert_rowid(db_);
    stored.set_id(absl::StrCat("site-", number));
    const std::string info_bytes = stored.SerializeAsString();
    return Statement(db_, "UPDATE sites SET id = ?, info = ? WHERE number = ?")
        .BindText(1, stored.id())
        .Bind(2, info_bytes)
        .Bind(3, number)
        .Run();
  });
  if (!status.ok()) return status;
  info.set_id(stored.id());
  return info.id();
}

absl::Status JobStore::UpdateSite(const v1::SiteInfo& info) {
  std::lock_guard lock(mutex_);
  v1::SiteInfo stored = info;
  stored.clear_scene();
  const std::string info_bytes = stored.SerializeAsString();
  return Transaction(/*durable=*/true, [&] {
    return Statement(db_, "UPDATE sites SET info = ? WHERE id = ?")
        .Bind(1, info_bytes)
        .BindText(2, info.id())
        .Run();
  });
}

absl::Status JobStore::DeleteSite(const std::string& id) {
  std::lock_guard lock(mutex_);
  return Transaction(/*durable=*/true, [&] {
    return Statement(db_, "DELETE FROM sites WHERE id = ?").BindText(1, id).Run();
  });
}

absl::StatusOr<JobStore::StoredSites> JobStore::LoadSites() {
  std::lock_guard lock(mutex_);
  StoredSites stored;
  std::vector<std::pair<int64_t, Quarantined>> bad;
  {
    Statement select(db_,
                     "SELECT number, id, info, weather_path FROM sites WHERE id IS NOT NULL "
                     "ORDER BY number");
    int rc;
    while ((rc = select.Step()) == SQLITE_ROW) {
      StoredSite site;
      const std::string id = select.Text(1);
      if (!Parse(site.info, select.Blob(2))) {
        bad.push_back({select.Int(0), {id, "its SiteInfo does not parse"}});
        continue;
      }
      if (site.info.id() != id) {
        bad.push_back({select.Int(0), {id, "its SiteInfo names another site"}});
        continue;
      }
      site.info.clear_scene();  // stored before scenes had their own column
      site.weather_path = select.Text(3);
      stored.sites.push_back(std::move(site));
    }
    if (rc != SQLITE_DONE) return select.Error();
  }
  for (auto& [number, record] : bad) {
    if (absl::Status s = QuarantineLocked("sites", number, record.reason); !s.ok()) {
      absl::StrAppend(&record.reason, " (left in place: ", s.message(), ")");
    }
    stored.quarantined.push_back(std::move(record));
  }
  return stored;
}

absl::StatusOr<v1::Scene> JobStore::LoadSiteScene(const std::string& id) {
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT scene, info FROM sites WHERE id = ?");
  select.BindText(1, id);
  const int rc = select.Step();
  if (rc == SQLITE_DONE) return absl::NotFoundError(absl::StrCat("no site '", id, "' is stored"));
  if (rc != SQLITE_ROW) return select.Error();
  v1::Scene scene;
  if (!select.Blob(0).empty()) {
    if (Parse(scene, select.Blob(0))) return scene;
  } else if (v1::SiteInfo info; Parse(info, select.Blob(1))) {
    return info.scene();  // stored before scenes had their own column
  }
  return absl::DataLossError(absl::StrCat("the stored scene of site ", id, " does not parse"));
}

absl::StatusOr<int64_t> JobStore::SiteSceneBytes(const std::string& id) {
  std::lock_guard lock(mutex_);
  Statement select(db_, "SELECT COALESCE(length(scene), length(info)) FROM sites WHERE id = ?");
  select.BindText(1, id);
  const int rc = select.Step();
  if (rc == SQLITE_DONE) return absl::NotFoundError(absl::StrCat("no site '", id, "' is stored"));
  if (rc != SQLITE_ROW) return select.Error();
  return select.Int(0);
}

absl::Status JobStore::Quarantine(const std::string& table, const std::string& id,
                                  const std::string& reason) {
  std::lock_guard lock(mutex_);
  const bool jobs = table == "jobs";
  Statement select(
      db_, jobs ? "SELECT number FROM jobs WHERE id = ?" : "SELECT number FROM sites WHERE id = ?");
  select.BindText(1, id);
  const int rc = select.Step();
  if (rc == SQLITE_DONE) return absl::OkStatus();
  if (rc != SQLITE_ROW) return select.Error();
  return QuarantineLocked(table, select.Int(0), reason);
}

absl::Status JobStore::QuarantineLocked(const std::string& table, int64_t number,
                                        const std::string& reason) {
  const bool jobs = table == "jobs";
  return Transaction(/*durable=*/true, [&]() -> absl::Status {
    if (absl::Status s =
            Statement(db_, jobs ? "INSERT INTO quarantine (source, id, reason, info, body, "
                                  "quarantined_unix_ms) SELECT 'jobs', id, ?, info, job, ? FROM "
                                  "jobs WHERE number = ?"
                                : "INSERT INTO quarantine (source, id, reason, info, body, "
                                  "weather_path, quarantined_unix_ms) SELECT 'sites', id, ?, "
                                  "info, scene, weather_path, ? FROM sites WHERE number = ?")
                .BindText(1, reason)
                .Bind(2, NowMs())
                .Bind(3, number)
                .Run();
        !s.ok()) {
      return s;
    }
    return Statement(db_, jobs ? "DELETE FROM jobs WHERE number = ?"
                               : "DELETE FROM sites WHERE number = ?")
        .Bind(1, number)
        .Run();
  });
}

absl::Status JobStore::InsertUser(const UserRecord& user) {
  std::lock_guard lock(mutex_);
  return Transaction(/*durable=*/true, [&]() -> absl::Status {
    Statement insert(db_,
                     "INSERT INTO users (name, token_sha256, admin, created_unix_ms, "
                     "revoked_unix_ms) VALUES (?, ?, ?, ?, ?)");
    const int rc = insert.BindText(1, user.name)
                       .Bind(2, user.token_sha256)
                       .Bind(3, int64_t{user.admin})
                       .Bind(4, user.created_unix_ms)
                       .Bind(5, user.revoked_unix_ms)
                       .Step();
    if ((rc & 0xff) == SQLITE_CONSTRAINT) {
      return absl::AlreadyExistsError(absl::StrCat("user '", user.name, "' exists"));
    }
    return rc == SQLITE_DONE ? absl::OkStatus() : insert.Error();
  });
}

absl::StatusOr<std::vector<UserRecord>> JobStore::LoadUsers() {
  std::lock_guard lock(mutex_);
  std::vector<UserRecord> users;
  Statement select(db_,
                   "SELECT name, token_sha256, admin, created_unix_ms, revoked_unix_ms FROM users "
                   "ORDER BY number");
  int rc;
  while ((rc = select.Step()) == SQLITE_ROW) {
    users.push_back(UserRecord{select.Text(0), select.Text(1), select.Int(2) != 0, select.Int(3),
                               select.Int(4)});
  }
  if (rc != SQLITE_DONE) return select.Error();
  return users;
}

absl::Status JobStore::RevokeUser(const std::string& name, int64_t unix_ms) {
  std::lock_guard lock(mutex_);
  return Transaction(/*durable=*/true, [&]() -> absl::Status {
    Statement update(db_,
                     "UPDATE users SET revoked_unix_ms = CASE WHEN revoked_unix_ms = 0 THEN ? "
                     "ELSE revoked_unix_ms END WHERE name = ?");
    if (absl::Status s = update.Bind(1, unix_ms).BindText(2, name).Run(); !s.ok()) return s;
    if (sqlite3_changes(db_) == 0) {
      return absl::NotFoundError(absl::StrCat("no user '", name, "'"));
    }
    return absl::OkStatus();
  });
}

}  // namespace fenestra
