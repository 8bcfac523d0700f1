// Triangles and convex pieces of a planar polygon with holes, by ear clipping. The outline
// and holes are taken to the polygon's plane and their edges split where a vertex of another
// ring touches them; edges that run along one segment both ways (a seam, a hole along the
// outline or along another hole) cancel, and what is left is traced into loops that touch
// only at vertices: outlines, each with the holes inside it. Each hole is joined to its
// outline by a bridge (a cut from the hole's rightmost vertex to the vertex of the outline it
// sees, Eberly's method), then ears (a convex vertex whose triangle holds no other vertex,
// crosses no edge and lies inside what is left) are cut off one at a time. Scenes need convex
// polygons; importers (Honeybee faces with their windows cut out, Radiance polygons with
// seams) call these.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"

namespace fenestra {

// Relative tolerance of the polygon checks: of the longest edge (planarity) and its square
// (area, corners).
inline constexpr double kPolygonShapeTolerance = 1e-6;

// The checks a polygon surface must pass (BuildScene) and an importer asks of a polygon:
// Newell's normal; area above kPolygonShapeTolerance x the longest edge squared; every vertex
// within kPolygonShapeTolerance x the longest edge of the plane; convex: every corner turns
// the same way, 2 pi in all (a star turns one way at every corner, but twice round).
struct PolygonShape {
  Vec3d normal{0, 0, 0};  // unit; zero without area
  bool area = false;
  bool planar = false;
  bool convex = false;
  int off_plane = -1;  // the first vertex off the plane, or -1
  int concave = -1;    // the first corner that turns the other way, or -1
};
PolygonShape ShapeOfPolygon(const std::vector<Vec3d>& vertices);

// Most vertices of one polygon, outline and holes together: bounds the ear clipping's work
// (quadratic in the vertices); a building's face with its openings has tens.
inline constexpr size_t kMaxTriangulatedVertices = 2048;

// How far a vertex may lie off the outline's plane, relative to the polygon's size (the
// diagonal of its bounding box). The triangles keep the given points.
inline constexpr double kTriangulationPlanarity = 1e-3;

// The triangles of the polygon `outline` less `holes`, in 3D, each counterclockwise about the
// outline's normal (Newell's: its vertices turn counterclockwise about it); their areas sum
// to the outline's less the holes'. The outline runs either way round, so do the holes; they
// may touch each other and the outline at points or along edges, and the outline may carry
// seams: a cut to a hole and back, its vertices repeated (as Radiance writes a polygon with a
// hole). Repeated consecutive vertices and collinear vertices are dropped; no triangle has
// zero area. InvalidArgument (a reason naming the outline or the hole by index) when there are
// fewer than 3 distinct vertices, more than kMaxTriangulatedVertices, a coordinate is not
// finite, the polygon has no area, a vertex lies off its plane, the outline crosses itself, a
// hole lies outside the outline or crosses it, or two holes overlap.
absl::StatusOr<std::vector<std::array<Vec3d, 3>>> TriangulatePlanarPolygon(
    std::span<const Vec3d> outline, std::span<const std::vector<Vec3d>> holes = {});

// The same region as convex polygons: the triangles merged across their shared edges while
// the union stays convex (Hertel and Mehlhorn's method: at most four times the fewest convex
// pieces). Each piece runs counterclockwise about the outline's normal; collinear vertices
// may remain on a piece's edges. Fails as TriangulatePlanarPolygon.
absl::StatusOr<std::vector<std::vector<Vec3d>>> ConvexPiecesOfPlanarPolygon(
    std::span<const Vec3d> outline, std::span<const std::vector<Vec3d>> holes = {});

}  // namespace fenestra
