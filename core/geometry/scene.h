#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
#include "core/geometry/blind.h"
#include "core/geometry/mesh.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra {

// The window rectangle (the opening's outer face), the interface of the two-stage method.
struct Window {
  Vec3d center;  // centre of the outer face [m]
  Vec3d normal;  // unit outward normal
  Vec3d up;      // unit, along the height
  Vec3d across;  // unit, along the width: Cross(up, normal)
  double width_m = 0;
  double height_m = 0;
  double depth_m = 0;  // wall thickness: inner face = center - depth_m * normal
  double Area() const { return width_m * height_m; }
};

struct Sensor {
  std::string name;
  Vec3d position;   // [m]
  Vec3d direction;  // unit
};

struct Site {
  double latitude_deg = 0;
  double longitude_deg = 0;
  double time_zone_h = 0;
  std::string weather_file;  // absolute path, or empty
  double ground_reflectance = 0.2;
};

// A validated scene: fixed geometry as triangles, plus what the blind and the stages need.
struct Scene {
  std::string name;
  std::string source_path;  // the scene file
  std::vector<Material> materials;
  TriangleMesh fixed;             // every surface except the blind
  size_t dropped_degenerate = 0;  // zero-area OBJ triangles left out
  Window window;
  std::vector<Sensor> sensors;
  std::optional<BlindSpec> blind;
  Site site;
};

// Reads a scene file (the JSON form of fenestra.v1.Scene); unknown fields are errors.
absl::StatusOr<v1::Scene> ReadSceneProto(const std::string& path);

// Validates a scene message and assembles its fixed geometry. `path` names the file in
// errors and anchors relative OBJ and weather paths. Errors name the file, field and reason.
absl::StatusOr<Scene> BuildScene(const v1::Scene& proto, const std::string& path);

// ReadSceneProto + BuildScene.
absl::StatusOr<Scene> LoadScene(const std::string& path);

// The complete geometry at `design` (blind included when the scene has one).
TriangleMesh AssembleMesh(const Scene& scene, const BlindDesign& design);

// True when a triangle has no area by the polygon check (area <= 1e-6 x its longest
// edge²): as a polygon surface it would be refused.
bool IsDegenerateTriangle(Vec3d a, Vec3d b, Vec3d c);

// The blind design the scene file states (its parameters' values), or an empty design.
BlindDesign DefaultDesign(const Scene& scene);

// Applies name=value overrides (alpha, width, spacing, thickness) to the scene's design,
// checking each against its range.
absl::StatusOr<BlindDesign> DesignWithOverrides(const Scene& scene,
                                                const std::map<std::string, double>& values);

}  // namespace fenestra
