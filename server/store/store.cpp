#include "server/store/store.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/status_macros.h"
#include "server/checksum.h"
#include "server/data_dir.h"
#include "server/store/migrations.h"
#include "server/store/postgres_database.h"
#include "server/store/sqlite_database.h"

namespace fenestra {
namespace {

// The lock every admission (a job or site stored against the limits) and every removal
// of a weather file takes, so that counts and references are read as they stand.
constexpr int64_t kAdmissionLock = 1;
// Keys of matrices a replica holds that a claim prefers, at most.
constexpr size_t kMaxPreferredKeys = 32;
// Jobs a claim reads in order before it locks the first free one.
constexpr int64_t kClaimCandidates = 16;
constexpr int64_t kQueued = v1::JOB_STATE_QUEUED;
constexpr int64_t kRunning = v1::JOB_STATE_RUNNING;
constexpr int64_t kComputing = v1::SITE_STATE_COMPUTING;

template <typename Message>
bool Parse(Message& message, const std::string& bytes) {
  return message.ParseFromString(bytes);
}

SqlBlob Blob(const std::string& bytes) { return SqlBlob{bytes}; }
// A blob of no bytes (not NULL).
constexpr SqlBlob kNoBytes{std::string_view("", 0)};

absl::Status NoJob(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no job '", id, "' is stored"));
}
absl::Status NoSite(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no site '", id, "' is stored"));
}

std::string WeatherFileName(const std::string& weather) { return weather + ".epw"; }

// `(?, ?, ...)` for `n` values.
std::string Placeholders(size_t n) {
  std::string out = "(";
  for (size_t i = 0; i < n; ++i) absl::StrAppend(&out, i ? ", ?" : "?");
  return out + ")";
}

// A waiting task, as QueuePositions orders them.
struct Waiting {
  std::string id;
  std::string owner;
  int64_t order = 0;
  bool is_job = false;
};

// The order in which workers take `tasks` (oldest first) when each free worker takes the
// oldest task of the user served least recently (`last_taken`: larger = more recent; a
// user never served first): indices into `tasks`.
std::vector<size_t> TakingOrder(const std::vector<Waiting>& tasks,
                                std::map<std::string, int64_t> last_taken) {
  std::map<std::string, std::deque<size_t>> waiting;
  for (size_t i = 0; i < tasks.size(); ++i) waiting[tasks[i].owner].push_back(i);
  int64_t takes = 0;
  for (const auto& [owner, taken] : last_taken) takes = std::max(takes, taken);
  std::vector<size_t> order;
  while (!waiting.empty()) {
    auto next = waiting.begin();
    for (auto it = waiting.begin(); it != waiting.end(); ++it) {
      if (std::pair(last_taken[it->first], it->second.front()) <
          std::pair(last_taken[next->first], next->second.front())) {
        next = it;
      }
    }
    order.push_back(next->second.front());
    next->second.pop_front();
    last_taken[next->first] = ++takes;
    if (next->second.empty()) waiting.erase(next);
  }
  return order;
}

}  // namespace

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

// ---- Jobs

absl::StatusOr<std::string> Store::PutWeather(SqlSession& s, std::string_view bytes) {
  const std::string sha = Sha256Hex(bytes);
  FENESTRA_RETURN_IF_ERROR(
      s.Run("INSERT INTO weather (sha256, bytes) VALUES (?, ?) ON CONFLICT (sha256) DO NOTHING",
            {sha, SqlBlob{bytes}})
          .status());
  return sha;
}

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

}  // namespace

absl::StatusOr<v1::JobInfo> Store::InsertJob(NewJob job, const v1::Limits& limits) {
  v1::JobInfo info = std::move(job.info);
  // SQLite: the upload is a file, written and counted before the transaction; the count
  // is the job's once it is stored
  std::vector<std::string> counted;
  bool stored = false;
  absl::Cleanup uncount = [&] {
    if (!stored) {
      for (const std::string& name : counted) weather_files_->Unref(name);
    }
  };
  std::string weather;
  if (weather_files_ && !job.weather_epw.empty()) {
    FENESTRA_ASSIGN_OR_RETURN(path, weather_files_->Add(job.weather_epw));
    weather = WeatherOfPath(path);
    counted.push_back(WeatherFileName(weather));
  }
  FENESTRA_RETURN_IF_ERROR(Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(s.Lock(kAdmissionLock));
    FENESTRA_ASSIGN_OR_RETURN(
        queued, s.Run("SELECT COUNT(*), CAST(COALESCE(SUM(CASE WHEN owner = ? THEN 1 ELSE 0 END), "
                      "0) AS BIGINT) FROM jobs WHERE state = ?",
                      {info.owner(), kQueued}));
    const int64_t waiting = queued.rows[0].Int(0), owned = queued.rows[0].Int(1);
    if (waiting >= limits.max_queued_jobs()) {
      return absl::ResourceExhaustedError(absl::StrCat(
          "the job queue is full: ", waiting, " jobs wait (this server's limit max_queued_jobs = ",
          limits.max_queued_jobs(), "); try again later"));
    }
    if (owned >= limits.max_queued_jobs_per_user()) {
      return absl::ResourceExhaustedError(absl::StrCat(
          "limits.max_queued_jobs_per_user (", limits.max_queued_jobs_per_user(), ") reached: ",
          owned, " of your jobs wait; submit more when one has started, or cancel one"));
    }
    FENESTRA_RETURN_IF_ERROR(CheckUploadQuota(s, info.owner(), info.upload_bytes(), limits));

    // The weather file: the upload, or the site's
    if (!job.weather_epw.empty() && !weather_files_) {
      FENESTRA_ASSIGN_OR_RETURN(sha, PutWeather(s, job.weather_epw));
      weather = sha;
    } else if (job.weather_epw.empty()) {
      FENESTRA_ASSIGN_OR_RETURN(site,
                                s.Run("SELECT weather FROM sites WHERE id = ?", {info.site_id()}));
      if (site.rows.empty()) {
        return absl::NotFoundError(absl::StrCat("no site '", info.site_id(), "' any more"));
      }
      weather = site.rows[0].Bytes(0);
      if (weather_files_ && !weather.empty()) {
        weather_files_->Ref(WeatherFileName(weather));
        counted.push_back(WeatherFileName(weather));
      }
    }
    job.job.set_weather_file(weather);

    FENESTRA_ASSIGN_OR_RETURN(order, NextCounter(s, "queue"));
    const std::string job_bytes = job.job.SerializeAsString();
    FENESTRA_ASSIGN_OR_RETURN(
        inserted,
        s.Run("INSERT INTO jobs (info, job, owner, state, outdoor_key, weather, upload_bytes, "
              "queue_order) VALUES (?, ?, ?, ?, ?, ?, ?, ?) RETURNING number",
              {kNoBytes, Blob(job_bytes), info.owner(), kQueued, info.outdoor_key(), weather,
               info.upload_bytes(), order}));
    const int64_t number = inserted.rows[0].Int(0);
    info.set_id(absl::StrCat("job-", number));
    info.set_state(v1::JOB_STATE_QUEUED);
    info.set_last_sequence(1);
    const std::string info_bytes = info.SerializeAsString();
    FENESTRA_RETURN_IF_ERROR(s.Run("UPDATE jobs SET id = ?, info = ? WHERE number = ?",
                                   {info.id(), Blob(info_bytes), number})
                                 .status());
    v1::JobEvent event;
    event.set_sequence(1);
    event.set_time_unix_ms(info.created_unix_ms());
    event.set_queued(static_cast<int32_t>(waiting));
    const std::string event_bytes = event.SerializeAsString();
    FENESTRA_RETURN_IF_ERROR(
        s.Run("INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)",
              {info.id(), int64_t{1}, Blob(event_bytes)})
            .status());
    return s.Notify();
  }));
  stored = true;
  return info;
}

absl::StatusOr<std::map<std::string, int>> Store::QueuePositions(SqlSession& s) {
  FENESTRA_ASSIGN_OR_RETURN(
      rows,
      s.Run(Sql("SELECT id, owner, queue_order, 1 FROM jobs WHERE state = ? UNION ALL SELECT id, "
                "owner, queue_order, 0 FROM sites WHERE state = ? AND lease_expires_unix_ms < "
                "{now}"),
            {kQueued, kComputing}));
  std::vector<Waiting> tasks;
  for (const SqlRow& row : rows.rows) {
    tasks.push_back(Waiting{row.Bytes(0), row.Bytes(1), row.Int(2), row.Int(3) != 0});
  }
  std::sort(tasks.begin(), tasks.end(),
            [](const Waiting& a, const Waiting& b) { return a.order < b.order; });
  FENESTRA_ASSIGN_OR_RETURN(turns, s.Run("SELECT owner, last_taken FROM turns"));
  std::map<std::string, int64_t> last_taken;
  for (const SqlRow& row : turns.rows) last_taken[row.Bytes(0)] = row.Int(1);
  std::map<std::string, int> positions;
  int ahead = 0;
  for (const size_t i : TakingOrder(tasks, std::move(last_taken))) {
    if (!tasks[i].is_job) continue;
    positions[tasks[i].id] = ahead++;
  }
  return positions;
}

namespace {

// A job row's info as callers see it: its owner, cancel flag and replica from the row.
void FillFromRow(v1::JobInfo& info, const std::string& owner, bool cancel_requested,
                 const std::string& replica) {
  info.set_owner(owner);
  info.set_cancel_requested(cancel_requested);
  if (info.state() == v1::JOB_STATE_RUNNING) info.set_replica(replica);
}

}  // namespace

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

absl::StatusOr<v1::JobInfo> Store::GetJob(const std::string& id, bool position) {
  v1::JobInfo info;
  int64_t bad = 0;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT number, info, owner, cancel_requested, lease_owner FROM jobs "
                       "WHERE id = ?",
                       {id}));
        if (row.rows.empty()) return NoJob(id);
        const SqlRow& r = row.rows[0];
        if (!Parse(info, r.Bytes(1)) || info.id() != id) {
          bad = r.Int(0);
          return absl::OkStatus();
        }
        FillFromRow(info, r.Bytes(2), r.Int(3) != 0, r.Bytes(4));
        if (!position || info.state() != v1::JOB_STATE_QUEUED) return absl::OkStatus();
        FENESTRA_ASSIGN_OR_RETURN(positions, QueuePositions(s));
        if (auto it = positions.find(id); it != positions.end())
          info.set_queue_position(it->second);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  if (bad) {
    (void)Transact(
        [&](SqlSession& s) { return QuarantineRow(s, "jobs", bad, "its JobInfo does not parse"); });
    spdlog::error("job {}: its stored record does not parse; moved to the quarantine table", id);
    return NoJob(id);
  }
  return info;
}

absl::StatusOr<std::vector<v1::JobInfo>> Store::ListJobs(const std::string& owner,
                                                         v1::JobState state, int limit) {
  // A claimed job is RUNNING in its row before its info says so: the rows of both states
  // are read for either, and the infos decide
  std::vector<int64_t> states;
  if (state == v1::JOB_STATE_QUEUED || state == v1::JOB_STATE_RUNNING) {
    states = {kQueued, kRunning};
  } else if (state != v1::JOB_STATE_UNSPECIFIED) {
    states = {int64_t{state}};
  }
  std::vector<v1::JobInfo> jobs;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        jobs.clear();
        std::optional<std::map<std::string, int>> positions;
        for (int64_t before = INT64_MAX; static_cast<int>(jobs.size()) < limit;) {
          std::vector<SqlParam> params = {before};
          std::string sql =
              "SELECT number, id, info, owner, cancel_requested, lease_owner FROM jobs WHERE id "
              "IS NOT NULL AND number < ?";
          if (!owner.empty()) {
            absl::StrAppend(&sql, " AND owner = ?");
            params.push_back(owner);
          }
          if (!states.empty()) {
            absl::StrAppend(&sql, " AND state IN ", Placeholders(states.size()));
            for (const int64_t st : states) params.push_back(st);
          }
          absl::StrAppend(&sql, " ORDER BY number DESC LIMIT ?");
          params.push_back(kRowsPerRead);
          FENESTRA_ASSIGN_OR_RETURN(rows, s.Run(sql, params));
          if (rows.rows.empty()) break;
          for (const SqlRow& r : rows.rows) {
            before = r.Int(0);
            v1::JobInfo info;
            if (!Parse(info, r.Bytes(2)) || info.id() != r.Bytes(1)) continue;
            if (state != v1::JOB_STATE_UNSPECIFIED && info.state() != state) continue;
            if (static_cast<int>(jobs.size()) >= limit) break;
            info.clear_result();
            FillFromRow(info, r.Bytes(3), r.Int(4) != 0, r.Bytes(5));
            if (info.state() == v1::JOB_STATE_QUEUED) {
              if (!positions) {
                FENESTRA_ASSIGN_OR_RETURN(found, QueuePositions(s));
                positions = std::move(found);
              }
              if (auto it = positions->find(info.id()); it != positions->end()) {
                info.set_queue_position(it->second);
              }
            }
            jobs.push_back(std::move(info));
          }
        }
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return jobs;
}

absl::StatusOr<v1::Job> Store::LoadJob(const std::string& id) {
  v1::Job job;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(row, s.Run("SELECT job FROM jobs WHERE id = ?", {id}));
        if (row.rows.empty()) return NoJob(id);
        if (!Parse(job, row.rows[0].Bytes(0))) {
          return absl::DataLossError(absl::StrCat("the stored job ", id, " does not parse"));
        }
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return job;
}

absl::StatusOr<std::vector<v1::JobEvent>> Store::LoadEvents(const std::string& id, int64_t after) {
  std::vector<v1::JobEvent> events;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            rows, s.Run("SELECT event FROM job_events WHERE job_id = ? AND sequence > ? ORDER BY "
                        "sequence",
                        {id, after}));
        events.clear();
        for (const SqlRow& row : rows.rows) {
          v1::JobEvent event;
          if (Parse(event, row.Bytes(0))) events.push_back(std::move(event));
        }
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return events;
}

namespace {

// How long the events of a job that ended stay after its end [ms]: a watcher on any
// replica that lags behind the end by less still gets every event. Then only the final
// event stays (the final JobInfo holds what the others said).
constexpr int64_t kEndedEventsKeptMs = 60'000;

// Stores a job's end in `s` (its info stored already): its final event; and drops the
// earlier events of the jobs that ended long enough ago.
absl::Status StoreEnd(const Database& db, SqlSession& s, const v1::JobInfo& info,
                      const v1::JobEvent& event) {
  const std::string event_bytes = event.SerializeAsString();
  FENESTRA_RETURN_IF_ERROR(
      s.Run("INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)",
            {info.id(), event.sequence(), Blob(event_bytes)})
          .status());
  FENESTRA_RETURN_IF_ERROR(
      s.Run(db.Sql("UPDATE jobs SET events_expire_unix_ms = {now} + ? WHERE id = ?"),
            {kEndedEventsKeptMs, info.id()})
          .status());
  FENESTRA_RETURN_IF_ERROR(
      s.Run(db.Sql("DELETE FROM job_events WHERE job_id IN (SELECT id FROM jobs WHERE "
                   "events_expire_unix_ms BETWEEN 1 AND {now}) AND sequence < (SELECT "
                   "MAX(sequence) FROM job_events latest WHERE latest.job_id = "
                   "job_events.job_id)"))
          .status());
  FENESTRA_RETURN_IF_ERROR(
      s.Run(db.Sql("UPDATE jobs SET events_expire_unix_ms = 0 WHERE events_expire_unix_ms "
                   "BETWEEN 1 AND {now}"))
          .status());
  return s.Notify();
}

}  // namespace

absl::StatusOr<Store::Cancelled> Store::CancelJob(
    const std::string& id, const std::function<v1::JobEvent(v1::JobInfo&)>& end) {
  Cancelled cancelled;
  FENESTRA_RETURN_IF_ERROR(Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_ASSIGN_OR_RETURN(
        row, s.Run(Sql("SELECT info, state, owner, weather, lease_owner FROM jobs WHERE id = ?"
                       "{for_update}"),
                   {id}));
    if (row.rows.empty()) return NoJob(id);
    const SqlRow& r = row.rows[0];
    cancelled = Cancelled{};
    if (!Parse(cancelled.info, r.Bytes(0))) {
      return absl::DataLossError(absl::StrCat("the stored job ", id, " does not parse"));
    }
    cancelled.weather = r.Bytes(3);
    FillFromRow(cancelled.info, r.Bytes(2), true, r.Bytes(4));
    if (r.Int(1) == kQueued) {
      const v1::JobEvent event = end(cancelled.info);
      const std::string info_bytes = cancelled.info.SerializeAsString();
      FENESTRA_RETURN_IF_ERROR(
          s.Run("UPDATE jobs SET info = ?, state = ?, cancel_requested = 1 WHERE id = ?",
                {Blob(info_bytes), int64_t{cancelled.info.state()}, id})
              .status());
      cancelled.ended = true;
      return StoreEnd(*db_, s, cancelled.info, event);
    }
    if (r.Int(1) != kRunning) {
      cancelled.info.set_cancel_requested(false);
      return absl::OkStatus();
    }
    FENESTRA_RETURN_IF_ERROR(
        s.Run("UPDATE jobs SET cancel_requested = 1 WHERE id = ?", {id}).status());
    return s.Notify();
  }));
  return cancelled;
}

absl::Status Store::DeleteJob(const std::string& id) {
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(s.Run("DELETE FROM job_events WHERE job_id = ?", {id}).status());
    return s.Run("DELETE FROM jobs WHERE id = ?", {id}).status();
  });
}

// ---- Work

namespace {

// What a claim may take: not `excluded`, jobs whose outdoor key is in `preferred` first.
struct ClaimFilter {
  const std::vector<std::string>& preferred;  // at most kMaxPreferredKeys used
  const std::vector<std::string>& excluded;
};

// The runnable jobs (`jobs`) or site computations in claiming order: `among` null, the
// first few, unlocked; else the first of `among` still runnable, locked (rows other
// transactions hold are skipped). Locking while ordering sorts every row read, so the deep
// queue is ordered without locks. Columns: id, owner, state, lease_owner, the owner's turn,
// 0 for a preferred key, queue_order.
absl::StatusOr<SqlResult> ClaimCandidates(const Database& db, SqlSession& s, bool jobs,
                                          const ClaimFilter& filter,
                                          const std::vector<std::string>* among) {
  const size_t keys = std::min(filter.preferred.size(), kMaxPreferredKeys);
  std::vector<SqlParam> params;
  std::string sql;
  if (jobs) {
    sql = absl::StrCat(
        "SELECT c.id, c.owner, c.state, c.lease_owner, COALESCE(t.last_taken, 0), CASE WHEN "
        "c.outdoor_key IN ",
        keys ? Placeholders(keys) : "(NULL)",
        " THEN 0 ELSE 1 END, c.queue_order FROM jobs c LEFT JOIN turns t ON t.owner = c.owner "
        "WHERE (c.state = ? OR (c.state = ? AND c.lease_expires_unix_ms < {now}))");
    for (size_t i = 0; i < keys; ++i) params.push_back(filter.preferred[i]);
    params.push_back(kQueued);
    params.push_back(kRunning);
  } else {
    sql =
        "SELECT c.id, c.owner, 0, c.lease_owner, COALESCE(t.last_taken, 0), 1, c.queue_order "
        "FROM sites c LEFT JOIN turns t ON t.owner = c.owner WHERE c.state = ? AND "
        "c.lease_expires_unix_ms < {now}";
    params.push_back(kComputing);
  }
  if (!filter.excluded.empty()) {
    absl::StrAppend(&sql, " AND c.id NOT IN ", Placeholders(filter.excluded.size()));
    for (const std::string& id : filter.excluded) params.push_back(id);
  }
  if (among) {
    absl::StrAppend(&sql, " AND c.id IN ", Placeholders(among->size()));
    for (const std::string& id : *among) params.push_back(id);
  }
  absl::StrAppend(&sql, " ORDER BY CASE WHEN c.state = ? THEN 0 ELSE 1 END, 5, 6, 7 LIMIT ?",
                  among ? "{claim_lock}" : "");
  params.push_back(jobs ? kRunning : int64_t{-1});
  params.push_back(among ? int64_t{1} : kClaimCandidates);
  return s.Run(db.Sql(sql), params);
}

// The first runnable job or site computation, locked (none: no row): the first few in
// order, then the first of them no other claim holds (again, a few times, while other
// claims took them all).
absl::StatusOr<SqlResult> FirstRunnable(const Database& db, SqlSession& s, bool jobs,
                                        const ClaimFilter& filter) {
  constexpr int kAttempts = 5;
  for (int attempt = 1;; ++attempt) {
    FENESTRA_ASSIGN_OR_RETURN(first, ClaimCandidates(db, s, jobs, filter, nullptr));
    if (first.rows.empty()) return first;
    std::vector<std::string> ids;
    for (const SqlRow& row : first.rows) ids.push_back(row.Bytes(0));
    FENESTRA_ASSIGN_OR_RETURN(locked, ClaimCandidates(db, s, jobs, filter, &ids));
    if (!locked.rows.empty() || attempt == kAttempts) return locked;
  }
}

}  // namespace

absl::StatusOr<std::optional<Claim>> Store::ClaimWork(const std::string& replica, int64_t lease_ms,
                                                      const std::vector<std::string>& preferred,
                                                      const std::vector<std::string>& excluded,
                                                      std::string* candidate) {
  std::optional<Claim> claim;
  const ClaimFilter filter{preferred, excluded};
  const absl::Status status = Transact([&](SqlSession& s) -> absl::Status {
    claim.reset();
    FENESTRA_ASSIGN_OR_RETURN(job, FirstRunnable(*db_, s, /*jobs=*/true, filter));
    FENESTRA_ASSIGN_OR_RETURN(site, FirstRunnable(*db_, s, /*jobs=*/false, filter));
    // The job or the site: taken-over jobs first, then the user's turn, then the order
    const auto rank = [](const SqlRow& r, bool is_job) {
      return std::tuple(is_job && r.Int(2) == kRunning ? 0 : 1, r.Int(4), r.Int(6));
    };
    bool is_job;
    if (!job.rows.empty() && !site.rows.empty()) {
      is_job = rank(job.rows[0], true) <= rank(site.rows[0], false);
    } else if (!job.rows.empty() || !site.rows.empty()) {
      is_job = !job.rows.empty();
    } else {
      return absl::OkStatus();
    }
    const SqlRow& r = is_job ? job.rows[0] : site.rows[0];
    Claim c;
    c.kind = is_job ? Claim::Kind::kJob : Claim::Kind::kSite;
    c.lease.id = r.Bytes(0);
    c.owner = r.Bytes(1);
    c.taken_over = is_job && r.Int(2) == kRunning;
    c.previous_replica = r.Bytes(3);
    if (candidate) *candidate = c.lease.id;

    FENESTRA_ASSIGN_OR_RETURN(turn, NextCounter(s, "turn"));
    FENESTRA_RETURN_IF_ERROR(
        s.Run("INSERT INTO turns (owner, last_taken) VALUES (?, ?) ON "
              "CONFLICT (owner) DO UPDATE SET last_taken = excluded.last_taken",
              {c.owner, turn})
            .status());
    FENESTRA_ASSIGN_OR_RETURN(
        run, s.Run(Sql(is_job ? "UPDATE jobs SET state = 2, lease_owner = ?, lease_expires_unix_ms "
                                "= {now} + ?, run = run + 1 WHERE id = ? RETURNING run"
                              : "UPDATE sites SET lease_owner = ?, lease_expires_unix_ms = {now} "
                                "+ ?, run = run + 1 WHERE id = ? RETURNING run"),
                   {replica, lease_ms, c.lease.id}));
    c.lease.run = run.rows.at(0).Int(0);
    claim = std::move(c);
    return s.Notify();
  });
  if (!status.ok()) return status;
  return claim;
}

absl::StatusOr<std::vector<Store::Renewal>> Store::RenewLeases(
    int64_t lease_ms, const std::vector<std::pair<Claim::Kind, Lease>>& held) {
  std::vector<Renewal> renewed;
  if (held.empty()) return renewed;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        renewed.assign(held.size(), Renewal{});
        for (size_t i = 0; i < held.size(); ++i) {
          const auto& [kind, lease] = held[i];
          const bool job = kind == Claim::Kind::kJob;
          FENESTRA_ASSIGN_OR_RETURN(
              row, s.Run(Sql(job ? "UPDATE jobs SET lease_expires_unix_ms = {now} + ? WHERE id = "
                                   "? AND run = ? AND state = ? RETURNING cancel_requested"
                                 : "UPDATE sites SET lease_expires_unix_ms = {now} + ? WHERE id "
                                   "= ? AND run = ? AND state = ? RETURNING 0"),
                         {lease_ms, lease.id, lease.run, job ? kRunning : kComputing}));
          renewed[i].held = !row.rows.empty();
          renewed[i].cancel_requested = !row.rows.empty() && row.rows[0].Int(0) != 0;
        }
        return absl::OkStatus();
      },
      /*durable=*/false));
  return renewed;
}

absl::Status Store::ExpireLeases() {
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(
        s.Run("UPDATE jobs SET lease_expires_unix_ms = 0 WHERE state = ?", {kRunning}).status());
    return s.Run("UPDATE sites SET lease_expires_unix_ms = 0 WHERE state = ?", {kComputing})
        .status();
  });
}

absl::Status Store::Release(Claim::Kind kind, const Lease& lease) {
  const bool job = kind == Claim::Kind::kJob;
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(
        Fenced(s.Run(job ? "UPDATE jobs SET lease_expires_unix_ms = 0 WHERE id = ? AND run = ? "
                           "AND state = ?"
                         : "UPDATE sites SET lease_expires_unix_ms = 0 WHERE id = ? AND run = ? "
                           "AND state = ?",
                     {lease.id, lease.run, job ? kRunning : kComputing}),
               lease));
    return s.Notify();
  });
}

// ---- A claimed job's writes

absl::Status Store::UpdateJob(const Lease& lease, const v1::JobInfo& info,
                              const v1::JobEvent* event, bool durable, bool* cancel_requested,
                              const std::string* checkpoint) {
  const std::string info_bytes = info.SerializeAsString();
  const std::string event_bytes = event ? event->SerializeAsString() : "";
  return Transact(
      [&](SqlSession& s) -> absl::Status {
        absl::StatusOr<SqlResult> updated = s.Run(
            "UPDATE jobs SET info = ?, state = ? WHERE id = ? AND run = ? AND state = ? "
            "RETURNING cancel_requested",
            {Blob(info_bytes), int64_t{info.state()}, lease.id, lease.run, kRunning});
        FENESTRA_RETURN_IF_ERROR(Fenced(updated, lease));
        if (cancel_requested) *cancel_requested = updated->rows[0].Int(0) != 0;
        if (checkpoint) {
          FENESTRA_RETURN_IF_ERROR(
              s.Run("UPDATE jobs SET checkpoint = ? WHERE id = ?", {Blob(*checkpoint), lease.id})
                  .status());
        }
        if (event) {
          FENESTRA_RETURN_IF_ERROR(
              s.Run("INSERT INTO job_events (job_id, sequence, event) VALUES (?, ?, ?)",
                    {lease.id, event->sequence(), Blob(event_bytes)})
                  .status());
        }
        return s.Notify();
      },
      durable);
}

absl::Status Store::FinishJob(const Lease& lease, const v1::JobInfo& info,
                              const v1::JobEvent& event) {
  const std::string info_bytes = info.SerializeAsString();
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(
        Fenced(s.Run("UPDATE jobs SET info = ?, state = ?, lease_owner = '', "
                     "lease_expires_unix_ms = 0, checkpoint = NULL WHERE id = ? AND run = ? AND "
                     "state = ?",
                     {Blob(info_bytes), int64_t{info.state()}, lease.id, lease.run, kRunning}),
               lease));
    return StoreEnd(*db_, s, info, event);
  });
}

absl::Status Store::SaveCheckpoint(const Lease& lease, std::string_view bytes) {
  return Transact(
      [&](SqlSession& s) {
        return Fenced(s.Run("UPDATE jobs SET checkpoint = ? WHERE id = ? AND run = ? AND state = ?",
                            {SqlBlob{bytes}, lease.id, lease.run, kRunning}),
                      lease);
      },
      /*durable=*/false);
}

absl::StatusOr<std::optional<std::string>> Store::LoadCheckpoint(const std::string& id) {
  std::optional<std::string> checkpoint;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(row, s.Run("SELECT checkpoint FROM jobs WHERE id = ?", {id}));
        if (row.rows.empty()) return NoJob(id);
        if (!row.rows[0].IsNull(0)) checkpoint = row.rows[0].TakeBytes(0);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return checkpoint;
}

// ---- Sites

absl::StatusOr<v1::SiteInfo> Store::InsertSite(v1::SiteInfo info, const v1::Scene& scene,
                                               std::string_view weather_epw,
                                               const v1::Limits& limits) {
  info.clear_scene();
  std::string weather;
  bool stored = false;
  absl::Cleanup uncount = [&] {
    if (!stored && weather_files_ && !weather.empty()) {
      weather_files_->Unref(WeatherFileName(weather));
    }
  };
  if (weather_files_ && !weather_epw.empty()) {
    FENESTRA_ASSIGN_OR_RETURN(path, weather_files_->Add(weather_epw));
    weather = WeatherOfPath(path);
  }
  const std::string scene_bytes = scene.SerializeAsString();
  FENESTRA_RETURN_IF_ERROR(Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(s.Lock(kAdmissionLock));
    FENESTRA_ASSIGN_OR_RETURN(
        count, s.Run("SELECT COUNT(*), CAST(COALESCE(SUM(CASE WHEN owner = ? THEN 1 ELSE 0 END), "
                     "0) AS BIGINT) FROM sites",
                     {info.owner()}));
    const int64_t total = count.rows[0].Int(0), owned = count.rows[0].Int(1);
    if (total >= limits.max_sites()) {
      return absl::ResourceExhaustedError(
          absl::StrCat("this server holds ", total,
                       " sites, its limit max_sites; delete one first (fenestra site rm)"));
    }
    if (owned >= limits.max_sites_per_user()) {
      return absl::ResourceExhaustedError(absl::StrCat(
          "limits.max_sites_per_user (", limits.max_sites_per_user(), ") reached: you have ", owned,
          " sites; delete one first (fenestra site rm)"));
    }
    FENESTRA_RETURN_IF_ERROR(CheckUploadQuota(s, info.owner(), info.upload_bytes(), limits));
    if (!weather_epw.empty() && !weather_files_) {
      FENESTRA_ASSIGN_OR_RETURN(sha, PutWeather(s, weather_epw));
      weather = sha;
    }
    info.set_has_weather(!weather.empty());
    FENESTRA_ASSIGN_OR_RETURN(order, NextCounter(s, "queue"));
    FENESTRA_ASSIGN_OR_RETURN(
        inserted,
        s.Run("INSERT INTO sites (info, weather_path, scene, owner, state, outdoor_key, weather, "
              "upload_bytes, queue_order) VALUES (?, '', ?, ?, ?, ?, ?, ?, ?) RETURNING number",
              {kNoBytes, Blob(scene_bytes), info.owner(), int64_t{info.state()}, info.outdoor_key(),
               weather, info.upload_bytes(), order}));
    const int64_t number = inserted.rows[0].Int(0);
    info.set_id(absl::StrCat("site-", number));
    const std::string info_bytes = info.SerializeAsString();
    FENESTRA_RETURN_IF_ERROR(s.Run("UPDATE sites SET id = ?, info = ? WHERE number = ?",
                                   {info.id(), Blob(info_bytes), number})
                                 .status());
    return s.Notify();
  }));
  stored = true;
  return info;
}

absl::StatusOr<Store::StoredSite> Store::GetSite(const std::string& id) {
  StoredSite site;
  int64_t bad = 0;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT number, info, owner, weather FROM sites WHERE id = ?", {id}));
        if (row.rows.empty()) return NoSite(id);
        const SqlRow& r = row.rows[0];
        if (!Parse(site.info, r.Bytes(1)) || site.info.id() != id) {
          bad = r.Int(0);
          return absl::OkStatus();
        }
        site.info.clear_scene();  // stored before scenes had their own column
        site.info.set_owner(r.Bytes(2));
        site.weather = r.Bytes(3);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  if (bad) {
    (void)Transact([&](SqlSession& s) {
      return QuarantineRow(s, "sites", bad, "its SiteInfo does not parse");
    });
    spdlog::error("site {}: its stored record does not parse; moved to the quarantine table", id);
    return NoSite(id);
  }
  return site;
}

absl::StatusOr<std::vector<v1::SiteInfo>> Store::ListSites(const std::string& owner) {
  std::vector<v1::SiteInfo> sites;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        sites.clear();
        for (int64_t after = 0;;) {
          std::vector<SqlParam> params = {after};
          std::string sql =
              "SELECT number, id, info, owner FROM sites WHERE id IS NOT NULL AND number > ?";
          if (!owner.empty()) {
            absl::StrAppend(&sql, " AND owner = ?");
            params.push_back(owner);
          }
          absl::StrAppend(&sql, " ORDER BY number LIMIT ?");
          params.push_back(kRowsPerRead);
          FENESTRA_ASSIGN_OR_RETURN(rows, s.Run(sql, params));
          if (rows.rows.empty()) break;
          for (const SqlRow& r : rows.rows) {
            after = r.Int(0);
            v1::SiteInfo info;
            if (!Parse(info, r.Bytes(2)) || info.id() != r.Bytes(1)) continue;
            info.clear_scene();
            info.set_owner(r.Bytes(3));
            sites.push_back(std::move(info));
          }
        }
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return sites;
}

absl::StatusOr<v1::Scene> Store::LoadSiteScene(const std::string& id) {
  v1::Scene scene;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(row, s.Run("SELECT scene, info FROM sites WHERE id = ?", {id}));
        if (row.rows.empty()) return NoSite(id);
        SqlRow& r = row.rows[0];
        if (const std::string bytes = r.TakeBytes(0); !bytes.empty()) {
          if (Parse(scene, bytes)) return absl::OkStatus();
        } else if (v1::SiteInfo info; Parse(info, r.TakeBytes(1))) {
          scene = info.scene();  // stored before scenes had their own column
          return absl::OkStatus();
        }
        return absl::DataLossError(
            absl::StrCat("the stored scene of site ", id, " does not parse"));
      },
      /*durable=*/false, /*write=*/false));
  return scene;
}

absl::StatusOr<int64_t> Store::SiteSceneBytes(const std::string& id) {
  int64_t bytes = 0;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row,
            s.Run("SELECT COALESCE(length(scene), length(info)) FROM sites WHERE id = ?", {id}));
        if (row.rows.empty()) return NoSite(id);
        bytes = row.rows[0].Int(0);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return bytes;
}

absl::StatusOr<v1::SiteInfo> Store::UpdateSite(const std::string& id, const Lease* lease,
                                               const std::function<void(v1::SiteInfo&)>& update) {
  v1::SiteInfo info;
  FENESTRA_RETURN_IF_ERROR(Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_ASSIGN_OR_RETURN(
        row, s.Run(Sql("SELECT info, owner, run FROM sites WHERE id = ?{for_update}"), {id}));
    if (row.rows.empty()) return NoSite(id);
    const SqlRow& r = row.rows[0];
    if (lease && r.Int(2) != lease->run) {
      return absl::AbortedError(
          absl::StrCat(id, ": its lease was lost (another replica took it over)"));
    }
    if (!Parse(info, r.Bytes(0))) {
      return absl::DataLossError(absl::StrCat("the stored site ", id, " does not parse"));
    }
    info.clear_scene();
    update(info);
    const std::string info_bytes = info.SerializeAsString();
    FENESTRA_RETURN_IF_ERROR(s.Run(lease
                                       ? "UPDATE sites SET info = ?, state = ?, lease_owner = '', "
                                         "lease_expires_unix_ms = 0 WHERE id = ?"
                                       : "UPDATE sites SET info = ?, state = ? WHERE id = ?",
                                   {Blob(info_bytes), int64_t{info.state()}, id})
                                 .status());
    info.set_owner(r.Bytes(1));
    return s.Notify();
  }));
  return info;
}

absl::StatusOr<Store::StoredSite> Store::DeleteSite(const std::string& id) {
  StoredSite site;
  FENESTRA_RETURN_IF_ERROR(Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_ASSIGN_OR_RETURN(
        row, s.Run(Sql("SELECT info, owner, weather FROM sites WHERE id = ?{for_update}"), {id}));
    if (row.rows.empty()) return NoSite(id);
    (void)Parse(site.info, row.rows[0].Bytes(0));
    site.info.clear_scene();
    site.info.set_owner(row.rows[0].Bytes(1));
    site.weather = row.rows[0].Bytes(2);
    FENESTRA_RETURN_IF_ERROR(s.Run("DELETE FROM sites WHERE id = ?", {id}).status());
    return s.Notify();
  }));
  return site;
}

absl::StatusOr<bool> Store::KeyInUse(const std::string& key) {
  bool used = false;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT (SELECT COUNT(*) FROM sites WHERE outdoor_key = ?) + (SELECT "
                       "COUNT(*) FROM jobs WHERE outdoor_key = ? AND state IN (?, ?))",
                       {key, key, kQueued, kRunning}));
        used = row.rows[0].Int(0) > 0;
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return used;
}

// ---- Weather files

absl::StatusOr<std::string> Store::ReadWeather(const std::string& weather) {
  if (weather_files_) {
    const std::filesystem::path path = weather_files_->dir() / WeatherFileName(weather);
    std::ifstream in(path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    if (!in) {
      spdlog::error("cannot read the weather file {}", path.string());
      return absl::DataLossError("the job's stored weather file cannot be read");
    }
    return bytes.str();
  }
  std::string bytes;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(row,
                                  s.Run("SELECT bytes FROM weather WHERE sha256 = ?", {weather}));
        if (row.rows.empty()) {
          return absl::DataLossError("the job's stored weather file is missing");
        }
        bytes = row.rows[0].TakeBytes(0);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  if (Sha256Hex(bytes) != weather) {
    return absl::DataLossError("the job's stored weather file does not match its checksum");
  }
  return bytes;
}

void Store::ReleaseWeather(const std::string& weather) {
  if (weather.empty()) return;
  if (weather_files_) {
    weather_files_->Unref(WeatherFileName(weather));
    return;
  }
  const absl::Status status = Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(s.Lock(kAdmissionLock));
    return s
        .Run(
            "DELETE FROM weather WHERE sha256 = ? AND NOT EXISTS (SELECT 1 FROM sites WHERE "
            "weather = ?) AND NOT EXISTS (SELECT 1 FROM jobs WHERE weather = ? AND state IN (?, "
            "?))",
            {weather, weather, weather, kQueued, kRunning})
        .status();
  });
  if (!status.ok()) {
    spdlog::warn("weather file {} not removed: {}", weather.substr(0, 16),
                 std::string(status.message()));
  }
}

absl::StatusOr<int> Store::CountWeatherReferences() {
  if (!weather_files_) return 0;
  std::vector<std::string> used;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            rows, s.Run("SELECT weather FROM sites WHERE weather <> '' UNION ALL SELECT weather "
                        "FROM jobs WHERE weather <> '' AND state IN (?, ?)",
                        {kQueued, kRunning}));
        used.clear();
        for (const SqlRow& row : rows.rows) used.push_back(row.Bytes(0));
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  for (const std::string& weather : used) weather_files_->Ref(WeatherFileName(weather));
  return weather_files_->RemoveUnreferenced();
}

// ---- Outdoor matrices

absl::Status Store::PutMatrix(const std::string& key, std::string_view bytes) {
  const std::string sha = Sha256(bytes);
  return Transact([&](SqlSession& s) {
    return s
        .Run(Sql("INSERT INTO outdoor_matrices (matrix_key, bytes, sha256, created_unix_ms) "
                 "VALUES (?, ?, ?, {now}) ON CONFLICT (matrix_key) DO NOTHING"),
             {key, SqlBlob{bytes}, Blob(sha)})
        .status();
  });
}

absl::StatusOr<std::optional<std::string>> Store::GetMatrix(const std::string& key) {
  std::optional<std::string> bytes;
  std::string sha;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT bytes, sha256 FROM outdoor_matrices WHERE matrix_key = ?", {key}));
        if (row.rows.empty()) return absl::OkStatus();
        bytes = row.rows[0].TakeBytes(0);
        sha = row.rows[0].Bytes(1);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  if (bytes && Sha256(*bytes) != sha) {
    (void)DeleteMatrix(key);
    return absl::DataLossError("SHA-256 checksum mismatch (corrupted stored matrix); removed");
  }
  return bytes;
}

absl::StatusOr<bool> Store::HasMatrix(const std::string& key) {
  bool found = false;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT COUNT(*) FROM outdoor_matrices WHERE matrix_key = ?", {key}));
        found = row.rows[0].Int(0) > 0;
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return found;
}

absl::Status Store::DeleteMatrix(const std::string& key) {
  return Transact([&](SqlSession& s) {
    return s.Run("DELETE FROM outdoor_matrices WHERE matrix_key = ?", {key}).status();
  });
}

absl::StatusOr<std::vector<std::string>> Store::MatrixKeys() {
  std::vector<std::string> keys;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(rows, s.Run("SELECT matrix_key FROM outdoor_matrices ORDER BY "
                                              "created_unix_ms"));
        keys.clear();
        for (const SqlRow& row : rows.rows) keys.push_back(row.Bytes(0));
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return keys;
}

// ---- Quarantine

absl::Status Store::QuarantineRow(SqlSession& s, const std::string& table, int64_t number,
                                  const std::string& reason) {
  const bool jobs = table == "jobs";
  FENESTRA_RETURN_IF_ERROR(
      s.Run(Sql(jobs ? "INSERT INTO quarantine (source, id, reason, info, body, "
                       "quarantined_unix_ms) SELECT 'jobs', id, ?, info, job, {now} FROM jobs "
                       "WHERE number = ?"
                     : "INSERT INTO quarantine (source, id, reason, info, body, weather_path, "
                       "quarantined_unix_ms) SELECT 'sites', id, ?, info, scene, weather, {now} "
                       "FROM sites WHERE number = ?"),
            {reason, number})
          .status());
  return s
      .Run(jobs ? "DELETE FROM jobs WHERE number = ?" : "DELETE FROM sites WHERE number = ?",
           {number})
      .status();
}

absl::Status Store::Quarantine(const std::string& table, const std::string& id,
                               const std::string& reason) {
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_ASSIGN_OR_RETURN(row, s.Run(table == "jobs" ? "SELECT number FROM jobs WHERE id = ?"
                                                         : "SELECT number FROM sites WHERE id = ?",
                                         {id}));
    if (row.rows.empty()) return absl::OkStatus();
    return QuarantineRow(s, table, row.rows[0].Int(0), reason);
  });
}

absl::StatusOr<std::vector<Store::Quarantined>> Store::QuarantineUnparsable() {
  std::vector<Quarantined> moved;
  for (const std::string table : {"jobs", "sites"}) {
    const bool jobs = table == "jobs";
    std::vector<std::pair<int64_t, Quarantined>> bad;
    FENESTRA_RETURN_IF_ERROR(Transact(
        [&](SqlSession& s) -> absl::Status {
          bad.clear();
          for (int64_t after = 0;;) {
            FENESTRA_ASSIGN_OR_RETURN(
                rows, s.Run(absl::StrCat("SELECT number, id, info FROM ", table,
                                         " WHERE id IS NOT NULL AND number > ? ORDER BY number "
                                         "LIMIT ?"),
                            {after, kRowsPerRead}));
            if (rows.rows.empty()) break;
            for (const SqlRow& r : rows.rows) {
              after = r.Int(0);
              const std::string id = r.Bytes(1);
              std::string parsed_id;
              bool parsed;
              if (jobs) {
                v1::JobInfo info;
                parsed = Parse(info, r.Bytes(2));
                parsed_id = info.id();
              } else {
                v1::SiteInfo info;
                parsed = Parse(info, r.Bytes(2));
                parsed_id = info.id();
              }
              const std::string what = jobs ? "JobInfo" : "SiteInfo";
              if (!parsed) {
                bad.push_back({after, {id, absl::StrCat("its ", what, " does not parse")}});
              } else if (parsed_id != id) {
                bad.push_back(
                    {after,
                     {id, absl::StrCat("its ", what, " names another ", jobs ? "job" : "site")}});
              }
            }
          }
          return absl::OkStatus();
        },
        /*durable=*/false, /*write=*/false));
    for (auto& entry : bad) {
      const auto& number = entry.first;
      auto& record = entry.second;
      if (absl::Status s = Transact([&](SqlSession& session) {
            return QuarantineRow(session, table, number, record.reason);
          });
          !s.ok()) {
        absl::StrAppend(&record.reason, " (left in place: ", s.message(), ")");
      }
      moved.push_back(std::move(record));
    }
  }
  return moved;
}

// ---- Users

absl::Status Store::InsertUser(const UserRecord& user) {
  const absl::Status status = Transact([&](SqlSession& s) {
    return s
        .Run(
            "INSERT INTO users (name, token_sha256, admin, created_unix_ms, revoked_unix_ms) "
            "VALUES (?, ?, ?, ?, ?)",
            {user.name, Blob(user.token_sha256), int64_t{user.admin}, user.created_unix_ms,
             user.revoked_unix_ms})
        .status();
  });
  if (status.code() == absl::StatusCode::kAlreadyExists) {
    return absl::AlreadyExistsError(absl::StrCat("user '", user.name, "' exists"));
  }
  return status;
}

absl::StatusOr<std::vector<UserRecord>> Store::LoadUsers() {
  std::vector<UserRecord> users;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            rows, s.Run("SELECT name, token_sha256, admin, created_unix_ms, revoked_unix_ms FROM "
                        "users ORDER BY number"));
        users.clear();
        for (const SqlRow& r : rows.rows) {
          users.push_back(UserRecord{r.Bytes(0), r.Bytes(1), r.Int(2) != 0, r.Int(3), r.Int(4)});
        }
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return users;
}

absl::Status Store::RevokeUser(const std::string& name, int64_t unix_ms) {
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_ASSIGN_OR_RETURN(
        updated, s.Run("UPDATE users SET revoked_unix_ms = CASE WHEN revoked_unix_ms = 0 THEN ? "
                       "ELSE revoked_unix_ms END WHERE name = ?",
                       {unix_ms, name}));
    if (updated.changed == 0) return absl::NotFoundError(absl::StrCat("no user '", name, "'"));
    return absl::OkStatus();
  });
}

// ---- Copying

namespace {

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
