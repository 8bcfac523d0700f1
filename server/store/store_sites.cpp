// Store: sites, uploaded weather files, the outdoor matrices kept in the database, and
// the quarantine of records that no longer parse.
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "server/checksum.h"
#include "server/data_dir.h"
#include "server/store/migrations.h"
#include "server/store/store.h"
#include "server/store/store_internal.h"

namespace fenestra {

namespace {

using store_internal::Blob;
using store_internal::CheckUploadQuota;
using store_internal::kAdmissionLock;
using store_internal::kNoBytes;
using store_internal::kQueued;
using store_internal::kRunning;
using store_internal::NextCounter;
using store_internal::Parse;
using store_internal::UnparsableRecord;
using store_internal::WeatherFileName;

}  // namespace

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
        if (row.rows.empty()) return store_internal::NoSite(id);
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
    return store_internal::NoSite(id);
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
        if (row.rows.empty()) return store_internal::NoSite(id);
        SqlRow& r = row.rows[0];
        if (const std::string bytes = r.TakeBytes(0); !bytes.empty()) {
          if (Parse(scene, bytes)) return absl::OkStatus();
        } else if (v1::SiteInfo info; Parse(info, r.TakeBytes(1))) {
          scene = info.scene();  // stored before scenes had their own column
          return absl::OkStatus();
        }
        return UnparsableRecord(id,
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
        if (row.rows.empty()) return store_internal::NoSite(id);
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
    if (row.rows.empty()) return store_internal::NoSite(id);
    const SqlRow& r = row.rows[0];
    if (lease && r.Int(2) != lease->run) {
      return absl::AbortedError(
          absl::StrCat(id, ": its lease was lost (another replica took it over)"));
    }
    if (!Parse(info, r.Bytes(0))) {
      return UnparsableRecord(id, absl::StrCat("the stored site ", id, " does not parse"));
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
    if (row.rows.empty()) return store_internal::NoSite(id);
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

absl::StatusOr<std::string> Store::PutWeather(SqlSession& s, std::string_view bytes) {
  const std::string sha = Sha256Hex(bytes);
  FENESTRA_RETURN_IF_ERROR(
      s.Run("INSERT INTO weather (sha256, bytes) VALUES (?, ?) ON CONFLICT (sha256) DO NOTHING",
            {sha, SqlBlob{bytes}})
          .status());
  return sha;
}

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
      s.Run(Sql(jobs ? "INSERT INTO quarantine (source, id, reason, info, result, body, "
                       "quarantined_unix_ms) SELECT 'jobs', id, ?, info, result, job, {now} FROM "
                       "jobs WHERE number = ?"
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

}  // namespace fenestra
