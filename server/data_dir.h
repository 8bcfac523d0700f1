#pragma once

// What fenestrad keeps under its data directory: the job store (fenestra.db), the cached
// outdoor matrices (outdoor/) and the uploaded weather files (weather/); the room they take
// against limits.max_data_dir_bytes; and file writes that tell a full disk from other
// failures. Messages meant for clients carry no server paths.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace fenestra {

// RESOURCE_EXHAUSTED "the server's storage is full; try later": what a client gets for a
// write refused because the disk under the data directory is full.
absl::Status StorageFullError();

// Whether a failed write's errno means the storage is full (ENOSPC, EDQUOT, EFBIG).
bool IsStorageFullErrno(int error_number);

// Writes `bytes` to `path` through a temporary sibling that is synced to disk and then
// renamed onto it, so `path` holds either nothing or all of it. StorageFullError when the
// disk is full, Internal otherwise; the path and the system's reason are logged, not
// returned.
absl::Status WriteFileDurably(const std::filesystem::path& path, std::string_view bytes);

// The data directory. Thread-safe.
class DataDir {
 public:
  // Creates the folder and its subfolders when missing, locks the folder for this process
  // (flock, released when the DataDir is destroyed: one daemon per data directory), checks
  // that fenestrad may write there and removes the temporaries of interrupted writes.
  // FailedPrecondition naming the folder when another process holds it or it is read-only
  // or not writable. A full disk is no error: the daemon serves reads and refuses writes
  // (full_at_start() says so).
  static absl::StatusOr<std::unique_ptr<DataDir>> Open(const std::filesystem::path& root,
                                                       int64_t max_bytes);
  ~DataDir();
  DataDir(const DataDir&) = delete;
  DataDir& operator=(const DataDir&) = delete;

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path db_path() const { return root_ / "fenestra.db"; }
  std::filesystem::path outdoor_dir() const { return root_ / "outdoor"; }
  std::filesystem::path weather_dir() const { return root_ / "weather"; }
  int64_t max_bytes() const { return max_bytes_; }
  // The disk had no room for even an empty file when the daemon started.
  bool full_at_start() const { return full_at_start_; }
  // Temporaries of interrupted writes removed at Open [count].
  int temporaries_removed() const { return temporaries_removed_; }

  // Size of every file under the folder now [bytes].
  int64_t UsedBytes() const;

  // Sets what frees room: it removes one file the daemon may drop (a cached outdoor
  // matrix nothing uses) and returns false when there is none.
  void SetEvictor(std::function<bool()> evict_one);
  // Makes room for `bytes` more [bytes]: while they would take the folder over max_bytes,
  // calls the evictor; then ResourceExhausted naming limits.max_data_dir_bytes when they
  // still do not fit.
  absl::Status MakeRoom(int64_t bytes) const;

 private:
  DataDir(std::filesystem::path root, int64_t max_bytes) : root_(root), max_bytes_(max_bytes) {}

  const std::filesystem::path root_;
  const int64_t max_bytes_;
  int lock_fd_ = -1;  // the folder, flock'ed
  bool full_at_start_ = false;
  int temporaries_removed_ = 0;
  mutable std::mutex mutex_;
  std::function<bool()> evict_one_;
};

// Uploaded files kept once by content, as <folder>/<sha256>.<extension>, each for as long
// as something refers to it (a site, a queued or running job): the last reference dropped
// removes the file. References are counted in memory; at start the daemon counts those of
// its stored sites and unfinished jobs, then drops the files nothing refers to.
// Thread-safe.
class UploadStore {
 public:
  UploadStore(const DataDir& data_dir, std::filesystem::path dir, std::string extension);

  // Stores `bytes` unless a file with that content is there, and counts a reference to it;
  // returns its path. ResourceExhausted when it would take the data directory over its
  // limit or the disk is full.
  absl::StatusOr<std::string> Add(std::string_view bytes);
  // Counts one more reference to a stored file (a path Add returned).
  void Ref(const std::string& path);
  // Drops a reference to a stored file; the last one removes it.
  void Unref(const std::string& path);
  // References to a stored file [count].
  int References(const std::string& path) const;
  // Removes the files of the folder nothing refers to [count removed].
  int RemoveUnreferenced();
  // The folder.
  const std::filesystem::path& dir() const { return dir_; }

 private:
  // The file name a path is counted under (<sha256>.<extension>).
  static std::string NameOf(const std::string& path);

  const DataDir& data_dir_;
  const std::filesystem::path dir_;
  const std::string extension_;
  mutable std::mutex mutex_;
  std::map<std::string, int> references_;  // by file name
};

}  // namespace fenestra
