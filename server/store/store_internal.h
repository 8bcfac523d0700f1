#pragma once

// What the files of Store (server/store/store*.cpp) share: the states and locks their SQL
// names, blobs, messages and the admission checks. Not for use outside server/store/.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/cord.h"
#include "absl/strings/str_cat.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/job.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/store/database.h"
#include "server/store/store.h"

namespace fenestra::store_internal {

// The lock every admission (a job or site stored against the limits) and every removal
// of a weather file takes, so that counts and references are read as they stand.
inline constexpr int64_t kAdmissionLock = 1;
inline constexpr int64_t kQueued = v1::JOB_STATE_QUEUED;
inline constexpr int64_t kRunning = v1::JOB_STATE_RUNNING;
inline constexpr int64_t kComputing = v1::SITE_STATE_COMPUTING;

// A JobInfo as the jobs table keeps it: `info` without the result (the bulk of a finished
// job's record, which listings do not read), and `result` the result alone as a JobInfo
// serialization holding only that field (so that `info` then `result` parse as the whole),
// NULL without one.
struct JobInfoColumns {
  std::string info;
  std::optional<std::string> result;
  SqlParam Info() const { return SqlBlob{info}; }
  SqlParam Result() const { return result ? SqlParam(SqlBlob{*result}) : SqlParam(nullptr); }
};
JobInfoColumns ColumnsOf(const v1::JobInfo& info);
// The whole JobInfo from a row's info and result columns (the result NULL or not).
bool ParseJobInfo(v1::JobInfo& info, const SqlRow& row, size_t info_column, size_t result_column);
template <typename Message>
bool Parse(Message& message, const std::string& bytes) {
  return message.ParseFromString(bytes);
}

inline SqlBlob Blob(const std::string& bytes) { return SqlBlob{bytes}; }
// A blob of no bytes (not NULL).
inline constexpr SqlBlob kNoBytes{std::string_view("", 0)};

inline absl::Status NoJob(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no job '", id, "' is stored"));
}
inline absl::Status NoSite(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no site '", id, "' is stored"));
}

// The DataLoss of a record `id` that does not parse: `message`, with the payload
// kUnparsableRecordUrl.
inline absl::Status UnparsableRecord(const std::string& id, const std::string& message) {
  absl::Status status = absl::DataLossError(message);
  status.SetPayload(kUnparsableRecordUrl, absl::Cord(id));
  return status;
}

inline std::string WeatherFileName(const std::string& weather) { return weather + ".epw"; }

// `(?, ?, ...)` for `n` values.
inline std::string Placeholders(size_t n) {
  std::string out = "(";
  for (size_t i = 0; i < n; ++i) absl::StrAppend(&out, i ? ", ?" : "?");
  return out + ")";
}

// Checks that `owner`'s uploads (weather files of its sites and queued or running jobs)
// and `bytes` more stay within max_upload_bytes_per_user; ResourceExhausted naming it.
absl::Status CheckUploadQuota(SqlSession& s, const std::string& owner, int64_t bytes,
                              const v1::Limits& limits);
// Counts the counter `name` up; its new value.
absl::StatusOr<int64_t> NextCounter(SqlSession& s, const char* name);

}  // namespace fenestra::store_internal
