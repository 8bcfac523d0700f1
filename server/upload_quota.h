#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "absl/status/status.h"

namespace fenestra {

// The uploads each user holds on the server: the weather files sent with their sites and
// with their queued or running jobs, counted as sent [bytes], against
// limits.max_upload_bytes_per_user. Thread-safe.
class UploadQuota {
 public:
  explicit UploadQuota(int64_t max_bytes_per_user) : max_bytes_per_user_(max_bytes_per_user) {}

  // Counts `bytes` more for `user`. ResourceExhausted naming the limit when that would pass
  // it, unless `force` (what a restart finds stored is counted whatever its size).
  absl::Status Reserve(const std::string& user, int64_t bytes, bool force = false);
  // Counts `bytes` less for `user` (a site deleted, a job ended).
  void Release(const std::string& user, int64_t bytes);
  // What `user` holds now [bytes].
  int64_t Held(const std::string& user) const;

 private:
  const int64_t max_bytes_per_user_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> held_;
};

}  // namespace fenestra
