#pragma once

#include <condition_variable>
#include <functional>
#include <list>
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
#include "server/data_dir.h"

namespace fenestra {

// Cache file format: "FNSTROMX", version (u32 LE, 2), reserved (u32), payload size (u64 LE,
// bytes), SHA-256 of the payload (32 bytes), then the payload: a serialized
// fenestra.v1.OutdoorMatrixEntry.
std::string EncodeOutdoorMatrix(const OutdoorMatrix& matrix);

// Parses a cache file's bytes. DataLoss when the header, size or checksum is wrong.
absl::StatusOr<OutdoorMatrix> DecodeOutdoorMatrix(std::string_view bytes);

class Store;

// Outdoor matrices by OutdoorMatrixKey, persisted one of two ways:
// - files <sha256(key)>.omx in one folder (the SQLite store's data directory), written
//   atomically (synced temporary file + rename). Files stay while the data directory has
//   room: when it needs room, the least recently used matrix that no site or unfinished
//   job uses is evicted first.
// - in a shared store (PostgreSQL), as the bytes EncodeOutdoorMatrix makes.
// Either way the process keeps the matrices it used last in memory, up to a bound, so that
// a site's next job does not read its matrix back (33 MB for the city office: 0.1-0.2 s
// with its checksum); beyond the bound a matrix stays in memory only while someone holds it
// (a job or a site computation).
// Thread-safe.
class OutdoorCache {
 public:
  // Files in `dir`. `data_dir`, when given, is asked for room before each file is written.
  // Up to `memory_bytes` of matrices are kept in memory once used.
  explicit OutdoorCache(std::string dir, const DataDir* data_dir = nullptr,
                        int64_t memory_bytes = 0);
  // Matrices in `store`, up to `memory_bytes` of them kept in memory once used.
  OutdoorCache(Store& store, int64_t memory_bytes);

  // What Load found: files loaded, and files discarded (corrupt or unreadable) with why.
  struct LoadReport {
    int loaded = 0;
    std::vector<std::string> discarded;
  };
  // Checks every cache file of the folder (created when missing) and indexes the sound
  // ones. A file whose checksum or format is wrong is deleted, so its matrix is recomputed
  // when needed. In a store: counts the matrices stored (each is checked when read).
  absl::StatusOr<LoadReport> Load();

  // The matrix with `key` (read from its file when no one holds it), or null. A file found
  // corrupt now is deleted (null).
  std::shared_ptr<const OutdoorMatrix> Find(const std::string& key);
  // Whether a matrix with `key` is cached, without reading it.
  bool Contains(const std::string& key) const;
  // Whether `key`'s matrix came from a file at Load, or from the store (rather than being
  // computed by this process).
  bool LoadedFromDisk(const std::string& key) const;
  // The keys of the matrices in this process's memory, most recently used first.
  std::vector<std::string> KeysInMemory() const;
  // Adds `matrix` under matrix.key, in memory and on disk; the status is the disk write's
  // (when it fails, or the data directory has no room, the matrix is kept in memory).
  absl::Status Put(std::shared_ptr<const OutdoorMatrix> matrix);

  // Where `key`'s file lives.
  std::string PathFor(const std::string& key) const;

  // Sets which keys are in use (by a site or an unfinished job): those are never evicted.
  void SetInUse(std::function<bool(const std::string& key)> in_use);
  // Removes the least recently used matrix that is cached on disk, held by no one and not
  // in use; false when there is none.
  bool EvictOne();

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
  struct Entry {
    std::weak_ptr<const OutdoorMatrix> held;    // while someone holds it
    std::shared_ptr<const OutdoorMatrix> kept;  // when it has no file (no room on disk)
    bool from_disk = false;                     // found at Load
    int64_t last_used = 0;                      // use counter: larger = more recent
  };

  // Keeps `matrix` among the recently used ones (mutex_ held).
  void KeepRecent(const std::string& key, std::shared_ptr<const OutdoorMatrix> matrix);
  // Drops `key` from the recently used ones, if there (mutex_ held).
  void DropRecent(const std::string& key);
  // Whether someone besides the recently used list holds `key`'s matrix (mutex_ held).
  bool HeldOutside(const std::string& key, const Entry& entry) const;
  // Reads a matrix back from its file or the store; DataLoss when it is corrupt (and
  // removed), NotFound when it is not there.
  absl::StatusOr<OutdoorMatrix> ReadBack(const std::string& key);
  // Writes a matrix's bytes to its file or the store.
  absl::Status WriteOut(const OutdoorMatrix& matrix);
  // Find, with the store's failures (Unavailable) told apart from a matrix not there
  // (null).
  absl::StatusOr<std::shared_ptr<const OutdoorMatrix>> FindOrError(const std::string& key);

  const std::string dir_;
  const DataDir* const data_dir_ = nullptr;
  Store* const store_ = nullptr;
  const int64_t memory_bytes_ = 0;
  // The matrices used last, most recent first, and their size [bytes]
  std::list<std::pair<std::string, std::shared_ptr<const OutdoorMatrix>>> recent_;
  int64_t recent_bytes_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::string, Entry> entries_;
  std::set<std::string> computing_;
  int64_t uses_ = 0;
  std::function<bool(const std::string& key)> in_use_;
};

}  // namespace fenestra
