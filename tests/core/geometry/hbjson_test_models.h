// Honeybee models written for the tests of hbjson_import, and helpers on the scenes they
// become.
#pragma once

#include <gtest/gtest.h>

#include <charconv>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/vec3.h"
#include "core/geometry/hbjson_import.h"

namespace fenestra::hbjson_test {

// ---------------------------------------------------------------------------------------
// Models written for the tests
// ---------------------------------------------------------------------------------------

// A number as JSON: the shortest text that reads back as it.
inline std::string N(double x) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof(text), x).ptr;
  return std::string(text, end);
}

inline std::string P(double x, double y, double z) {
  return absl::StrCat("[", N(x), ", ", N(y), ", ", N(z), "]");
}

inline std::string Geometry(const std::vector<std::string>& points, const std::string& holes = "") {
  return absl::StrCat(R"({"type": "Face3D", "boundary": [)", absl::StrJoin(points, ", "), "]",
                      holes.empty() ? "" : absl::StrCat(R"(, "holes": )", holes), "}");
}

// An element's radiance properties naming its modifier (none when empty).
inline std::string Properties(const std::string& modifier, const std::string& extra = "") {
  return absl::StrCat(R"({"type": "PropertiesAbridged", "radiance": {"type": "RadianceProperties")",
                      modifier.empty() ? "" : absl::StrCat(R"(, "modifier": ")", modifier, "\""),
                      extra, "}}");
}

inline std::string Aperture(const std::string& id, const std::vector<std::string>& points,
                            const std::string& extra = "") {
  return absl::StrCat(R"({"type": "Aperture", "identifier": ")", id, R"(", "geometry": )",
                      Geometry(points), R"(, "boundary_condition": {"type": "Outdoors"}, )",
                      R"("properties": )", Properties(""), extra, "}");
}

inline std::string Shade(const std::string& id, const std::vector<std::string>& points,
                         const std::string& extra = "") {
  return absl::StrCat(R"({"type": "Shade", "identifier": ")", id, R"(", "geometry": )",
                      Geometry(points), R"(, "properties": )", Properties(""), extra, "}");
}

struct FaceSpec {
  std::string id, type, boundary = "Outdoors";
  std::vector<std::string> points;
  std::string extra = "";     // more members: "apertures", "properties"...
  std::string adjacent = "";  // a Surface condition's objects (a JSON array)
};

inline std::string Face(const FaceSpec& f) {
  const std::string objects =
      f.adjacent.empty() ? "" : absl::StrCat(R"(, "boundary_condition_objects": )", f.adjacent);
  return absl::StrCat(R"({"type": "Face", "identifier": ")", f.id, R"(", "face_type": ")", f.type,
                      R"(", "geometry": )", Geometry(f.points),
                      R"(, "boundary_condition": {"type": ")", f.boundary, "\"", objects,
                      R"(}, "properties": )", Properties(""), f.extra, "}");
}

// The six faces of the box [x0, x1] x [y0, y1] x [z0, z1], each turning counterclockwise seen
// from outside (Honeybee's outward normals), named <room>_<side>; `extra` adds members to a
// face by its side (floor, roof, south, north, west, east).
inline std::vector<FaceSpec> BoxFaces(const std::string& room, double x0, double y0, double z0,
                                      double x1, double y1, double z1,
                                      const std::map<std::string, std::string>& extra = {}) {
  std::vector<FaceSpec> faces = {
      {room + "_floor",
       "Floor",
       "Ground",
       {P(x0, y0, z0), P(x0, y1, z0), P(x1, y1, z0), P(x1, y0, z0)}},
      {room + "_roof",
       "RoofCeiling",
       "Outdoors",
       {P(x0, y0, z1), P(x1, y0, z1), P(x1, y1, z1), P(x0, y1, z1)}},
      {room + "_south",
       "Wall",
       "Outdoors",
       {P(x0, y0, z0), P(x1, y0, z0), P(x1, y0, z1), P(x0, y0, z1)}},
      {room + "_north",
       "Wall",
       "Outdoors",
       {P(x1, y1, z0), P(x0, y1, z0), P(x0, y1, z1), P(x1, y1, z1)}},
      {room + "_west",
       "Wall",
       "Outdoors",
       {P(x0, y1, z0), P(x0, y0, z0), P(x0, y0, z1), P(x0, y1, z1)}},
      {room + "_east",
       "Wall",
       "Outdoors",
       {P(x1, y0, z0), P(x1, y1, z0), P(x1, y1, z1), P(x1, y0, z1)}},
  };
  for (FaceSpec& f : faces) {
    const auto it = extra.find(f.id.substr(room.size() + 1));
    if (it != extra.end()) f.extra = it->second;
  }
  return faces;
}

inline std::string Room(const std::string& id, const std::vector<FaceSpec>& faces,
                        const std::string& extra = "") {
  std::vector<std::string> written;
  for (const FaceSpec& f : faces) written.push_back(Face(f));
  // Properties of its own unless `extra` gives them
  const bool properties = extra.find(R"("properties")") == std::string::npos;
  return absl::StrCat(
      R"({"type": "Room", "identifier": ")", id, R"(", "faces": [)", absl::StrJoin(written, ", "),
      "]", properties ? R"(, "properties": {"type": "RoomProperties"})" : "", extra, "}");
}

// A grid of sensors facing up at `z`, at the given (x, y).
inline std::string Grid(const std::string& id, const std::vector<std::pair<double, double>>& xy,
                        double z, const std::string& extra = "") {
  std::vector<std::string> sensors;
  for (const auto& [x, y] : xy) {
    sensors.push_back(absl::StrCat(R"({"pos": )", P(x, y, z), R"(, "dir": [0, 0, 1]})"));
  }
  return absl::StrCat(R"({"type": "SensorGrid", "identifier": ")", id, R"(", "sensors": [)",
                      absl::StrJoin(sensors, ", "), "]", extra, "}");
}

struct ModelSpec {
  std::vector<std::string> rooms;
  std::vector<std::string> grids;
  std::string modifiers, modifier_sets;  // JSON arrays' contents
  std::string extra;                     // more members of the model
  std::string units = "Meters";
};

inline std::string Model(const ModelSpec& m) {
  return absl::StrCat(R"({"type": "Model", "identifier": "test_model", "units": ")", m.units,
                      R"(", "tolerance": 0.001, "angle_tolerance": 1.0, "rooms": [)",
                      absl::StrJoin(m.rooms, ", "),
                      R"(], "properties": {"type": "ModelProperties", "energy": {"type": "E"}, )",
                      R"("radiance": {"type": "ModelRadianceProperties", "modifiers": [)",
                      m.modifiers, R"(], "modifier_sets": [)", m.modifier_sets,
                      R"(], "sensor_grids": [)", absl::StrJoin(m.grids, ", "), "]}}", m.extra, "}");
}

// The office: a 4 m x 6 m x 3 m box with a 2 m x 1.5 m window in its south wall (y = 0), its
// sill at 0.9 m, and four sensors on a work plane, all scaled by `scale` (the model's units).
inline std::string Office(double s = 1, const std::string& units = "Meters",
                          const std::string& window_extra = "", const std::string& room_extra = "",
                          const std::string& model_extra = "") {
  const std::string window = Aperture(
      "office_window",
      {P(1 * s, 0, 0.9 * s), P(3 * s, 0, 0.9 * s), P(3 * s, 0, 2.4 * s), P(1 * s, 0, 2.4 * s)},
      window_extra);
  const auto faces = BoxFaces("office", 0, 0, 0, 4 * s, 6 * s, 3 * s,
                              {{"south", absl::StrCat(R"(, "apertures": [)", window, "]")}});
  ModelSpec m;
  m.rooms = {Room("office", faces, room_extra)};
  m.grids = {
      Grid("desks", {{1 * s, 2 * s}, {3 * s, 2 * s}, {1 * s, 4 * s}, {3 * s, 4 * s}}, 0.8 * s)};
  m.units = units;
  m.extra = model_extra;
  return Model(m);
}

// Two rooms side by side along x, sharing a wall: west [0, 4] and east [4, 8], each with a
// south window; grids as given.
inline std::string TwoRooms(const std::vector<std::string>& grids) {
  const auto window = [](const std::string& id, double x) {
    return absl::StrCat(
        R"(, "apertures": [)",
        Aperture(id, {P(x + 1, 0, 1), P(x + 3, 0, 1), P(x + 3, 0, 2), P(x + 1, 0, 2)}), "]");
  };
  auto west = BoxFaces("west", 0, 0, 0, 4, 6, 3, {{"south", window("west_window", 0)}});
  auto east = BoxFaces("east", 4, 0, 0, 8, 6, 3, {{"south", window("east_window", 4)}});
  west[5].boundary = "Surface";  // west's east wall touches east's west wall
  west[5].adjacent = R"(["east_west", "east"])";
  east[4].boundary = "Surface";
  east[4].adjacent = R"(["west_east", "west"])";
  ModelSpec m;
  m.rooms = {Room("west", west), Room("east", east)};
  m.grids = grids;
  return Model(m);
}

// ---------------------------------------------------------------------------------------
// Helpers on scenes
// ---------------------------------------------------------------------------------------

inline absl::StatusOr<v1::Scene> Import(const std::string& json,
                                        const HoneybeeImportOptions& options = {},
                                        HoneybeeImportSummary* summary = nullptr) {
  return ImportHoneybee(json, "model.hbjson", options, summary);
}

// The import's error message; fails the test when it is not InvalidArgument.
inline std::string ErrorOf(const std::string& json, const HoneybeeImportOptions& options = {}) {
  const absl::StatusOr<v1::Scene> scene = Import(json, options);
  EXPECT_FALSE(scene.ok()) << "accepted";
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
  return std::string(scene.status().message());
}

inline Vec3d V(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

inline double PolygonArea(const v1::Polygon& polygon) {
  Vec3d n{0, 0, 0};
  const Vec3d o = V(polygon.vertices(0));
  for (int k = 1; k + 1 < polygon.vertices_size(); ++k) {
    n += Cross(V(polygon.vertices(k)) - o, V(polygon.vertices(k + 1)) - o);
  }
  return 0.5 * Length(n);
}

// The surfaces named `name` or "<name>#<k>".
inline std::vector<const v1::Surface*> Parts(const v1::Scene& scene, const std::string& name) {
  std::vector<const v1::Surface*> parts;
  for (const v1::Surface& s : scene.surfaces()) {
    if (s.name() == name || s.name().rfind(name + "#", 0) == 0) parts.push_back(&s);
  }
  return parts;
}

inline double PartsArea(const v1::Scene& scene, const std::string& name) {
  double area = 0;
  for (const v1::Surface* s : Parts(scene, name)) area += PolygonArea(s->polygon());
  return area;
}

inline const v1::Material* MaterialOf(const v1::Scene& scene, const std::string& surface) {
  const std::vector<const v1::Surface*> parts = Parts(scene, surface);
  if (parts.empty()) return nullptr;
  for (const v1::Material& m : scene.materials()) {
    if (m.name() == parts[0]->material()) return &m;
  }
  return nullptr;
}

// The office with `find` replaced by `replace` (the first occurrence after `after`).
inline std::string Edited(const std::string& find, const std::string& replace,
                          const std::string& after = "") {
  std::string json = Office();
  const size_t at = json.find(find, after.empty() ? 0 : json.find(after));
  EXPECT_NE(at, std::string::npos) << find;
  if (at != std::string::npos) json.replace(at, find.size(), replace);
  return json;
}

inline std::string ReadSample(const std::string& path) {
  std::ifstream in(std::string(FENESTRA_SOURCE_DIR "/tests/data/models/") + path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_FALSE(text.str().empty()) << path;
  return text.str();
}

}  // namespace fenestra::hbjson_test
