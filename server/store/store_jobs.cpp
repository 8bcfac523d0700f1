// Store: jobs, their events and, for a claimed job, its writes and checkpoints.
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/wire_format_lite.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <deque>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "server/data_dir.h"
#include "server/store/migrations.h"
#include "server/store/store.h"
#include "server/store/store_internal.h"

namespace fenestra {

namespace {

using store_internal::Blob;
using store_internal::CheckUploadQuota;
using store_internal::kAdmissionLock;
using store_internal::kComputing;
using store_internal::kNoBytes;
using store_internal::kQueued;
using store_internal::kRunning;
using store_internal::NextCounter;
using store_internal::Parse;
using store_internal::Placeholders;
using store_internal::UnparsableRecord;
using store_internal::WeatherFileName;

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

// ---- Jobs

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
    const store_internal::JobInfoColumns columns = store_internal::ColumnsOf(info);
    FENESTRA_RETURN_IF_ERROR(s.Run("UPDATE jobs SET id = ?, info = ?, result = ? WHERE number = ?",
                                   {info.id(), columns.Info(), columns.Result(), number})
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

absl::StatusOr<v1::JobInfo> Store::GetJob(const std::string& id, bool position) {
  v1::JobInfo info;
  int64_t bad = 0;
  FENESTRA_RETURN_IF_ERROR(Transact(
      [&](SqlSession& s) -> absl::Status {
        FENESTRA_ASSIGN_OR_RETURN(
            row, s.Run("SELECT number, info, owner, cancel_requested, lease_owner, result FROM "
                       "jobs WHERE id = ?",
                       {id}));
        if (row.rows.empty()) return store_internal::NoJob(id);
        const SqlRow& r = row.rows[0];
        if (!store_internal::ParseJobInfo(info, r, 1, 5) || info.id() != id) {
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
    return store_internal::NoJob(id);
  }
  return info;
}

store_internal::JobInfoColumns store_internal::ColumnsOf(const v1::JobInfo& info) {
  JobInfoColumns columns;
  if (!info.has_result()) {
    columns.info = info.SerializeAsString();
    return columns;
  }
  v1::JobInfo head = info;
  head.clear_result();
  columns.info = head.SerializeAsString();
  // The field as JobInfo's serialization writes it: tag, length, the result's bytes
  using google::protobuf::internal::WireFormatLite;
  const std::string body = info.result().SerializeAsString();
  columns.result.emplace();
  {
    google::protobuf::io::StringOutputStream sink(&*columns.result);
    google::protobuf::io::CodedOutputStream out(&sink);
    out.WriteTag(WireFormatLite::MakeTag(v1::JobInfo::kResultFieldNumber,
                                         WireFormatLite::WIRETYPE_LENGTH_DELIMITED));
    out.WriteVarint32(static_cast<uint32_t>(body.size()));
    out.WriteString(body);
  }
  return columns;
}

bool store_internal::ParseJobInfo(v1::JobInfo& info, const SqlRow& row, size_t info_column,
                                  size_t result_column) {
  if (!info.ParseFromString(row.Bytes(info_column))) return false;
  return row.IsNull(result_column) || info.MergeFromString(row.Bytes(result_column));
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
        if (row.rows.empty()) return store_internal::NoJob(id);
        if (!Parse(job, row.rows[0].Bytes(0))) {
          return UnparsableRecord(id, absl::StrCat("the stored job ", id, " does not parse"));
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
        row, s.Run(Sql("SELECT info, state, owner, weather, lease_owner, result FROM jobs WHERE "
                       "id = ?{for_update}"),
                   {id}));
    if (row.rows.empty()) return store_internal::NoJob(id);
    const SqlRow& r = row.rows[0];
    cancelled = Cancelled{};
    if (!store_internal::ParseJobInfo(cancelled.info, r, 0, 5)) {
      return UnparsableRecord(id, absl::StrCat("the stored job ", id, " does not parse"));
    }
    cancelled.weather = r.Bytes(3);
    FillFromRow(cancelled.info, r.Bytes(2), true, r.Bytes(4));
    if (r.Int(1) == kQueued) {
      const v1::JobEvent event = end(cancelled.info);
      const store_internal::JobInfoColumns columns = store_internal::ColumnsOf(cancelled.info);
      FENESTRA_RETURN_IF_ERROR(
          s.Run(
               "UPDATE jobs SET info = ?, result = ?, state = ?, cancel_requested = 1 WHERE id = ?",
               {columns.Info(), columns.Result(), int64_t{cancelled.info.state()}, id})
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

// ---- A claimed job's writes

absl::Status Store::UpdateJob(const Lease& lease, const v1::JobInfo& info,
                              const v1::JobEvent* event, bool durable, bool* cancel_requested,
                              const std::string* checkpoint) {
  const store_internal::JobInfoColumns columns = store_internal::ColumnsOf(info);
  const std::string event_bytes = event ? event->SerializeAsString() : "";
  return Transact(
      [&](SqlSession& s) -> absl::Status {
        absl::StatusOr<SqlResult> updated = s.Run(
            "UPDATE jobs SET info = ?, result = ?, state = ? WHERE id = ? AND run = ? AND "
            "state = ? RETURNING cancel_requested",
            {columns.Info(), columns.Result(), int64_t{info.state()}, lease.id, lease.run,
             kRunning});
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
  const store_internal::JobInfoColumns columns = store_internal::ColumnsOf(info);
  return Transact([&](SqlSession& s) -> absl::Status {
    FENESTRA_RETURN_IF_ERROR(
        Fenced(s.Run("UPDATE jobs SET info = ?, result = ?, state = ?, lease_owner = '', "
                     "lease_expires_unix_ms = 0, checkpoint = NULL WHERE id = ? AND run = ? AND "
                     "state = ?",
                     {columns.Info(), columns.Result(), int64_t{info.state()}, lease.id, lease.run,
                      kRunning}),
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
        if (row.rows.empty()) return store_internal::NoJob(id);
        if (!row.rows[0].IsNull(0)) checkpoint = row.rows[0].TakeBytes(0);
        return absl::OkStatus();
      },
      /*durable=*/false, /*write=*/false));
  return checkpoint;
}

}  // namespace fenestra
