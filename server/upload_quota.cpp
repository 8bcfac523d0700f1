#include "server/upload_quota.h"

#include "absl/strings/str_cat.h"

namespace fenestra {

absl::Status UploadQuota::Reserve(const std::string& user, int64_t bytes, bool force) {
  if (bytes <= 0) return absl::OkStatus();
  std::lock_guard lock(mutex_);
  int64_t& held = held_[user];
  if (!force && held + bytes > max_bytes_per_user_) {
    return absl::ResourceExhaustedError(
        absl::StrCat("limits.max_upload_bytes_per_user (", max_bytes_per_user_,
                     ") reached: your sites and "
                     "queued or running jobs hold ",
                     held, " bytes of weather files and this request brings ", bytes,
                     " more; delete a site, or wait until a job ends"));
  }
  held += bytes;
  return absl::OkStatus();
}

void UploadQuota::Release(const std::string& user, int64_t bytes) {
  if (bytes <= 0) return;
  std::lock_guard lock(mutex_);
  auto it = held_.find(user);
  if (it == held_.end()) return;
  it->second -= bytes;
  if (it->second <= 0) held_.erase(it);
}

int64_t UploadQuota::Held(const std::string& user) const {
  std::lock_guard lock(mutex_);
  auto it = held_.find(user);
  return it == held_.end() ? 0 : it->second;
}

}  // namespace fenestra
