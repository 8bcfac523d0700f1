#include "server/outdoor_cache.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "core/common/atomic_file.h"
#include "fenestra/v1/daemon.pb.h"
#include "server/checksum.h"

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
  matrix.parts = {std::max(1, entry.window_columns()), std::max(1, entry.window_rows())};
  matrix.paths = entry.paths();
  matrix.bounces = entry.bounces();
  matrix.seed = entry.seed();
  matrix.wall_seconds = entry.wall_seconds();
  matrix.backend = entry.backend();
  return matrix;
}

OutdoorCache::OutdoorCache(std::string dir) : dir_(std::move(dir)) {}

std::string OutdoorCache::PathFor(const std::string& key) const {
  return (std::filesystem::path(dir_) / (Sha256Hex(key) + ".omx")).string();
}

absl::StatusOr<OutdoorCache::LoadReport> OutdoorCache::Load() {
  std::error_code error;
  std::filesystem::create_directories(dir_, error);
  if (error) {
    return absl::InternalError(absl::StrCat("cannot create ", dir_, ": ", error.message()));
  }
  LoadReport report;
  std::lock_guard lock(mutex_);
  for (const auto& file : std::filesystem::directory_iterator(dir_, error)) {
    const std::string path = file.path().string();
    if (file.path().extension() != ".omx") {
      // Temporaries of an interrupted write
      if (path.find(".omx") != std::string::npos) std::filesystem::remove(file.path(), error);
      continue;
    }
    std::ifstream in(path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    absl::StatusOr<OutdoorMatrix> matrix = DecodeOutdoorMatrix(bytes.str());
    if (matrix.ok() && PathFor(matrix->key) != path) {
      matrix = absl::DataLossError("file name does not match the key inside");
    }
    if (!matrix.ok()) {
      report.discarded.push_back(absl::StrCat(path, ": ", matrix.status().message()));
      std::filesystem::remove(file.path(), error);
      continue;
    }
    const std::string key = matrix->key;
    entries_[key] = std::make_shared<const OutdoorMatrix>(*std::move(matrix));
    from_disk_.insert(key);
    ++report.loaded;
  }
  if (error) {
    return absl::InternalError(absl::StrCat("cannot list ", dir_, ": ", error.message()));
  }
  return report;
}

std::shared_ptr<const OutdoorMatrix> OutdoorCache::Find(const std::string& key) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(key);
  return it == entries_.end() ? nullptr : it->second;
}

bool OutdoorCache::LoadedFromDisk(const std::string& key) const {
  std::lock_guard lock(mutex_);
  return from_disk_.contains(key);
}

absl::Status OutdoorCache::Put(std::shared_ptr<const OutdoorMatrix> matrix) {
  const std::string bytes = EncodeOutdoorMatrix(*matrix);
  {
    std::lock_guard lock(mutex_);
    from_disk_.erase(matrix->key);
    entries_[matrix->key] = matrix;
  }
  changed_.notify_all();
  return WriteFileAtomically(
      PathFor(matrix->key),
      [&](std::ostream& out) {
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        return absl::OkStatus();
      },
      /*binary=*/true);
}

absl::StatusOr<OutdoorCache::Lookup> OutdoorCache::GetOrCompute(
    const std::string& key, const std::function<absl::StatusOr<OutdoorMatrix>()>& compute,
    const std::function<bool()>& cancelled) {
  {
    std::unique_lock lock(mutex_);
    while (true) {
      if (auto it = entries_.find(key); it != entries_.end()) return Lookup{it->second, false};
      if (!computing_.contains(key)) break;
      if (cancelled && cancelled()) {
        return absl::CancelledError("cancelled while waiting for the outdoor matrix");
      }
      changed_.wait_for(lock, std::chrono::milliseconds(200));
    }
    computing_.insert(key);
  }
  absl::StatusOr<OutdoorMatrix> result = compute();
  std::shared_ptr<const OutdoorMatrix> matrix;
  if (result.ok()) {
    result->key = key;
    matrix = std::make_shared<const OutdoorMatrix>(*std::move(result));
    if (absl::Status written = Put(matrix); !written.ok()) {
      spdlog::warn("outdoor matrix {} kept in memory only: {}", key, written.ToString());
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
