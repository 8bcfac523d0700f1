#pragma once

// What fenestrad's memory test and registration_memory_bench share: a large site
// registration (the city office with `triangles` more outdoor triangles, a grid under the
// ground shifted by `shift_m` so each request has its own outdoor key; 600 000 of them make
// a 58 MiB request), and a process's memory as /proc/PID/status tells it.
#include <google/protobuf/util/json_util.h>
#include <sys/types.h>

#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "fenestra/v1/service.pb.h"

namespace fenestra {

inline v1::RegisterSiteRequest LargeRegistration(int triangles, int64_t outdoor_paths,
                                                 double shift_m = 0) {
  v1::RegisterSiteRequest request;
  std::ifstream in(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  std::stringstream json;
  json << in.rdbuf();
  (void)google::protobuf::util::JsonStringToMessage(json.str(), request.mutable_scene());
  request.mutable_scene()->mutable_site()->clear_weather_file();
  const int row = 1000;
  for (int i = 0; i < triangles; ++i) {
    v1::Surface& s = *request.mutable_scene()->add_surfaces();
    s.set_name("t");
    s.set_material("city");
    s.set_side(v1::SIDE_OUTDOOR);
    const double x = -50 + 0.1 * (i % row) + shift_m, y = -50 + 0.1 * (i / row);
    for (const auto& [dx, dy] : {std::pair{0.0, 0.0}, {0.08, 0.0}, {0.0, 0.08}}) {
      v1::Vec3& v = *s.mutable_polygon()->add_vertices();
      v.set_x(x + dx);
      v.set_y(y + dy);
      v.set_z(-0.5);
    }
  }
  request.set_name("large");
  request.mutable_sampling()->set_outdoor_paths(outdoor_paths);
  request.mutable_sampling()->set_backend("cpu");
  return request;
}

// A field of /proc/PID/status (VmRSS, VmHWM) [MiB], or -1.
inline double ProcessStatusMiB(pid_t pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(field + ":", 0) == 0) return std::stod(line.substr(field.size() + 1)) / 1024;
  }
  return -1;
}

}  // namespace fenestra
