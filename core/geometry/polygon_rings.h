// The rings of a planar polygon in its own plane, checked and untangled for the ear clipping
// of polygon_triangulate.cpp (which is what uses them).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/common/vec3.h"

namespace fenestra::planar {

// Tolerances relative to the polygon's size (length) and its square (twice an area).
inline constexpr double kRelativeLength = 1e-9;

struct Vec2 {
  double x, y;
};
inline Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
inline double Cross(Vec2 a, Vec2 b) { return a.x * b.y - a.y * b.x; }
// Twice the signed area of triangle (a, b, c): positive when it turns counterclockwise.
inline double Orient(Vec2 a, Vec2 b, Vec2 c) { return Cross(b - a, c - a); }
inline double Distance(Vec2 a, Vec2 b) { return std::hypot(a.x - b.x, a.y - b.y); }

enum class Where { kInside, kOutside, kOnBoundary };

// The polygon in its own plane: every input point (outline, then each hole) in 2D, and the
// rings as indices of those points, without consecutive repeats: the outline counterclockwise,
// the holes clockwise.
struct PlanePolygon {
  std::vector<Vec3d> points3;
  std::vector<Vec2> points;
  std::vector<std::vector<int>> rings;
  std::vector<size_t> ring_start;  // index of each ring's first input point
  double eps_length = 0, eps_area = 0, size = 0;

  Vec2 At(int i) const { return points[static_cast<size_t>(i)]; }
  bool Same(int i, int j) const { return Near(At(i), At(j)); }
  bool Near(Vec2 a, Vec2 b) const {
    const Vec2 d = a - b;
    return d.x * d.x + d.y * d.y <= eps_length * eps_length;
  }
  int Sign(double orient) const { return orient > eps_area ? 1 : (orient < -eps_area ? -1 : 0); }

  // Whether segments ab and cd cross at a point inside both (touching and overlapping along a
  // line are not crossing).
  bool Cross(Vec2 a, Vec2 b, Vec2 c, Vec2 d) const {
    return Sign(Orient(a, b, c)) * Sign(Orient(a, b, d)) < 0 &&
           Sign(Orient(c, d, a)) * Sign(Orient(c, d, b)) < 0;
  }

  bool OnSegment(Vec2 p, Vec2 a, Vec2 b) const {
    if (p.x < std::min(a.x, b.x) - eps_length || p.x > std::max(a.x, b.x) + eps_length ||
        p.y < std::min(a.y, b.y) - eps_length || p.y > std::max(a.y, b.y) + eps_length) {
      return false;
    }
    const Vec2 ab = b - a, ap = p - a;
    const double length2 = ab.x * ab.x + ab.y * ab.y;
    const double t = length2 > 0 ? std::clamp((ap.x * ab.x + ap.y * ab.y) / length2, 0.0, 1.0) : 0;
    return Distance(p, Vec2{a.x + t * ab.x, a.y + t * ab.y}) <= eps_length;
  }

  // Where `p` lies against ring `r` (crossing number, the boundary within eps_length).
  Where Locate(Vec2 p, const std::vector<int>& ring) const {
    bool inside = false;
    for (size_t k = 0; k < ring.size(); ++k) {
      const Vec2 a = At(ring[k]), b = At(ring[(k + 1) % ring.size()]);
      if (OnSegment(p, a, b)) return Where::kOnBoundary;
      if ((a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y)) {
        inside = !inside;
      }
    }
    return inside ? Where::kInside : Where::kOutside;
  }
};

// The signed area of `ring`: positive when it turns counterclockwise.
double SignedArea(const PlanePolygon& poly, const std::vector<int>& ring);

// The polygon's plane (Newell's normal of the outline) and its points in 2D, checked as
// TriangulatePlanarPolygon says.
absl::StatusOr<PlanePolygon> ToPlane(std::span<const Vec3d> outline,
                                     std::span<const std::vector<Vec3d>> holes);

// The outline does not cross itself; every hole lies within it, crossing neither it nor
// another hole.
absl::Status CheckRings(const PlanePolygon& poly);

// Every ring with the vertices of all rings that lie inside one of its edges added there (a
// hole touching the outline, or another hole, in the middle of an edge), so that rings meet
// only at shared vertices.
void SplitAtTouches(PlanePolygon& poly);

// Per point, the id of its place: points within eps_length of each other share one.
std::vector<int> Places(const PlanePolygon& poly);

// An outline and the holes in it, as point indices.
using Component = std::vector<std::vector<int>>;

// The region's own boundary: the rings' edges (split where they touch) less every pair that
// runs along one segment both ways (a seam, a hole along the outline or another hole), traced
// into loops that keep the region on their left and turn as sharply left as they can where
// several meet, so that they touch only at vertices. Counterclockwise loops are outlines,
// clockwise ones holes, each given to the smallest outline around it.
std::vector<Component> BoundaryLoops(const PlanePolygon& poly, const std::vector<int>& place);

// Every triangle lies in the region: its centroid not outside the outline nor inside a hole.
absl::Status CheckTriangles(const PlanePolygon& poly,
                            const std::vector<std::array<int, 3>>& triangles);

}  // namespace fenestra::planar
