#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/job.pb.h"
#include "fenestra/v1/service.pb.h"

struct sqlite3;

namespace fenestra {

// A user of the daemon as stored; the token only as its SHA-256.
struct UserRecord {
  std::string name;
  std::string token_sha256;  // 32 raw bytes
  bool admin = false;
  int64_t created_unix_ms = 0;
  int64_t revoked_unix_ms = 0;  // 0 while the token is valid
};

// Where the users live. JobStore keeps them in its SQLite file; the interface lets
// another database take them over.
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

// The daemon's persistent state in one SQLite file (WAL journal): jobs (their submitted
// form and latest JobInfo, result included), the events of unfinished jobs, sites (their
// SiteInfo and registered scene), users, and a quarantine table for records that no
// longer parse. Every change is one transaction; state changes are synced to disk before
// the call returns. Errors carry no paths: a full disk is StorageFullError
// (RESOURCE_EXHAUSTED), anything else Internal. Thread-safe.
class JobStore final : public UserStore {
 public:
  // Who else may open the file while this process has it open.
  enum class Sharing {
    // Other processes too (`fenestrad user` beside a running daemon); the WAL index lives
    // in a -shm file next to the database.
    kShared,
    // This process alone (another gets FailedPrecondition); the WAL index lives in
    // memory, so a store on a full disk, where no -shm file can be made, still opens.
    kExclusive,
  };
  // Opens or creates the database at `path` and its tables. FailedPrecondition naming the
  // file when it is read-only or, kExclusive, another process holds it.
  static absl::StatusOr<std::unique_ptr<JobStore>> Open(const std::string& path,
                                                        Sharing sharing = Sharing::kShared);
  ~JobStore() override;
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Stores a new job and, when given, its first event; returns its id "job-N" (N never
  // reused), also set in `info` (and as the event's job).
  absl::StatusOr<std::string> InsertJob(v1::JobInfo& info, const v1::Job& job,
                                        const v1::JobEvent* first_event = nullptr);
  // Replaces a job's JobInfo and appends `event` when given (its sequence must be new for
  // the job). `durable` = false for progress: a crash may then lose the latest progress,
  // never a state.
  absl::Status UpdateJob(const v1::JobInfo& info, const v1::JobEvent* event = nullptr,
                         bool durable = true);
  // A job's end: replaces its JobInfo, appends its final event and drops its earlier
  // events (the final JobInfo holds what they said).
  absl::Status FinishJob(const v1::JobInfo& info, const v1::JobEvent& event);
  // Removes a job and its events.
  absl::Status DeleteJob(const std::string& id);
  // Appends one event (its sequence must be new for the job).
  absl::Status AppendEvent(const std::string& id, const v1::JobEvent& event);

  // A record that did not parse, moved to the quarantine table.
  struct Quarantined {
    std::string id;      // "job-N" or "site-N"
    std::string reason;  // what did not parse
  };

  struct StoredJobs {
    std::vector<v1::JobInfo> jobs;  // oldest first; last_sequence = the last stored event
    std::vector<Quarantined> quarantined;
  };
  // Every job's JobInfo. Those that do not parse are moved to the quarantine table and
  // listed in `quarantined` instead.
  absl::StatusOr<StoredJobs> LoadJobs();
  // A job as submitted. DataLoss when its record does not parse.
  absl::StatusOr<v1::Job> LoadJob(const std::string& id);
  // A job's stored events in order (those that do not parse left out).
  absl::StatusOr<std::vector<v1::JobEvent>> LoadEvents(const std::string& id);

  // Stores a new site with its registered scene; returns its id "site-N", also set in
  // `info`.
  absl::StatusOr<std::string> InsertSite(v1::SiteInfo& info, const std::string& weather_path,
                                         const v1::Scene& scene);
  // Replaces a site's SiteInfo.
  absl::Status UpdateSite(const v1::SiteInfo& info);
  absl::Status DeleteSite(const std::string& id);

  struct StoredSite {
    v1::SiteInfo info;         // without the scene
    std::string weather_path;  // uploaded weather file in the data directory, or empty
  };
  struct StoredSites {
    std::vector<StoredSite> sites;  // oldest first
    std::vector<Quarantined> quarantined;
  };
  // Every site. Those that do not parse are moved to the quarantine table and listed in
  // `quarantined` instead.
  absl::StatusOr<StoredSites> LoadSites();
  // A site's registered scene. DataLoss when its record does not parse.
  absl::StatusOr<v1::Scene> LoadSiteScene(const std::string& id);
  // The size of a site's stored scene [bytes], without reading it.
  absl::StatusOr<int64_t> SiteSceneBytes(const std::string& id);

  // Moves a job (`table` "jobs", its events stay) or a site ("sites") to the quarantine
  // table with `reason`.
  absl::Status Quarantine(const std::string& table, const std::string& id,
                          const std::string& reason);

  // UserStore
  absl::Status InsertUser(const UserRecord& user) override;
  absl::StatusOr<std::vector<UserRecord>> LoadUsers() override;
  absl::Status RevokeUser(const std::string& name, int64_t unix_ms) override;

 private:
  explicit JobStore(sqlite3* db) : db_(db) {}
  // Runs SQL without results (mutex_ held).
  absl::Status Exec(const char* sql);
  // Runs `body` in one transaction (mutex_ held), synced to disk before it returns when
  // `durable`; rolled back when `body` or the commit fails.
  template <typename Body>
  absl::Status Transaction(bool durable, Body&& body);
  absl::Status QuarantineLocked(const std::string& table, int64_t number,
                                const std::string& reason);

  std::mutex mutex_;
  sqlite3* db_;
};

}  // namespace fenestra
