#include "core/trace/window_cells.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/common/thread_pool.h"

namespace fenestra {
namespace {

constexpr int kEdgeSamples = 16;        // per edge of a direction cell
constexpr double kAngleMargin = 1e-3;   // [rad], above the bulge of a cell's edges
constexpr double kLengthMargin = 1e-3;  // [m], float rounding of the rays

Vec3d ToDouble(Vec3f v) { return {v.x, v.y, v.z}; }

// A convex planar polygon, its vertices in counterclockwise order about its normal.
struct Polygon {
  std::vector<Vec3d> vertices;
  Vec3d normal;                // unit
  std::vector<Vec3d> outward;  // per edge i (from vertex i): unit, in the plane
};

Vec3d Normal(Vec3d a, Vec3d b, Vec3d c) {
  const Vec3d n = Cross(b - a, c - a);
  const double length = Length(n);
  return length > 0 ? n * (1 / length) : Vec3d{0, 0, 0};
}

// The quad a b c d when convex (every turn the same way about `normal`).
bool Convex(const std::vector<Vec3d>& q, Vec3d normal) {
  for (size_t i = 0; i < q.size(); ++i) {
    const Vec3d e0 = q[(i + 1) % q.size()] - q[i],
                e1 = q[(i + 2) % q.size()] - q[(i + 1) % q.size()];
    if (Dot(Cross(e0, e1), normal) <= 0) return false;
  }
  return true;
}

// The geometry's triangles as convex polygons: coplanar pairs that share an edge and form
// a convex quad merged.
std::vector<Polygon> Polygons(const TraceGeometry& geometry) {
  const size_t count = geometry.TriangleCount();
  std::vector<Polygon> polygons;
  std::vector<bool> used(count, false);
  auto vertex = [&](size_t t, int k) { return ToDouble(geometry.vertices[3 * t + k]); };
  for (size_t t = 0; t < count; ++t) {
    if (used[t] || !HasArea(geometry, t)) continue;
    used[t] = true;
    const Vec3d n = Normal(vertex(t, 0), vertex(t, 1), vertex(t, 2));
    Polygon polygon{{vertex(t, 0), vertex(t, 1), vertex(t, 2)}, n, {}};
    for (size_t u = t + 1; u < count && polygon.vertices.size() == 3; ++u) {
      if (used[u] || !HasArea(geometry, u)) continue;
      const Vec3d m = Normal(vertex(u, 0), vertex(u, 1), vertex(u, 2));
      if (std::abs(std::abs(Dot(m, n)) - 1) > 1e-9 ||
          std::abs(Dot(vertex(u, 0) - vertex(t, 0), n)) > 1e-6) {
        continue;
      }
      // The edge of t that u shares, and u's other vertex
      for (int k = 0; k < 3; ++k) {
        const Vec3d a = vertex(t, k), b = vertex(t, (k + 1) % 3), c = vertex(t, (k + 2) % 3);
        int shared = 0, other = -1;
        for (int j = 0; j < 3; ++j) {
          const Vec3d v = vertex(u, j);
          if ((v.x == a.x && v.y == a.y && v.z == a.z) ||
              (v.x == b.x && v.y == b.y && v.z == b.z)) {
            ++shared;
          } else {
            other = j;
          }
        }
        if (shared != 2) continue;
        const std::vector<Vec3d> quad = {a, vertex(u, other), b, c};
        if (Convex(quad, n)) {
          polygon.vertices = quad;
          used[u] = true;
        }
        break;
      }
    }
    for (size_t i = 0; i < polygon.vertices.size(); ++i) {
      const Vec3d a = polygon.vertices[i], b = polygon.vertices[(i + 1) % polygon.vertices.size()];
      polygon.outward.push_back(Normal(a, b, b + polygon.normal));
    }
    polygons.push_back(std::move(polygon));
  }
  return polygons;
}

// Unit directions (window frame, then trace frame) along the boundary of direction cell
// `cell`, and the largest angle by which the cell's boundary leaves their chords.
std::vector<Vec3d> Boundary(const HemisphereBasis& basis, const TraceWindow& window, int cell) {
  int ring = 0;
  while (basis.cumulative[ring] <= cell) ++ring;
  const int first = ring == 0 ? 0 : basis.cumulative[ring - 1];
  const int cells = basis.cumulative[ring] - first;
  const double n = basis.cell_count;
  const double cos_hi = 1 - first / n, cos_lo = 1 - basis.cumulative[ring] / n;
  const double theta_hi = std::acos(std::clamp(cos_lo, -1.0, 1.0));
  const double theta_lo = std::acos(std::clamp(cos_hi, -1.0, 1.0));
  const double phi0 = 2 * std::numbers::pi * (cell - first) / cells;
  const double phi1 = 2 * std::numbers::pi * (cell - first + 1) / cells;
  const Vec3d across = ToDouble(window.across), up = ToDouble(window.up),
              normal = ToDouble(window.normal);
  std::vector<Vec3d> out;
  auto add = [&](double theta, double phi) {
    out.push_back(across * (std::sin(theta) * std::cos(phi)) +
                  up * (std::sin(theta) * std::sin(phi)) + normal * std::cos(theta));
  };
  for (int k = 0; k <= kEdgeSamples; ++k) {
    const double s = static_cast<double>(k) / kEdgeSamples;
    const double phi = phi0 + s * (phi1 - phi0);
    add(theta_hi, phi);
    if (ring > 0) {
      add(theta_lo, phi);
      add(theta_lo + s * (theta_hi - theta_lo), phi0);
      add(theta_lo + s * (theta_hi - theta_lo), phi1);
    }
  }
  return out;
}

// Whether the ray from x along d meets `polygon` inside its edges by the margin (which
// grows with the distance and the obliquity of the hit); `towards` = d . normal.
bool Meets(const Polygon& polygon, Vec3d x, Vec3d d, double margin_angle) {
  const Vec3d n = polygon.normal;
  const double towards = Dot(d, n);
  if (std::abs(towards) < 2 * kAngleMargin) return false;
  const double t = Dot(polygon.vertices[0] - x, n) / towards;
  if (!(t > kLengthMargin)) return false;
  const Vec3d hit = x + d * t;
  const double margin = margin_angle * t / std::abs(towards) + kLengthMargin;
  for (size_t i = 0; i < polygon.vertices.size(); ++i) {
    if (Dot(hit - polygon.vertices[i], polygon.outward[i]) > -margin) return false;
  }
  return true;
}

// Whether every ray from `corners` along `directions` meets `polygon`, all from one side.
bool AllMeet(const Polygon& polygon, const std::vector<Vec3d>& corners,
             const std::vector<Vec3d>& directions) {
  const double side = Dot(directions[0], polygon.normal);
  for (const Vec3d& d : directions) {
    if (Dot(d, polygon.normal) * side <= 0) return false;
  }
  for (const Vec3d& x : corners) {
    for (const Vec3d& d : directions) {
      if (!Meets(polygon, x, d, kAngleMargin)) return false;
    }
  }
  return true;
}

}  // namespace

std::vector<uint8_t> WindowCellsMeetingSurfaces(const TraceGeometry& geometry,
                                                const TraceWindow& window,
                                                const HemisphereBasis& basis) {
  const std::vector<Polygon> polygons = Polygons(geometry);
  // Each direction cell's boundary and middle, the same from every part
  std::vector<std::vector<Vec3d>> boundaries(basis.cell_count);
  std::vector<Vec3d> middles(basis.cell_count);
  for (int cell = 0; cell < basis.cell_count; ++cell) {
    boundaries[cell] = Boundary(basis, window, cell);
    middles[cell] = ToDouble(window.ToWorld(SampleBasisCell(basis, cell, 0.5f, 0.5f)));
  }
  std::vector<uint8_t> met(static_cast<size_t>(window.Parts()) * basis.cell_count, 0);
  ParallelFor(window.Parts(), ResolveThreadCount(0), [&](uint64_t p) {
    const int part = static_cast<int>(p);
    std::vector<Vec3d> corners;
    for (const float u0 : {0.0f, 1.0f}) {
      for (const float u1 : {0.0f, 1.0f})
        corners.push_back(ToDouble(window.PartPoint(part, u0, u1)));
    }
    const Vec3d centre = ToDouble(window.PartPoint(part, 0.5f, 0.5f));
    for (int cell = 0; cell < basis.cell_count; ++cell) {
      const std::vector<Vec3d>& directions = boundaries[cell];
      const Vec3d middle = middles[cell];
      for (const Polygon& polygon : polygons) {
        // Only a polygon that the middle ray meets can be met by all
        if (Meets(polygon, centre, middle, 0) && AllMeet(polygon, corners, directions)) {
          met[static_cast<size_t>(part) * basis.cell_count + cell] = 1;
          break;
        }
      }
    }
  });
  return met;
}

}  // namespace fenestra
