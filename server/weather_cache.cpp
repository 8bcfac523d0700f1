#include "server/weather_cache.h"

#include <utility>

#include "core/common/status_macros.h"

namespace fenestra {

absl::StatusOr<WeatherCache::Entry> WeatherCache::Get(
    const std::string& sha256, const SkyMatrixOptions& options,
    const std::function<absl::StatusOr<std::string>()>& read) {
  {
    std::lock_guard lock(mutex_);
    for (auto it = held_.begin(); it != held_.end(); ++it) {
      if (it->sha256 == sha256 && it->options == options) {
        held_.splice(held_.begin(), held_, it);
        ++hits_;
        return it->entry;
      }
    }
  }
  // Built outside the lock: two jobs that miss at once each build it
  FENESTRA_ASSIGN_OR_RETURN(bytes, read());
  FENESTRA_ASSIGN_OR_RETURN(weather, ParseEpw(bytes, "weather_epw"));
  FENESTRA_ASSIGN_OR_RETURN(sky, BuildSkyMatrix(weather, options));
  Entry entry{std::make_shared<const EpwData>(std::move(weather)),
              std::make_shared<const SkyMatrix>(std::move(sky))};
  std::lock_guard lock(mutex_);
  held_.push_front({sha256, options, entry});
  if (held_.size() > kWeatherCacheEntries) held_.pop_back();
  return entry;
}

bool WeatherCache::Holds(const std::string& sha256) const {
  std::lock_guard lock(mutex_);
  for (const Held& h : held_) {
    if (h.sha256 == sha256) return true;
  }
  return false;
}

int64_t WeatherCache::hits() const {
  std::lock_guard lock(mutex_);
  return hits_;
}

}  // namespace fenestra
