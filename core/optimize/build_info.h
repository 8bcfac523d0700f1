#pragma once

// What a job runs with, for results and reports.
#include <map>
#include <string>

namespace fenestra {

// Component -> version this build was made with: "fenestra" (the project's version),
// "embree", "eigen", "protobuf" (their headers' versions) and "compiler".
std::map<std::string, std::string> ComponentVersions();

}  // namespace fenestra
