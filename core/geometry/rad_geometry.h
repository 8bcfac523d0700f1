#pragma once

// The geometry ImportRadiance (rad_import.h) reads from a Radiance polygon: BuildScene's shape
// checks, the holes behind a polygon's seams, and a glass rectangle as a window.
#include <vector>

#include "core/common/vec3.h"

namespace fenestra {

// BuildScene's polygon checks (scene.cpp's AddPolygon), computed the same way, so that a
// polygon taken here is taken there; convexity also asks the corners to turn once round,
// which a star polygon (BuildScene takes it) does not.
struct RadPolygonShape {
  Vec3d normal{0, 0, 0};  // unit, Newell's; zero without area
  bool area = false;      // area above 1e-6 x the longest edge squared
  bool planar = false;    // every vertex within 1e-6 x the longest edge of the plane
  bool convex = false;    // every corner turns the same way, 2 pi in all
};
RadPolygonShape ShapeOfRadPolygon(const std::vector<Vec3d>& vertices);

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
