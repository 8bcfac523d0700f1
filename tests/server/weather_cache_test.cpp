#include "server/weather_cache.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "server/checksum.h"

namespace fenestra {
namespace {

std::string ExampleWeather() {
  std::ifstream in(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw",
                   std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// A weather file is read, parsed and its sky built once per content and sky options; later
// jobs get the same ones, another ground reflectance gets its own sky, and the least recently
// used file goes beyond kWeatherCacheEntries.
TEST(WeatherCacheTest, BuildsEachWeatherAndSkyOnce) {
  const std::string epw = ExampleWeather();
  const std::string sha = Sha256Hex(epw);
  WeatherCache cache;
  int reads = 0;
  const auto read = [&]() -> absl::StatusOr<std::string> {
    ++reads;
    return epw;
  };
  SkyMatrixOptions options;
  absl::StatusOr<WeatherCache::Entry> first = cache.Get(sha, options, read);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->weather->records.size(), 8760u);
  EXPECT_EQ(first->sky->radiance.cols(), 8760);
  absl::StatusOr<WeatherCache::Entry> again = cache.Get(sha, options, read);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->sky.get(), first->sky.get());
  EXPECT_EQ(reads, 1);
  EXPECT_EQ(cache.hits(), 1);
  EXPECT_TRUE(cache.Holds(sha));
  EXPECT_FALSE(cache.Holds(Sha256Hex("other bytes")));

  // Another ground: the same weather, its own sky, whose ground bin differs
  SkyMatrixOptions white = options;
  white.ground_reflectance = 0.9;
  absl::StatusOr<WeatherCache::Entry> other = cache.Get(sha, white, read);
  ASSERT_TRUE(other.ok());
  EXPECT_EQ(reads, 2);
  EXPECT_NE(other->sky->radiance.row(0), first->sky->radiance.row(0));

  // Filled with other files' keys (the same bytes), the first key is read again
  for (int k = 0; k < WeatherCache::kWeatherCacheEntries; ++k) {
    ASSERT_TRUE(cache.Get("other" + std::to_string(k), options, read).ok());
  }
  reads = 0;
  ASSERT_TRUE(cache.Get(sha, options, read).ok());
  EXPECT_EQ(reads, 1);
}

// A file that cannot be read or does not parse is an error, and nothing is kept.
TEST(WeatherCacheTest, FailuresAreNotKept) {
  WeatherCache cache;
  int reads = 0;
  const auto lost = [&]() -> absl::StatusOr<std::string> {
    ++reads;
    return absl::DataLossError("the job's stored weather file cannot be read");
  };
  EXPECT_EQ(cache.Get("a", {}, lost).status().code(), absl::StatusCode::kDataLoss);
  EXPECT_EQ(cache.Get("a", {}, lost).status().code(), absl::StatusCode::kDataLoss);
  EXPECT_EQ(reads, 2);
  const auto garbage = []() -> absl::StatusOr<std::string> { return std::string("no,epw\n"); };
  const absl::Status bad = cache.Get("b", {}, garbage).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.message().find("weather_epw"), std::string::npos) << bad;
  EXPECT_EQ(cache.hits(), 0);
  EXPECT_FALSE(cache.Holds("a") || cache.Holds("b"));
}

}  // namespace
}  // namespace fenestra
