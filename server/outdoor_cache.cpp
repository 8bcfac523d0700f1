#include "server/outdoor_cache.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "fenestra/v1/daemon.pb.h"
#include "server/checksum.h"
#include "server/store/store.h"

namespace fenestra {
namespace {

constexpr char kMagic[8] = {'F', 'N', 'S', 'T', 'R', 'O', 'M', 'X'};
constexpr uint32_t kVersion = 2;
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 32;

void PutLittleEndian(std::string& out, uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((value >> (8 * i)) & 0xff));
}

uint64_t GetLittleEndian(std::string_view in, size_t offset, int bytes) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) {
    value |= static_cast<uint64_t>(static_cast<unsigned char>(in[offset + i])) << (8 * i);
  }
  return value;
}

}  // namespace

std::string EncodeOutdoorMatrix(const OutdoorMatrix& matrix) {
  v1::OutdoorMatrixEntry entry;
  entry.set_key(matrix.key);
  entry.set_rows(static_cast<int32_t>(matrix.coefficients.rows()));
  entry.set_cols(static_cast<int32_t>(matrix.coefficients.cols()));
  const Eigen::Index n = matrix.coefficients.size();
  entry.mutable_coefficients()->Add(matrix.coefficients.data(), matrix.coefficients.data() + n);
  if (matrix.standard_error.size() == n) {
    entry.mutable_standard_error()->Add(matrix.standard_error.data(),
                                        matrix.standard_error.data() + n);
  }
  entry.set_basis_cells(matrix.basis_cells);
  entry.set_window_columns(matrix.parts.columns);
  entry.set_window_rows(matrix.parts.rows);
  entry.set_paths(matrix.paths);
  entry.set_bounces(matrix.bounces);
  entry.set_seed(matrix.seed);
  entry.set_wall_seconds(matrix.wall_seconds);
  entry.set_backend(matrix.backend);
  entry.set_batches(static_cast<int32_t>(matrix.batches.size()));
  for (const Matrix& b : matrix.batches) {
    entry.mutable_batch_coefficients()->Add(b.data(), b.data() + b.size());
  }
  const std::string payload = entry.SerializeAsString();

  std::string out(kMagic, sizeof(kMagic));
  PutLittleEndian(out, kVersion, 4);
  PutLittleEndian(out, 0, 4);
  PutLittleEndian(out, payload.size(), 8);
  out += Sha256(payload);
  out += payload;
  return out;
}

absl::StatusOr<OutdoorMatrix> DecodeOutdoorMatrix(std::string_view bytes) {
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return absl::DataLossError("not an outdoor matrix cache file (bad header)");
  }
  if (GetLittleEndian(bytes, 8, 4) != kVersion) {
    return absl::DataLossError(
        absl::StrCat("unsupported cache file version ", GetLittleEndian(bytes, 8, 4)));
  }
  const uint64_t size = GetLittleEndian(bytes, 16, 8);
  const std::string_view payload = bytes.substr(kHeaderBytes);
  if (payload.size() != size) {
    return absl::DataLossError(absl::StrCat("payload is ", payload.size(),
                                            " bytes, the header says ", size, " (truncated file)"));
  }
  if (Sha256(payload) != bytes.substr(24, 32)) {
    return absl::DataLossError("SHA-256 checksum mismatch (corrupted file)");
  }
  v1::OutdoorMatrixEntry entry;
  if (!entry.ParseFromArray(payload.data(), static_cast<int>(payload.size()))) {
    return absl::DataLossError("payload does not parse");
  }
  const int64_t n = int64_t{entry.rows()} * entry.cols();
  if (entry.rows() <= 0 || entry.cols() <= 0 || entry.coefficients_size() != n ||
      (entry.standard_error_size() != 0 && entry.standard_error_size() != n) ||
      entry.batches() < 2 || entry.batch_coefficients_size() != n * entry.batches()) {
    return absl::DataLossError("matrix sizes do not match");
  }
  OutdoorMatrix matrix;
  matrix.key = entry.key();
  matrix.coefficients = Matrix(entry.rows(), entry.cols());
  std::copy(entry.coefficients().begin(), entry.coefficients().end(), matrix.coefficients.data());
  if (entry.standard_error_size() == n) {
    matrix.standard_error = Matrix(entry.rows(), entry.cols());
    std::copy(entry.standard_error().begin(), entry.standard_error().end(),
              matrix.standard_error.data());
  }
  for (int b = 0; b < entry.batches(); ++b) {
    Matrix batch(entry.rows(), entry.cols());
    std::copy_n(entry.batch_coefficients().begin() + b * n, n, batch.data());
    matrix.batches.push_back(std::move(batch));
  }
  matrix.basis_cells = entry.basis_cells();
  // Sides of 0: each window's automatic split (a scene of several windows), or, in an entry of
  // one window's rows, from before the window had parts (one part)
  matrix.parts = {entry.window_columns(), entry.window_rows()};
  if (entry.window_columns() == 0 && entry.window_rows() == 0 &&
      entry.rows() == OutdoorRowCount(entry.basis_cells())) {
    matrix.parts = {1, 1};
  }
  matrix.paths = entry.paths();
  matrix.bounces = entry.bounces();
  matrix.seed = entry.seed();
  matrix.wall_seconds = entry.wall_seconds();
  matrix.backend = entry.backend();
  return matrix;
}

OutdoorCache::OutdoorCache(std::string dir, const DataDir* data_dir, int64_t memory_bytes)
    : dir_(std::move(dir)), data_dir_(data_dir), memory_bytes_(memory_bytes) {}

OutdoorCache::OutdoorCache(Store& store, int64_t memory_bytes)
    : store_(&store), memory_bytes_(memory_bytes) {}

std::string OutdoorCache::PathFor(const std::string& key) const {
  return (std::filesystem::path(dir_) / (Sha256Hex(key) + ".omx")).string();
}

namespace {

// A cache file's matrix; DataLoss when it is unreadable, corrupt or holds another key
// (`key` empty: any).
absl::StatusOr<OutdoorMatrix> ReadMatrixFile(const std::string& path, const std::string& key) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return absl::DataLossError("cannot be read");
  std::string bytes(static_cast<size_t>(in.tellg()), '\0');
  in.seekg(0);
  if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) {
    return absl::DataLossError("cannot be read");
  }
  absl::StatusOr<OutdoorMatrix> matrix = DecodeOutdoorMatrix(bytes);
  if (matrix.ok() && !key.empty() && matrix->key != key) {
    return absl::DataLossError("file name does not match the key inside");
  }
  return matrix;
}

int64_t MatrixBytes(const OutdoorMatrix& m) {
  int64_t values = m.coefficients.size() + m.standard_error.size();
  for (const Matrix& batch : m.batches) values += batch.size();
  return static_cast<int64_t>(sizeof(double)) * values;
}

}  // namespace

absl::StatusOr<OutdoorCache::LoadReport> OutdoorCache::Load() {
  LoadReport report;
  if (store_) {
    absl::StatusOr<std::vector<std::string>> keys = store_->MatrixKeys();
    if (!keys.ok()) return keys.status();
    std::lock_guard lock(mutex_);
    for (const std::string& key : *keys) {
      Entry& entry = entries_[key];
      entry.from_disk = true;
      entry.last_used = ++uses_;
      ++report.loaded;
    }
    return report;
  }
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  if (error) {
    return absl::InternalError(absl::StrCat("cannot create ", dir_, ": ", error.message()));
  }
  // Oldest first, so the use order starts as the files' age
  std::vector<std::pair<std::filesystem::file_time_type, std::filesystem::path>> files;
  for (const auto& file : std::filesystem::directory_iterator(dir_, error)) {
    if (file.path().extension() != ".omx") continue;
    std::error_code time_error;
    files.push_back({file.last_write_time(time_error), file.path()});
  }
  if (error) {
    return absl::InternalError(absl::StrCat("cannot list ", dir_, ": ", error.message()));
  }
  std::sort(files.begin(), files.end());
  std::lock_guard lock(mutex_);
  for (const auto& [time, file] : files) {
    const std::string path = file.string();
    absl::StatusOr<OutdoorMatrix> matrix = ReadMatrixFile(path, "");
    if (matrix.ok() && PathFor(matrix->key) != path) {
      matrix = absl::DataLossError("file name does not match the key inside");
    }
    if (!matrix.ok()) {
      report.discarded.push_back(absl::StrCat(path, ": ", matrix.status().message()));
      std::filesystem::remove(file, error);
      continue;
    }
    Entry& entry = entries_[matrix->key];
    entry.from_disk = true;
    entry.last_used = ++uses_;
    ++report.loaded;
  }
  return report;
}

absl::StatusOr<OutdoorMatrix> OutdoorCache::ReadBack(const std::string& key) {
  if (store_) {
    absl::StatusOr<std::optional<std::string>> bytes = store_->GetMatrix(key);
    if (!bytes.ok()) return bytes.status();
    if (!*bytes) return absl::NotFoundError("not stored");
    absl::StatusOr<OutdoorMatrix> matrix = DecodeOutdoorMatrix(**bytes);
    if (matrix.ok() && matrix->key != key) {
      return absl::DataLossError("the stored matrix holds another key");
    }
    return matrix;
  }
  const std::string path = PathFor(key);
  absl::StatusOr<OutdoorMatrix> matrix = ReadMatrixFile(path, key);
  if (!matrix.ok()) {
    spdlog::warn("outdoor cache: discarded {}: {}", path, std::string(matrix.status().message()));
    std::error_code error;
    std::filesystem::remove(path, error);
  }
  return matrix;
}

absl::Status OutdoorCache::WriteOut(const OutdoorMatrix& matrix) {
  const std::string bytes = EncodeOutdoorMatrix(matrix);
  if (store_) return store_->PutMatrix(matrix.key, bytes);
  // Room is made outside the lock: evicting asks the sites and jobs what they use
  absl::Status written =
      data_dir_ ? data_dir_->MakeRoom(static_cast<int64_t>(bytes.size())) : absl::OkStatus();
  if (written.ok()) written = WriteFileDurably(PathFor(matrix.key), bytes);
  return written;
}

void OutdoorCache::DropRecent(const std::string& key) {
  for (auto it = recent_.begin(); it != recent_.end(); ++it) {
    if (it->first != key) continue;
    recent_bytes_ -= MatrixBytes(*it->second);
    recent_.erase(it);
    return;
  }
}

void OutdoorCache::KeepRecent(const std::string& key, std::shared_ptr<const OutdoorMatrix> matrix) {
  DropRecent(key);
  recent_bytes_ += MatrixBytes(*matrix);
  recent_.emplace_front(key, std::move(matrix));
  while (!recent_.empty() && recent_bytes_ > memory_bytes_) {
    recent_bytes_ -= MatrixBytes(*recent_.back().second);
    recent_.pop_back();
  }
}

bool OutdoorCache::HeldOutside(const std::string& key, const Entry& entry) const {
  const bool recent = std::any_of(recent_.begin(), recent_.end(),
                                  [&](const auto& kept) { return kept.first == key; });
  return entry.held.use_count() > (recent ? 1 : 0);
}

absl::StatusOr<std::shared_ptr<const OutdoorMatrix>> OutdoorCache::FindOrError(
    const std::string& key) {
  {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(key);
    if (it == entries_.end() && !store_) return nullptr;
    if (it != entries_.end()) {
      it->second.last_used = ++uses_;
      if (it->second.kept) return it->second.kept;
      if (auto held = it->second.held.lock()) {
        KeepRecent(key, held);
        return held;
      }
    }
  }
  // Read it back, outside the lock (megabytes)
  absl::StatusOr<OutdoorMatrix> matrix = ReadBack(key);
  std::lock_guard lock(mutex_);
  auto it = entries_.find(key);
  if (it == entries_.end() && !store_) return nullptr;  // evicted meanwhile
  if (it != entries_.end()) {
    if (it->second.kept) return it->second.kept;
    if (auto held = it->second.held.lock()) return held;  // read by another caller meanwhile
  }
  if (!matrix.ok()) {
    if (it != entries_.end()) entries_.erase(it);
    const absl::StatusCode code = matrix.status().code();
    if (code == absl::StatusCode::kNotFound) return nullptr;
    if (code == absl::StatusCode::kDataLoss) {
      if (store_) {
        spdlog::warn("outdoor cache: discarded the stored matrix {}: {}", key.substr(0, 16),
                     std::string(matrix.status().message()));
        (void)store_->DeleteMatrix(key);
      }
      return nullptr;
    }
    return matrix.status();
  }
  auto shared = std::make_shared<const OutdoorMatrix>(*std::move(matrix));
  const bool known = it != entries_.end();
  Entry& entry = entries_[key];
  if (!known) entry.from_disk = true;  // another replica's
  entry.held = shared;
  entry.last_used = ++uses_;
  KeepRecent(key, shared);
  return shared;
}

std::shared_ptr<const OutdoorMatrix> OutdoorCache::Find(const std::string& key) {
  absl::StatusOr<std::shared_ptr<const OutdoorMatrix>> found = FindOrError(key);
  if (!found.ok()) {
    spdlog::warn("outdoor cache: matrix {} cannot be read: {}", key.substr(0, 16),
                 std::string(found.status().message()));
    return nullptr;
  }
  return *found;
}

bool OutdoorCache::Contains(const std::string& key) const {
  {
    std::lock_guard lock(mutex_);
    if (entries_.contains(key)) return true;
  }
  if (!store_) return false;
  absl::StatusOr<bool> stored = store_->HasMatrix(key);
  return stored.ok() && *stored;
}

bool OutdoorCache::LoadedFromDisk(const std::string& key) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(key);
  return it != entries_.end() ? it->second.from_disk : store_ != nullptr;
}

std::vector<std::string> OutdoorCache::KeysInMemory() const {
  std::lock_guard lock(mutex_);
  std::vector<std::pair<int64_t, std::string>> used;
  for (const auto& [key, entry] : entries_) {
    if (entry.kept || !entry.held.expired()) used.push_back({entry.last_used, key});
  }
  for (const auto& [key, matrix] : recent_) {
    auto it = entries_.find(key);
    if (it != entries_.end() && !it->second.kept && it->second.held.expired()) {
      used.push_back({it->second.last_used, key});
    }
  }
  std::sort(used.rbegin(), used.rend());
  std::vector<std::string> keys;
  for (auto& [last_used, key] : used) keys.push_back(std::move(key));
  return keys;
}

absl::Status OutdoorCache::Put(std::shared_ptr<const OutdoorMatrix> matrix) {
  const absl::Status written = WriteOut(*matrix);
  {
    std::lock_guard lock(mutex_);
    Entry& entry = entries_[matrix->key];
    entry.held = matrix;
    entry.kept = written.ok() ? nullptr : matrix;
    entry.from_disk = false;
    entry.last_used = ++uses_;
    KeepRecent(matrix->key, matrix);
  }
  changed_.notify_all();
  return written;
}

void OutdoorCache::SetInUse(std::function<bool(const std::string& key)> in_use) {
  std::lock_guard lock(mutex_);
  in_use_ = std::move(in_use);
}

bool OutdoorCache::EvictOne() {
  if (store_) return false;  // the store keeps every matrix
  std::vector<std::pair<int64_t, std::string>> candidates;
  std::function<bool(const std::string&)> in_use;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [key, entry] : entries_) {
      if (!entry.kept && !HeldOutside(key, entry) && !computing_.contains(key)) {
        candidates.push_back({entry.last_used, key});
      }
    }
    in_use = in_use_;
  }
  std::sort(candidates.begin(), candidates.end());
  // What the sites and jobs use is asked outside the lock (they take their own locks)
  for (const auto& [last_used, key] : candidates) {
    if (in_use && in_use(key)) continue;
    {
      std::lock_guard lock(mutex_);
      auto it = entries_.find(key);
      if (it == entries_.end() || it->second.last_used != last_used || it->second.kept ||
          HeldOutside(key, it->second)) {
        continue;
      }
      DropRecent(key);
      entries_.erase(it);
    }
    std::error_code error;
    std::filesystem::remove(PathFor(key), error);
    spdlog::info(
        "outdoor cache: evicted matrix {} (least recently used; no site or unfinished "
        "job uses it) to make room",
        key.substr(0, 16));
    return true;
  }
  return false;
}

absl::StatusOr<OutdoorCache::Lookup> OutdoorCache::GetOrCompute(
    const std::string& key, const std::function<absl::StatusOr<OutdoorMatrix>()>& compute,
    const std::function<bool()>& cancelled) {
  while (true) {
    absl::StatusOr<std::shared_ptr<const OutdoorMatrix>> found = FindOrError(key);
    if (!found.ok()) return found.status();
    if (*found) return Lookup{*found, false};
    std::unique_lock lock(mutex_);
    if (entries_.contains(key)) continue;  // cached meanwhile
    if (!computing_.contains(key)) {
      computing_.insert(key);
      break;
    }
    if (cancelled && cancelled()) {
      return absl::CancelledError("cancelled while waiting for the outdoor matrix");
    }
    changed_.wait_for(lock, std::chrono::milliseconds(200));
  }
  absl::StatusOr<OutdoorMatrix> result = compute();
  std::shared_ptr<const OutdoorMatrix> matrix;
  if (result.ok()) {
    result->key = key;
    matrix = std::make_shared<const OutdoorMatrix>(*std::move(result));
    if (absl::Status written = Put(matrix); !written.ok()) {
      spdlog::warn("outdoor matrix {} kept in memory only: {}", key.substr(0, 16),
                   std::string(written.message()));
    }
  }
  {
    std::lock_guard lock(mutex_);
    computing_.erase(key);
  }
  changed_.notify_all();
  if (!result.ok()) return result.status();
  return Lookup{matrix, true};
}

}  // namespace fenestra
