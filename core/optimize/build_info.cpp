#include "core/optimize/build_info.h"

#include <embree3/rtcore_config.h>
#include <google/protobuf/stubs/common.h>

#include <Eigen/Core>

#include "absl/strings/str_cat.h"

namespace fenestra {

std::map<std::string, std::string> ComponentVersions() {
  constexpr int kProtobuf = GOOGLE_PROTOBUF_VERSION;  // major * 1e6 + minor * 1e3 + patch
#if defined(__clang__)
  const std::string compiler = absl::StrCat("clang ", __clang_version__);
#elif defined(__GNUC__)
  const std::string compiler = absl::StrCat("gcc ", __VERSION__);
#else
  const std::string compiler = "unknown";
#endif
  return {
      {"fenestra", FENESTRA_VERSION},
      {"embree", RTC_VERSION_STRING},
      {"eigen",
       absl::StrCat(EIGEN_WORLD_VERSION, ".", EIGEN_MAJOR_VERSION, ".", EIGEN_MINOR_VERSION)},
      {"protobuf",
       absl::StrCat(kProtobuf / 1000000, ".", kProtobuf / 1000 % 1000, ".", kProtobuf % 1000)},
      {"compiler", compiler},
  };
}

}  // namespace fenestra
