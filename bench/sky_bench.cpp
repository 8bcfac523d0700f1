// Time to read the Montevideo EPW and to build its 146 x 8760 sky matrix (columns on every core).
// Usage: sky_bench [EPW] [RUNS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/common/seconds.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace {

template <typename F>
std::vector<double> TimeRuns(int runs, F&& f) {
  std::vector<double> seconds;
  for (int i = 0; i < runs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    f();
    seconds.push_back(fenestra::SecondsSince(start));
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds;
}

void Report(const char* what, const std::vector<double>& s) {
  std::printf("%-34s best %8.2f ms   median %8.2f ms   (%zu runs)\n", what, 1e3 * s.front(),
              1e3 * s[s.size() / 2], s.size());
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path =
      argc > 1 ? argv[1] : FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw";
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 10;

  absl::StatusOr<fenestra::EpwData> epw;
  const std::vector<double> read = TimeRuns(runs, [&] { epw = fenestra::ReadEpw(path); });
  if (!epw.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(epw.status().message()).c_str());
    return 1;
  }
  Report("read EPW", read);
  for (const auto& [name, options] :
       {std::pair{"sky matrix MF 1, visible", fenestra::SkyMatrixOptions{}},
        std::pair{"sky matrix MF 1, solar",
                  fenestra::SkyMatrixOptions{.quantity = fenestra::SkyQuantity::kSolar}},
        std::pair{"sky matrix MF 2, visible", fenestra::SkyMatrixOptions{.mf = 2}}}) {
    absl::StatusOr<fenestra::SkyMatrix> sky;
    const fenestra::SkyMatrixOptions& sky_options = options;  // lambdas cannot capture bindings
    const std::vector<double> s =
        TimeRuns(runs, [&] { sky = fenestra::BuildSkyMatrix(*epw, sky_options); });
    if (!sky.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(sky.status().message()).c_str());
      return 1;
    }
    Report(name, s);
    std::printf("  %ld x %ld, %d daytime steps\n", static_cast<long>(sky->radiance.rows()),
                static_cast<long>(sky->radiance.cols()), sky->daytime_steps);
  }
  return 0;
}
