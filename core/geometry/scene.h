#pragma once

#include <cstdint>
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

// Largest |coordinate| of any point of a scene [m]: polygon and box corners, the window's
// corners, sensors. The tracers work in float, relative to the centre of the scene's
// bounding box; at 1e5 m from it floats are 7.8 mm apart, the thickness of a slat, so a
// scene that reaches further loses the blind's geometry. 100 km also holds any site model
// (a city, a ground plane to the horizon).
inline constexpr double kMaxCoordinateM = 1e5;
// Narrowest window side [m]: a slit below 1 cm lets in no daylight worth simulating, and
// the tracer divides by the window's area.
inline constexpr double kMinWindowSideM = 0.01;
// Thickest wall a window may sit in (`Window::depth_m`) [m]; castle walls reach 3 m.
inline constexpr double kMaxWindowDepthM = 5.0;
// Most windows and skylights in a scene: each adds its own outdoor matrix and stages.
inline constexpr int kMaxSceneWindows = 64;
// Most view points in a scene.
inline constexpr int kMaxSceneViews = 1000;
// Most sensors in a scene, grids expanded: bounds the memory of a scene file's grid (the
// service has its own, lower limit).
inline constexpr int64_t kMaxSceneSensors = 1'000'000;

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

// The name of the one-window form's window (scene.proto: `window`).
inline constexpr char kOneWindowName[] = "window";

// A window or skylight with its optional blind.
struct SceneWindow {
  std::string name;  // unique in the scene
  Window window;
  std::optional<BlindSpec> blind;
};

struct Sensor {
  std::string name;
  Vec3d position;   // [m]
  Vec3d direction;  // unit
  // Where the scene defines it, e.g. "sensors[3]" or "sensor_grids[0]"; empty for a sensor
  // made in code.
  std::string field = {};
};

// An eye for glare (scene.proto, ViewPoint): its vertical eye illuminance is that of a sensor
// at the eye facing the view direction (EyeSensor).
struct ViewPoint {
  std::string name;
  Vec3d position;     // [m]
  Vec3d direction;    // unit
  Vec3d up;           // unit, not along direction
  std::string field;  // e.g. "views[0]"
};

// The sensor whose illuminance is `view`'s vertical eye illuminance.
inline Sensor EyeSensor(const ViewPoint& view) {
  return {view.name, view.position, view.direction, view.field};
}

// A Box surface: a solid no sensor may lie in.
struct SolidBox {
  Vec3d min, max;  // [m]
  uint32_t part = 0;
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
  // At least one; the one-window form (scene.proto: `window`, `blind`) is windows[0],
  // named "window".
  std::vector<SceneWindow> windows = std::vector<SceneWindow>(1);
  std::vector<Sensor> sensors;
  std::vector<ViewPoint> views;
  std::vector<SolidBox> solid_boxes;  // every Box surface, indoor and outdoor
  Site site;

  // The first window.
  const Window& window() const { return windows.front().window; }
  Window& window() { return windows.front().window; }
  // The first blind of the windows (empty: none): its ranges are the design's (every blind
  // of a scene is in one group so far, with the same ranges). With one window, its blind.
  const std::optional<BlindSpec>& blind() const { return BlindWindow().blind; }
  std::optional<BlindSpec>& blind() { return const_cast<SceneWindow&>(BlindWindow()).blind; }
  // The window of blind(): the first window with a blind, else the first window.
  const SceneWindow& BlindWindow() const {
    for (const SceneWindow& w : windows) {
      if (w.blind) return w;
    }
    return windows.front();
  }
};

// Reads a scene file (the JSON form of fenestra.v1.Scene); unknown fields are errors.
absl::StatusOr<v1::Scene> ReadSceneProto(const std::string& path);

// Validates a scene message and assembles its fixed geometry. `path` names the file in
// errors and anchors relative OBJ and weather paths. Errors name the file, field and reason.
// Checks every field on its own (text, enums, finite and bounded numbers, shapes, the
// blind's physical ranges); how surfaces, window and sensors fit together as a room needs
// the tracer: ValidateScene (core/trace/room_check.h) checks both.
absl::StatusOr<Scene> BuildScene(const v1::Scene& proto, const std::string& path);

// ReadSceneProto + BuildScene.
absl::StatusOr<Scene> LoadScene(const std::string& path);

// The complete geometry at `design`: every window's blind where the design has one (all
// blinds take the same design: BuildScene refuses blinds of different groups so far).
TriangleMesh AssembleMesh(const Scene& scene, const BlindDesign& design);

// True when a triangle has no area by the polygon check (area <= 1e-6 x its longest
// edge²): as a polygon surface it would be refused.
bool IsDegenerateTriangle(Vec3d a, Vec3d b, Vec3d c);

// The blind design the scene file states (its parameters' values), or an empty design.
BlindDesign DefaultDesign(const Scene& scene);

// Applies name=value overrides (alpha, width, spacing, thickness) to the scene's design,
// checking each against its range. A job's finish needs its job (JobDesignWithOverrides,
// core/optimize/design_variables.h).
absl::StatusOr<BlindDesign> DesignWithOverrides(const Scene& scene,
                                                const std::map<std::string, double>& values);

// The index of material `name` among `materials` as the slats' material: InvalidArgument
// "unknown material 'NAME'" or "'NAME' is a glass: ..." (the caller adds the field).
absl::StatusOr<uint32_t> SlatMaterialIndex(const std::vector<Material>& materials,
                                           const std::string& name);

}  // namespace fenestra
