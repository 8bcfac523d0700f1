#pragma once

// The daemon's state, shared by every replica that opens the same database: jobs (their
// submitted form, latest JobInfo, events, per-run checkpoint and lease), sites (SiteInfo,
// scene, lease of their computation), users, the users' turns for fair share, records
// that no longer parse (quarantine), uploaded weather files, and, with PostgreSQL, the
// cached outdoor matrices. Two databases: SQLite in the data directory (one daemon;
// weather files and matrices stay files beside it) and PostgreSQL (any number of
// replicas; everything in the database). Every change is one transaction; the schema is
// versioned (server/store/migrations.h).
//
// Work is claimed, not assigned: a replica's worker takes the next job or site
// computation (ClaimWork: the user served least recently first, then a job whose matrix
// this replica holds, then the oldest; PostgreSQL: SELECT ... FOR UPDATE SKIP LOCKED) under
// a lease it renews (RenewLeases). Each claim counts up the row's `run`: the writes of a
// run (UpdateJob, FinishJob, SaveCheckpoint, UpdateSite with a lease) are refused with
// Aborted once another claim took the row, so a replica that lost its lease cannot
// overwrite what the next one does, and a job ends once.
//
// Errors carry no paths or host names: a full disk is StorageFullError
// (RESOURCE_EXHAUSTED), a database that cannot be reached Unavailable, a limit
// ResourceExhausted naming it, anything else Internal. Thread-safe.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/job.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/store/database.h"

namespace fenestra {

class UploadStore;

// A user of the daemon as stored; the token only as its SHA-256.
struct UserRecord {
  std::string name;
  std::string token_sha256;  // 32 raw bytes
  bool admin = false;
  int64_t created_unix_ms = 0;
  int64_t revoked_unix_ms = 0;  // 0 while the token is valid
};

// Where the users live.
class UserStore {
 public:
  virtual ~UserStore() = default;
  // Stores a new user; AlreadyExists when the name is taken (revoked users included).
  virtual absl::Status InsertUser(const UserRecord& user) = 0;
  // Every user, revoked ones included, oldest first.
  virtual absl::StatusOr<std::vector<UserRecord>> LoadUsers() = 0;
  // Marks a user's token revoked at `unix_ms` (a revoked user keeps its first time);
  // NotFound when there is no such user.
  virtual absl::Status RevokeUser(const std::string& name, int64_t unix_ms) = 0;
};

// One claim on a job's run or a site's computation: `run` is the row's claim count when
// it was taken; only the latest claim may write.
struct Lease {
  std::string id;
  int64_t run = 0;
};

// What a worker took from the store.
struct Claim {
  enum class Kind { kJob, kSite };
  Kind kind = Kind::kJob;
  Lease lease;
  std::string owner;
  // A job another claim was running, whose lease expired (its replica stopped).
  bool taken_over = false;
  std::string previous_replica;  // who held it then
};

class Store final : public UserStore {
 public:
  // Opens a store on `db`, its schema brought to the newest version (Migrate).
  // `weather_files`: SQLite, the data directory's uploads (kept as files, counted in this
  // process); null: weather files in the database. FailedPrecondition when the schema is
  // newer than this binary knows.
  static absl::StatusOr<std::unique_ptr<Store>> Open(std::unique_ptr<Database> db,
                                                     UploadStore* weather_files = nullptr);
  ~Store() override;
  Store(const Store&) = delete;
  Store& operator=(const Store&) = delete;

  Database& database() { return *db_; }
  // True when several processes may share the store (PostgreSQL).
  bool shared() const { return db_->dialect() == Dialect::kPostgres; }
  // Waits `poll`, then on until the database answers a query (one out of reach, such as a
  // restarting PostgreSQL, answers again) or `stop()` is true; true when it answers.
  bool AwaitAnswer(std::chrono::milliseconds poll, const std::function<bool()>& stop);

  // ---- Jobs

  // A job to store: its info (owner, name, site, outdoor key, backend, upload size), its
  // submitted form without weather path, and its uploaded weather file (empty: the site's;
  // not copied).
  struct NewJob {
    v1::JobInfo info;
    v1::Job job;
    std::string_view weather_epw;
  };
  // Stores a queued job and its first event ("queued": the jobs waiting before it); its
  // info with the new id "job-N" (N unique and never reused). Checked in the same
  // transaction against `limits` (max_queued_jobs, max_queued_jobs_per_user,
  // max_upload_bytes_per_user: ResourceExhausted naming the limit) and its site (NotFound
  // when deleted meanwhile).
  absl::StatusOr<v1::JobInfo> InsertJob(NewJob job, const v1::Limits& limits);
  // A job's stored info with cancel_requested, the replica running it and, with
  // `position`, its place in the queue when queued (which reads the whole queue). NotFound
  // when unknown; a record that no longer parses is quarantined (and NotFound).
  absl::StatusOr<v1::JobInfo> GetJob(const std::string& id, bool position = true);
  // `owner`'s jobs (empty: everyone's) in `state` (UNSPECIFIED: all), newest first, at
  // most `limit`, results left out.
  absl::StatusOr<std::vector<v1::JobInfo>> ListJobs(const std::string& owner, v1::JobState state,
                                                    int limit);
  // A job as submitted. DataLoss when its record does not parse.
  absl::StatusOr<v1::Job> LoadJob(const std::string& id);
  // A job's stored events after sequence `after`, in order (those that do not parse left
  // out).
  absl::StatusOr<std::vector<v1::JobEvent>> LoadEvents(const std::string& id, int64_t after = 0);
  // Cancels a job: a queued one ends at once (`end` turns its info into the final one and
  // returns the final event), a running one gets cancel_requested for its runner. The job
  // as it is then; `ended` tells which.
  struct Cancelled {
    v1::JobInfo info;
    bool ended = false;
    std::string weather;  // the ended job's weather file, to release
  };
  absl::StatusOr<Cancelled> CancelJob(const std::string& id,
                                      const std::function<v1::JobEvent(v1::JobInfo&)>& end);
  // Removes a job and its events (a submission that could not be completed).
  absl::Status DeleteJob(const std::string& id);

  // ---- Work for the replicas' workers

  // The next job or site computation for `replica`: jobs whose lease expired first (they
  // were running), then the user served least recently, then jobs whose outdoor key is in
  // `preferred`, then the oldest. Not the ids in `excluded` (what this replica holds).
  // The claim's lease lasts `lease_ms` from now (the database's clock). None when no work
  // waits. When storing the claim fails, `candidate` names what it was for.
  absl::StatusOr<std::optional<Claim>> ClaimWork(const std::string& replica, int64_t lease_ms,
                                                 const std::vector<std::string>& preferred,
                                                 const std::vector<std::string>& excluded,
                                                 std::string* candidate = nullptr);
  // Renews the leases of `held` for `lease_ms`; for each, whether it is still held and
  // whether its job was asked to cancel.
  struct Renewal {
    bool held = false;
    bool cancel_requested = false;
  };
  absl::StatusOr<std::vector<Renewal>> RenewLeases(
      int64_t lease_ms, const std::vector<std::pair<Claim::Kind, Lease>>& held);
  // Ends every lease now (a single daemon at start: no one else can hold one), so what was
  // running is taken over at once.
  absl::Status ExpireLeases();
  // Gives a running job or site computation back: its lease ends now and another replica
  // (or this one) takes it over.
  absl::Status Release(Claim::Kind kind, const Lease& lease);

  // ---- A claimed job's writes: Aborted ("lease lost") once another claim took it

  // Replaces the job's info and appends `event` (numbered after the last stored one), and
  // its checkpoint when given (opaque bytes, replaced); `durable` = false for progress.
  // `cancel_requested`, when given, is set from the store.
  absl::Status UpdateJob(const Lease& lease, const v1::JobInfo& info, const v1::JobEvent* event,
                         bool durable = true, bool* cancel_requested = nullptr,
                         const std::string* checkpoint = nullptr);
  // The job's end: its final info and event; its earlier events and checkpoint are dropped.
  absl::Status FinishJob(const Lease& lease, const v1::JobInfo& info, const v1::JobEvent& event);
  // Stores the job's checkpoint (opaque bytes, replaced).
  absl::Status SaveCheckpoint(const Lease& lease, std::string_view bytes);
  // A job's last checkpoint, if any.
  absl::StatusOr<std::optional<std::string>> LoadCheckpoint(const std::string& id);

  // ---- Sites

  // Stores a new site (`info` in state READY or COMPUTING) with its registered scene and
  // uploaded weather file (may be empty); its info with the new id "site-N" and
  // has_weather. Checked in the same transaction against max_sites, max_sites_per_user and
  // max_upload_bytes_per_user.
  absl::StatusOr<v1::SiteInfo> InsertSite(v1::SiteInfo info, const v1::Scene& scene,
                                          std::string_view weather_epw, const v1::Limits& limits);
  struct StoredSite {
    v1::SiteInfo info;    // without the scene
    std::string weather;  // its weather file, or empty
  };
  // NotFound when unknown; a record that no longer parses is quarantined (and NotFound).
  absl::StatusOr<StoredSite> GetSite(const std::string& id);
  // `owner`'s sites (empty: everyone's), oldest first, without scenes.
  absl::StatusOr<std::vector<v1::SiteInfo>> ListSites(const std::string& owner);
  // A site's registered scene. DataLoss when it does not parse.
  absl::StatusOr<v1::Scene> LoadSiteScene(const std::string& id);
  // The size of a site's stored scene [bytes], without reading it.
  absl::StatusOr<int64_t> SiteSceneBytes(const std::string& id);
  // Stores what `update` makes of a site's info, read and written under the row's lock;
  // with `lease`, only while that claim holds it (Aborted otherwise), and the lease ends.
  // The info stored.
  absl::StatusOr<v1::SiteInfo> UpdateSite(const std::string& id, const Lease* lease,
                                          const std::function<void(v1::SiteInfo&)>& update);
  // Removes a site; what it was.
  absl::StatusOr<StoredSite> DeleteSite(const std::string& id);
  // Whether a site or a queued or running job uses the outdoor matrix with `key`.
  absl::StatusOr<bool> KeyInUse(const std::string& key);

  // ---- Uploaded weather files, by content (SHA-256)

  // A stored weather file's bytes.
  absl::StatusOr<std::string> ReadWeather(const std::string& weather);
  // Drops a reference (a job that ended, a site deleted); the file goes with the last one.
  void ReleaseWeather(const std::string& weather);
  // SQLite: counts the references of the stored sites and unfinished jobs to their files
  // and removes the files nothing refers to [files removed]; PostgreSQL: 0.
  absl::StatusOr<int> CountWeatherReferences();

  // ---- Outdoor matrices in the database (PostgreSQL; SQLite keeps them as files): the
  // bytes OutdoorCache encodes, with their SHA-256 checked on every read

  absl::Status PutMatrix(const std::string& key, std::string_view bytes);
  // None when not stored; DataLoss (and removed) when its checksum does not match.
  absl::StatusOr<std::optional<std::string>> GetMatrix(const std::string& key);
  absl::StatusOr<bool> HasMatrix(const std::string& key);
  // Removes a stored matrix (one whose bytes do not decode), so that it is traced again.
  absl::Status DeleteMatrix(const std::string& key);
  absl::StatusOr<std::vector<std::string>> MatrixKeys();

  // ---- Records that no longer parse

  struct Quarantined {
    std::string id;      // "job-N" or "site-N"
    std::string reason;  // what did not parse
  };
  // Moves every job and site whose info does not parse to the quarantine table.
  absl::StatusOr<std::vector<Quarantined>> QuarantineUnparsable();
  // Moves a job (`table` "jobs", its events stay) or a site ("sites") to the quarantine
  // table with `reason`.
  absl::Status Quarantine(const std::string& table, const std::string& id,
                          const std::string& reason);

  // ---- Users

  absl::Status InsertUser(const UserRecord& user) override;
  absl::StatusOr<std::vector<UserRecord>> LoadUsers() override;
  absl::Status RevokeUser(const std::string& name, int64_t unix_ms) override;

  // ---- Copying (fenestrad migrate)

  // Whether the store holds users, jobs or sites.
  absl::StatusOr<bool> Empty();
  // Copies everything into `target` in one transaction of the target: users, sites, jobs
  // with their events and checkpoints, quarantine, turns, counters, the weather files
  // sites and unfinished jobs use, and the outdoor matrices stored in the database (a
  // SQLite store's matrix files are the caller's to copy: PutMatrix). Ids are kept;
  // running jobs' leases end, so the target's replicas take them over from their
  // checkpoints. `target` must be empty unless `overwrite`, which clears it first
  // (FailedPrecondition otherwise). `progress` hears one line per table.
  absl::Status CopyTo(Store& target, bool overwrite,
                      const std::function<void(const std::string&)>& progress);

 private:
  Store(std::unique_ptr<Database> db, UploadStore* weather_files)
      : db_(std::move(db)), weather_files_(weather_files) {}
  // Runs `body` in a transaction.
  absl::Status Transact(const std::function<absl::Status(SqlSession&)>& body, bool durable = true,
                        bool write = true);
  // The SQL of this store's dialect.
  std::string Sql(std::string_view sql) const { return db_->Sql(sql); }
  // Stores an uploaded weather file in the transaction; its reference.
  absl::StatusOr<std::string> PutWeather(SqlSession& session, std::string_view bytes);
  // The queue as workers would take it: job id -> jobs ahead of it.
  absl::StatusOr<std::map<std::string, int>> QueuePositions(SqlSession& session);
  absl::Status QuarantineRow(SqlSession& session, const std::string& table, int64_t number,
                             const std::string& reason);
  // Checks the fence of a claimed job's write: Aborted when `changed` is 0.
  static absl::Status Fenced(const absl::StatusOr<SqlResult>& result, const Lease& lease);

  std::unique_ptr<Database> db_;
  UploadStore* const weather_files_;
};

// The payload (absl::Status::SetPayload) of the DataLoss a stored job or site answers
// with when its record no longer parses (LoadJob, CancelJob, LoadSiteScene, UpdateSite):
// the record's id. Its reader moves such a record to the quarantine table (Quarantine).
inline constexpr char kUnparsableRecordUrl[] =
    "type.googleapis.com/fenestra.store.UnparsableRecord";
// True when `status` is such a DataLoss.
bool IsUnparsableRecord(const absl::Status& status);

// Opens the store `url` names: "postgresql://user@host:port/db" (or "postgres://") with
// `connections` pooled connections; "sqlite:DIR" for DIR/fenestra.db without a data
// directory's files (users only: `fenestrad user`). InvalidArgument for anything else.
absl::StatusOr<std::unique_ptr<Store>> OpenStoreUrl(const std::string& url, int connections = 4);

// True when `url` names a PostgreSQL database.
bool IsPostgresUrl(const std::string& url);

}  // namespace fenestra
