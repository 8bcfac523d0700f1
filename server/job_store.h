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
// form and latest JobInfo, result included), every job event in order, sites and users.
// Thread-safe.
class JobStore final : public UserStore {
 public:
  // Opens or creates the database at `path` and its tables.
  static absl::StatusOr<std::unique_ptr<JobStore>> Open(const std::string& path);
  ~JobStore() override;
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // Stores a new job; returns its id "job-N" (N never reused), also set in `info`.
  absl::StatusOr<std::string> InsertJob(v1::JobInfo& info, const v1::Job& job);
  // Replaces a job's JobInfo (state, result, timings).
  absl::Status UpdateJob(const v1::JobInfo& info);
  // Removes a job and its events.
  absl::Status DeleteJob(const std::string& id);
  // Appends one event (its sequence must be new for the job).
  absl::Status AppendEvent(const std::string& id, const v1::JobEvent& event);

  struct StoredJob {
    v1::JobInfo info;  // last_sequence = the job's last stored event
    v1::Job job;
  };
  // Every job, oldest first.
  absl::StatusOr<std::vector<StoredJob>> LoadJobs();
  // A job's events in order.
  absl::StatusOr<std::vector<v1::JobEvent>> LoadEvents(const std::string& id);

  // Stores a new site; returns its id "site-N", also set in `info`.
  absl::StatusOr<std::string> InsertSite(v1::SiteInfo& info, const std::string& weather_path);
  // Replaces a site's SiteInfo.
  absl::Status UpdateSite(const v1::SiteInfo& info);
  absl::Status DeleteSite(const std::string& id);

  struct StoredSite {
    v1::SiteInfo info;
    std::string weather_path;  // uploaded weather file in the data directory, or empty
  };
  // Every site, oldest first.
  absl::StatusOr<std::vector<StoredSite>> LoadSites();

  // UserStore
  absl::Status InsertUser(const UserRecord& user) override;
  absl::StatusOr<std::vector<UserRecord>> LoadUsers() override;
  absl::Status RevokeUser(const std::string& name, int64_t unix_ms) override;

 private:
  explicit JobStore(sqlite3* db) : db_(db) {}
  absl::Status Exec(const std::string& sql);

  std::mutex mutex_;
  sqlite3* db_;
};

}  // namespace fenestra
