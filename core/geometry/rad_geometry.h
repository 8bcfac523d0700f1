#pragma once

// The geometry ImportRadiance (rad_import.h) reads from a Radiance polygon: the holes behind a
// polygon's seams, and a glass rectangle as a window (its shape: ShapeOfPolygon,
// polygon_triangulate.h).
#include <vector>

#include "core/common/vec3.h"

namespace fenestra {

// A polygon as its outline and the holes its seams reach. Radiance writes a wall with a hole
// as one outline that runs from a vertex A to the hole's first vertex H, round the hole, back
// to H and to A: each such run (A, H, ..., H, A, the vertices repeated exactly) is cut out as
// a hole, innermost first, whichever way round it runs (Radiance leaves the hole open either
// way). A polygon without seams is its own outline.
struct RadRings {
  std::vector<Vec3d> outline;
  std::vector<std::vector<Vec3d>> holes;
};
RadRings SplitRadSeams(const std::vector<Vec3d>& vertices);

// A rectangle as a window: its centre, the unit normal (`normal`, or its opposite when
// `normal` faces `inside`), `up` along the edge closest to +z (or, in a horizontal
// rectangle, to +y) made exactly perpendicular to the normal, and its sides along `up`
// (height) and across it (width).
struct RadRectangle {
  Vec3d center, normal, up;
  double width_m = 0, height_m = 0;
};
RadRectangle RadRectangleOf(const std::vector<Vec3d>& corners, Vec3d normal, const Vec3d* inside);

}  // namespace fenestra
