#pragma once

// A large site registration, for fenestrad's memory test and registration_memory_bench: the
// city office with `triangles` more outdoor triangles, a grid under the ground shifted by
// `shift_m` (so each request has its own outdoor key); 600 000 of them make a 58 MiB request.
#include <google/protobuf/util/json_util.h>

#include <fstream>
#include <sstream>
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

}  // namespace fenestra
