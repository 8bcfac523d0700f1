// The polygons of a Honeybee model as scene surfaces: a Face3D read in metres and flattened
// onto its plane, its openings cut out into convex pieces, and an aperture's rectangle as a
// window.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
#include "core/geometry/hbjson_json.h"
#include "fenestra/v1/scene.pb.h"

namespace fenestra::hbjson {

// A planar polygon in metres, its points on its plane.
struct Shape {
  std::vector<Vec3d> outline;
  std::vector<std::vector<Vec3d>> holes;
  Vec3d normal;  // unit: Newell's, about which the outline turns counterclockwise
  Vec3d origin;  // a point of the plane
};

// The lengths the model's checks use [m, rad].
struct Tolerances {
  double length = 0.01;
  double angle = 0.0175;
};

// The Face3D `geometry` (boundary and holes) times `scale`: every coordinate within
// kMaxCoordinateM, the polygon with area, every point within `tolerances.length` of the plane
// of the boundary (Newell's), then moved onto it.
absl::StatusOr<Shape> ReadShape(const Json& geometry, double scale, const Tolerances& tolerances);

// `points` moved onto `face`'s plane; each must lie within `tolerances.length` of it, and
// their own plane within `tolerances.angle` of its (`where` names them in errors).
absl::StatusOr<std::vector<Vec3d>> OntoPlane(const Shape& face, const std::vector<Vec3d>& points,
                                             const Tolerances& tolerances, const Json& where);

// A window of the rectangle `corners` (4, in `face`'s plane): its centre, the face's normal
// as the outward one, `up` its side closest to +z (+y when level), width and height, depth
// 0, no name yet. InvalidArgument at `where` for another shape or a side below
// kMinWindowSideM.
absl::StatusOr<v1::Window> RectangleWindow(const std::vector<Vec3d>& corners, const Shape& face,
                                           const Tolerances& tolerances, const Json& where);

// Whether a polygon has (nearly) no area or is too small to check: a scene would refuse it.
bool IsDegeneratePolygon(const std::vector<Vec3d>& polygon);

// Twice the area vector of `ring` (Newell's normal), about its first point.
Vec3d NewellNormal(const std::vector<Vec3d>& ring);

// The corners of `window`'s rectangle moved `inset` against its outward normal.
std::vector<Vec3d> WindowCorners(const v1::Window& window, double inset);

// Adds polygon surfaces to a scene under names unique within it.
class SurfaceWriter {
 public:
  explicit SurfaceWriter(v1::Scene& scene) : scene_(scene) {}

  // The region `outline` less `holes` (on the plane of normal `normal`) of `material` on
  // `side`: one polygon named `name` when convex without holes, else convex pieces
  // "<name>#<k>"; pieces without area are dropped (counted). `where` names it in errors.
  absl::Status Add(const std::string& name, const std::string& material, v1::Side side,
                   const std::vector<Vec3d>& outline, const std::vector<std::vector<Vec3d>>& holes,
                   Vec3d normal, const Json& where);

  size_t degenerate() const { return degenerate_; }

 private:
  absl::Status AddPolygon(const std::string& name, const std::string& material, v1::Side side,
                          const std::vector<Vec3d>& vertices, const Json& where);

  v1::Scene& scene_;
  std::set<std::string> names_;
  size_t degenerate_ = 0;
};

// `id` as a window's name: letters, digits, '_', '-' and '.' (others made '_'), at most 64,
// unique among `taken` (to which it is added).
std::string WindowName(const std::string& id, std::set<std::string>& taken);

}  // namespace fenestra::hbjson
