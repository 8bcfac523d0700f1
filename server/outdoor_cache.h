#pragma once

#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/optimize/job.h"

namespace fenestra {

// Cache file format: "FNSTROMX", version (u32 LE, 2), reserved (u32), payload size (u64 LE,
// bytes), SHA-256 of the payload (32 bytes), then the payload: a serialized
// fenestra.v1.OutdoorMatrixEntry.
std::string EncodeOutdoorMatrix(const OutdoorMatrix& matrix);

// Parses a cache file's bytes. DataLoss when the header, size or checksum is wrong.
absl::StatusOr<OutdoorMatrix> DecodeOutdoorMatrix(std::string_view bytes);

// Outdoor matrices by OutdoorMatrixKey, in memory and as files <sha256(key)>.omx in one
// folder, written atomically (temporary file + rename). Thread-safe.
class OutdoorCache {
 public:
  explicit OutdoorCache(std::string dir);

  // What Load found: files loaded, and files discarded (corrupt or unreadable) with why.
  struct LoadReport {
    int loaded = 0;
    std::vector<std::string> discarded;
  };
  // Loads every cache file of the folder (created when missing). A file whose checksum or
  // format is wrong is deleted, so its matrix is recomputed when needed.
  absl::StatusOr<LoadReport> Load();

  // The matrix with `key`, or null.
  std::shared_ptr<const OutdoorMatrix> Find(const std::string& key) const;
  // Whether `key`'s matrix came from a file at Load (rather than being computed by this
  // process).
  bool LoadedFromDisk(const std::string& key) const;
  // Adds `matrix` under matrix.key, in memory and on disk; the status is the disk write's.
  absl::Status Put(std::shared_ptr<const OutdoorMatrix> matrix);

  // Where `key`'s file lives.
  std::string PathFor(const std::string& key) const;

  // The result of GetOrCompute: the matrix, and whether this call traced it.
  struct Lookup {
    std::shared_ptr<const OutdoorMatrix> matrix;
    bool computed = false;
  };
  // The cached matrix with `key`; otherwise runs `compute` and caches its result. Callers
  // asking for a key another caller is computing wait for it (polling `cancelled`, which
  // ends the wait with Cancelled). A failed computation is not cached.
  absl::StatusOr<Lookup> GetOrCompute(const std::string& key,
                                      const std::function<absl::StatusOr<OutdoorMatrix>()>& compute,
                                      const std::function<bool()>& cancelled = {});

 private:
  std::string dir_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, std::shared_ptr<const OutdoorMatrix>> entries_;
  std::set<std::string> from_disk_;
  std::set<std::string> computing_;
};

}  // namespace fenestra
