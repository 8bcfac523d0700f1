#pragma once

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>

#include "absl/status/statusor.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {

// The weather files of recent jobs, parsed, with their sky matrices, by the file's content
// (SHA-256, as the store keeps it) and the sky's options. A daemon's jobs mostly share a
// few weather files; parsing one and building its sky took 20-40 ms of a job that runs in
// 0.7 s. Holds the kWeatherCacheEntries used last (a year's Tregenza sky is 10 MB).
// Thread-safe.
class WeatherCache {
 public:
  static constexpr int kWeatherCacheEntries = 4;

  struct Entry {
    std::shared_ptr<const EpwData> weather;
    std::shared_ptr<const SkyMatrix> sky;
  };

  // The weather file with content `sha256` and its sky with `options`: held, or read with
  // `read`, parsed (errors name it "weather_epw") and built now. A failure is not held.
  absl::StatusOr<Entry> Get(const std::string& sha256, const SkyMatrixOptions& options,
                            const std::function<absl::StatusOr<std::string>()>& read);

  // Whether the weather file with content `sha256` is held (it parsed).
  bool Holds(const std::string& sha256) const;

  // How many Get calls found their entry held.
  int64_t hits() const;

 private:
  struct Held {
    std::string sha256;
    SkyMatrixOptions options;
    Entry entry;
  };
  mutable std::mutex mutex_;
  std::list<Held> held_;  // used last first
  int64_t hits_ = 0;
};

}  // namespace fenestra
