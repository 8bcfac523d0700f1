#include "server/data_dir.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "server/checksum.h"

namespace fenestra {
namespace fs = std::filesystem;
namespace {

// Names of temporaries: "<name>.tmp.<pid>[.<n>]" (WriteFileDurably, WriteFileAtomically).
bool IsTemporary(const fs::path& path) {
  return path.filename().string().find(".tmp.") != std::string::npos;
}

// Writes all of `bytes` to `fd`; false with errno set on failure.
bool WriteAll(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = write(fd, bytes.data(), bytes.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = ENOSPC;
      return false;
    }
    bytes.remove_prefix(static_cast<size_t>(n));
  }
  return true;
}

// Syncs a folder, so a rename in it survives a power loss.
void SyncFolder(const fs::path& dir) {
  const int fd = open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  fsync(fd);
  close(fd);
}

}  // namespace

absl::Status StorageFullError() {
  return absl::ResourceExhaustedError("the server's storage is full; try later");
}

bool IsStorageFullErrno(int error_number) {
  return error_number == ENOSPC || error_number == EDQUOT || error_number == EFBIG;
}

absl::Status WriteFileDurably(const fs::path& path, std::string_view bytes) {
  static std::atomic<int64_t> counter = 0;
  const fs::path tmp = absl::StrCat(path.string(), ".tmp.", getpid(), ".", counter++);
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  bool ok = fd >= 0 && WriteAll(fd, bytes) && fsync(fd) == 0;
  int error = ok ? 0 : errno;
  if (fd >= 0 && close(fd) != 0 && ok) ok = false, error = errno;
  if (ok && rename(tmp.c_str(), path.c_str()) != 0) ok = false, error = errno;
  if (!ok) {
    unlink(tmp.c_str());
    spdlog::warn("cannot write {}: {}", path.string(), std::strerror(error));
    return IsStorageFullErrno(error) ? StorageFullError()
                                     : absl::InternalError("the server could not store a file");
  }
  SyncFolder(path.parent_path());
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<DataDir>> DataDir::Open(const fs::path& root, int64_t max_bytes) {
  std::unique_ptr<DataDir> d(new DataDir(root, max_bytes));
  const auto not_writable = [&](int error) {
    return absl::FailedPreconditionError(
        absl::StrCat("the data directory ", root.string(), " is read-only or not writable (",
                     std::strerror(error),
                     "); fenestrad keeps its job store and files there and needs to "
                     "write to it: give a writable --data-dir"));
  };
  std::error_code ec;
  fs::create_directories(root, ec);
  if (ec) {
    if (ec.value() == EROFS || ec.value() == EACCES || ec.value() == EPERM) {
      return not_writable(ec.value());
    }
    return absl::FailedPreconditionError(
        absl::StrCat("cannot create the data directory ", root.string(), ": ", ec.message()));
  }

  // One daemon per folder: a second one would run the same jobs and drop files the first
  // still uses
  d->lock_fd_ = open(root.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (d->lock_fd_ < 0) return not_writable(errno);
  if (flock(d->lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) {
      return absl::FailedPreconditionError(absl::StrCat(
          "the data directory ", root.string(),
          " is in use by another process (another fenestrad on this data directory?)"));
    }
    return absl::FailedPreconditionError(
        absl::StrCat("cannot lock the data directory ", root.string(), ": ", std::strerror(errno)));
  }

  // Whether a file can be created and written there
  const fs::path probe = root / ".fenestrad-write-test";
  const int fd = open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) {
    if (!IsStorageFullErrno(errno)) return not_writable(errno);
    d->full_at_start_ = true;
  } else {
    const std::string block(4096, '\0');
    if (!WriteAll(fd, block) || fsync(fd) != 0) {
      if (!IsStorageFullErrno(errno)) return not_writable(errno);
      d->full_at_start_ = true;
    }
    close(fd);
    unlink(probe.c_str());
  }

  for (const fs::path& dir : {d->outdoor_dir(), d->weather_dir()}) {
    fs::create_directories(dir, ec);
    if (ec && !IsStorageFullErrno(ec.value())) {
      return absl::FailedPreconditionError(
          absl::StrCat("cannot create ", dir.string(), ": ", ec.message()));
    }
    for (const auto& file : fs::directory_iterator(dir, ec)) {
      if (IsTemporary(file.path()) && fs::remove(file.path(), ec)) ++d->temporaries_removed_;
    }
  }
  return d;
}

DataDir::~DataDir() {
  if (lock_fd_ >= 0) close(lock_fd_);
}

int64_t DataDir::UsedBytes() const {
  int64_t total = 0;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root_, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    std::error_code size_error;
    if (it->is_regular_file(size_error)) {
      const uintmax_t size = it->file_size(size_error);
      if (!size_error) total += static_cast<int64_t>(size);
    }
  }
  return total;
}

void DataDir::SetEvictor(std::function<bool()> evict_one) {
  std::lock_guard lock(mutex_);
  evict_one_ = std::move(evict_one);
}

absl::Status DataDir::MakeRoom(int64_t bytes) const {
  std::lock_guard lock(mutex_);
  while (true) {
    const int64_t used = UsedBytes();
    if (used + bytes <= max_bytes_) return absl::OkStatus();
    if (!evict_one_ || !evict_one_()) {
      return absl::ResourceExhaustedError(absl::StrCat(
          "the server's data directory holds ", used, " bytes and this needs ", bytes,
          " more, above its limit max_data_dir_bytes = ", max_bytes_,
          "; delete sites that are no longer needed, or ask the operator to raise the limit"));
    }
  }
}

UploadStore::UploadStore(const DataDir& data_dir, fs::path dir, std::string extension)
    : data_dir_(data_dir), dir_(std::move(dir)), extension_(std::move(extension)) {}

std::string UploadStore::NameOf(const std::string& path) {
  return fs::path(path).filename().string();
}

absl::StatusOr<std::string> UploadStore::Add(std::string_view bytes) {
  const std::string name = absl::StrCat(Sha256Hex(bytes), ".", extension_);
  const fs::path path = dir_ / name;
  // Whether the content is stored already (mutex_ held)
  const auto stored = [&] {
    std::error_code ec;
    return references_.contains(name) || fs::exists(path, ec);
  };
  {
    std::lock_guard lock(mutex_);
    if (stored()) {
      ++references_[name];
      return path.string();
    }
  }
  // Room is made outside the lock: evicting may ask the sites and jobs what they use
  if (absl::Status s = data_dir_.MakeRoom(static_cast<int64_t>(bytes.size())); !s.ok()) {
    return s;
  }
  std::lock_guard lock(mutex_);
  if (!stored()) {
    if (absl::Status s = WriteFileDurably(path, bytes); !s.ok()) return s;
  }
  ++references_[name];
  return path.string();
}

void UploadStore::Ref(const std::string& path) {
  std::lock_guard lock(mutex_);
  ++references_[NameOf(path)];
}

void UploadStore::Unref(const std::string& path) {
  std::lock_guard lock(mutex_);
  const std::string name = NameOf(path);
  auto it = references_.find(name);
  if (it == references_.end()) return;
  if (--it->second > 0) return;
  references_.erase(it);
  std::error_code ec;
  fs::remove(dir_ / name, ec);
  if (ec) spdlog::warn("cannot remove {}: {}", (dir_ / name).string(), ec.message());
}

int UploadStore::References(const std::string& path) const {
  std::lock_guard lock(mutex_);
  auto it = references_.find(NameOf(path));
  return it == references_.end() ? 0 : it->second;
}

int UploadStore::RemoveUnreferenced() {
  std::lock_guard lock(mutex_);
  int removed = 0;
  std::error_code ec;
  for (const auto& file : fs::directory_iterator(dir_, ec)) {
    const std::string name = file.path().filename().string();
    if (IsTemporary(file.path())) continue;
    auto it = references_.find(name);
    if (it != references_.end() && it->second > 0) continue;
    std::error_code remove_error;
    if (fs::remove(file.path(), remove_error)) ++removed;
  }
  return removed;
}

}  // namespace fenestra
