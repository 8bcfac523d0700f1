#include "core/geometry/polygon_rings.h"

#include <algorithm>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geometry/polygon_triangulate.h"

namespace fenestra::planar {
namespace {

// Largest |coordinate| taken: the products of differences stay far from overflowing.
constexpr double kMaxCoordinate = 1e100;

absl::Status Invalid(const std::string& reason) { return absl::InvalidArgumentError(reason); }

// "outline vertex 3", "hole 1 vertex 0"
std::string VertexName(int ring, size_t k) {
  return ring == 0 ? absl::StrCat("outline vertex ", k)
                   : absl::StrCat("hole ", ring - 1, " vertex ", k);
}

// Ring `r`'s points from `first` on, consecutive repeats dropped (the closing one too).
std::vector<int> RingWithoutRepeats(const PlanePolygon& poly, int first, size_t count) {
  std::vector<int> ring;
  for (size_t k = 0; k < count; ++k) {
    const int i = first + static_cast<int>(k);
    if (ring.empty() || !poly.Same(ring.back(), i)) ring.push_back(i);
  }
  while (ring.size() > 1 && poly.Same(ring.back(), ring.front())) ring.pop_back();
  return ring;
}

// The index of input point `point` among ring r's, for messages.
size_t EdgeName(const PlanePolygon& poly, size_t r, int point) {
  return static_cast<size_t>(point) - poly.ring_start[r];
}

// The loops of the rings' edges less those that run both ways (BoundaryLoops).
std::vector<std::vector<int>> TraceLoops(const PlanePolygon& poly, const std::vector<int>& place) {
  std::map<std::pair<int, int>, int> count;           // (place, place) -> edges along it that way
  std::vector<int> point_of(poly.points.size(), -1);  // place -> a point there
  for (const std::vector<int>& ring : poly.rings) {
    for (size_t k = 0; k < ring.size(); ++k) {
      const int a = place[static_cast<size_t>(ring[k])];
      const int b = place[static_cast<size_t>(ring[(k + 1) % ring.size()])];
      point_of[static_cast<size_t>(a)] = ring[k];
      if (a == b) continue;
      auto back = count.find({b, a});
      if (back != count.end() && back->second > 0) {
        --back->second;  // runs both ways: no boundary
      } else {
        ++count[{a, b}];
      }
    }
  }
  std::map<int, std::vector<int>> out;  // place -> the places its edges go to
  std::map<std::pair<int, int>, int> left = count;
  for (const auto& [edge, n] : count) {
    for (int i = 0; i < n; ++i) out[edge.first].push_back(edge.second);
  }
  const auto at = [&](int place_id) { return poly.At(point_of[static_cast<size_t>(place_id)]); };
  std::vector<std::vector<int>> loops;
  for (const auto& [edge, n] : count) {
    while (left[edge] > 0) {
      std::vector<int> loop;
      int from = edge.first, to = edge.second;
      for (size_t steps = 0; steps <= poly.points.size() * 4 && left[{from, to}] > 0; ++steps) {
        --left[{from, to}];
        loop.push_back(point_of[static_cast<size_t>(from)]);
        // Leave `to` by the edge first met turning clockwise from the way back
        const Vec2 back = at(from) - at(to);
        int best = -1;
        double best_angle = HUGE_VAL;
        for (const int next : out[to]) {
          const Vec2 d = at(next) - at(to);
          double angle = std::atan2(Cross(d, back), back.x * d.x + back.y * d.y);  // clockwise
          if (angle <= 0) angle += 2 * std::numbers::pi;
          if (angle < best_angle) best_angle = angle, best = next;
        }
        if (best < 0) break;
        from = to, to = best;
      }
      if (loop.size() >= 3) loops.push_back(std::move(loop));
    }
  }
  return loops;
}

}  // namespace

double SignedArea(const PlanePolygon& poly, const std::vector<int>& ring) {
  double twice = 0;
  const Vec2 o = poly.At(ring[0]);
  for (size_t k = 1; k + 1 < ring.size(); ++k) {
    twice += Orient(o, poly.At(ring[k]), poly.At(ring[k + 1]));
  }
  return 0.5 * twice;
}

absl::StatusOr<PlanePolygon> ToPlane(std::span<const Vec3d> outline,
                                     std::span<const std::vector<Vec3d>> holes) {
  if (outline.size() < 3) return Invalid("a polygon needs at least 3 vertices");
  size_t total = outline.size();
  for (const std::vector<Vec3d>& hole : holes) total += hole.size();
  if (total > kMaxTriangulatedVertices) {
    return Invalid(absl::StrCat(total, " vertices, more than the ", kMaxTriangulatedVertices,
                                " a polygon may have"));
  }
  PlanePolygon poly;
  poly.points3.assign(outline.begin(), outline.end());
  poly.ring_start.push_back(0);
  for (const std::vector<Vec3d>& hole : holes) {
    poly.ring_start.push_back(poly.points3.size());
    poly.points3.insert(poly.points3.end(), hole.begin(), hole.end());
  }
  Vec3d lo = poly.points3[0], hi = poly.points3[0];
  for (size_t i = 0; i < poly.points3.size(); ++i) {
    const Vec3d p = poly.points3[i];
    for (int axis = 0; axis < 3; ++axis) {
      if (!(std::abs(p[axis]) <= kMaxCoordinate)) {
        const size_t ring = static_cast<size_t>(
            std::upper_bound(poly.ring_start.begin(), poly.ring_start.end(), i) -
            poly.ring_start.begin() - 1);
        return Invalid(absl::StrCat(VertexName(static_cast<int>(ring), i - poly.ring_start[ring]),
                                    ": coordinates must be finite numbers within ",
                                    kMaxCoordinate));
      }
    }
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  poly.size = Length(hi - lo);
  poly.eps_length = kRelativeLength * poly.size;
  poly.eps_area = kRelativeLength * poly.size * poly.size;

  // Newell's normal, about the first vertex for precision
  const Vec3d o = outline[0];
  Vec3d normal{0, 0, 0};
  for (size_t k = 0; k < outline.size(); ++k) {
    normal += Cross(outline[k] - o, outline[(k + 1) % outline.size()] - o);
  }
  if (!(0.5 * Length(normal) > poly.eps_area)) return Invalid("the outline has no area");
  normal = Normalize(normal);
  const Vec3d axis = std::abs(normal.x) < 0.6 ? Vec3d{1, 0, 0} : Vec3d{0, 1, 0};
  const Vec3d u = Normalize(Cross(axis, normal));
  const Vec3d v = Cross(normal, u);
  for (size_t i = 0; i < poly.points3.size(); ++i) {
    const Vec3d d = poly.points3[i] - o;
    if (std::abs(Dot(d, normal)) > kTriangulationPlanarity * poly.size) {
      const size_t ring =
          static_cast<size_t>(std::upper_bound(poly.ring_start.begin(), poly.ring_start.end(), i) -
                              poly.ring_start.begin() - 1);
      return Invalid(absl::StrCat(VertexName(static_cast<int>(ring), i - poly.ring_start[ring]),
                                  " lies ", std::abs(Dot(d, normal)),
                                  " off the outline's plane: the polygon is not planar"));
    }
    poly.points.push_back({Dot(d, u), Dot(d, v)});
  }

  // The rings: the outline counterclockwise (as Newell's normal makes it), holes clockwise
  for (size_t r = 0; r < poly.ring_start.size(); ++r) {
    const size_t count =
        (r + 1 < poly.ring_start.size() ? poly.ring_start[r + 1] : poly.points3.size()) -
        poly.ring_start[r];
    std::vector<int> ring = RingWithoutRepeats(poly, static_cast<int>(poly.ring_start[r]), count);
    const std::string name = r == 0 ? "the outline" : absl::StrCat("hole ", r - 1);
    if (ring.size() < 3) return Invalid(name + " has fewer than 3 distinct vertices");
    const double area = SignedArea(poly, ring);
    if (!(std::abs(area) > poly.eps_area)) return Invalid(name + " has no area");
    if ((r == 0) != (area > 0)) std::reverse(ring.begin(), ring.end());
    poly.rings.push_back(std::move(ring));
  }
  return poly;
}

absl::Status CheckRings(const PlanePolygon& poly) {
  const std::vector<int>& outline = poly.rings[0];
  const size_t n = outline.size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // neighbours through the closing edge
      if (poly.Cross(poly.At(outline[i]), poly.At(outline[i + 1]), poly.At(outline[j]),
                     poly.At(outline[(j + 1) % n]))) {
        return Invalid(absl::StrCat("the outline crosses itself (its edges from vertex ",
                                    EdgeName(poly, 0, outline[i]), " and from vertex ",
                                    EdgeName(poly, 0, outline[j]), ")"));
      }
    }
  }
  const auto crosses = [&](const std::vector<int>& a, const std::vector<int>& b) {
    for (size_t i = 0; i < a.size(); ++i) {
      for (size_t j = 0; j < b.size(); ++j) {
        if (poly.Cross(poly.At(a[i]), poly.At(a[(i + 1) % a.size()]), poly.At(b[j]),
                       poly.At(b[(j + 1) % b.size()]))) {
          return true;
        }
      }
    }
    return false;
  };
  // Whether every vertex of a lies on b's boundary (a hole given twice)
  const auto on_boundary = [&](const std::vector<int>& a, const std::vector<int>& b) {
    return std::all_of(a.begin(), a.end(),
                       [&](int i) { return poly.Locate(poly.At(i), b) == Where::kOnBoundary; });
  };
  for (size_t h = 1; h < poly.rings.size(); ++h) {
    const std::vector<int>& hole = poly.rings[h];
    for (const int i : hole) {
      if (poly.Locate(poly.At(i), outline) == Where::kOutside) {
        return Invalid(absl::StrCat("hole ", h - 1, " lies outside the outline (its vertex ",
                                    EdgeName(poly, h, i), ")"));
      }
    }
    if (crosses(hole, outline))
      return Invalid(absl::StrCat("hole ", h - 1, " crosses the outline"));
    for (size_t g = 1; g < h; ++g) {
      const std::vector<int>& other = poly.rings[g];
      bool overlap = crosses(hole, other) || (on_boundary(hole, other) && on_boundary(other, hole));
      for (const int i : hole)
        overlap = overlap || poly.Locate(poly.At(i), other) == Where::kInside;
      for (const int i : other)
        overlap = overlap || poly.Locate(poly.At(i), hole) == Where::kInside;
      if (overlap) return Invalid(absl::StrCat("holes ", g - 1, " and ", h - 1, " overlap"));
    }
  }
  return absl::OkStatus();
}

void SplitAtTouches(PlanePolygon& poly) {
  std::vector<int> all;
  for (const std::vector<int>& ring : poly.rings) all.insert(all.end(), ring.begin(), ring.end());
  for (std::vector<int>& ring : poly.rings) {
    std::vector<int> split;
    for (size_t k = 0; k < ring.size(); ++k) {
      const int a = ring[k], b = ring[(k + 1) % ring.size()];
      const Vec2 pa = poly.At(a), pb = poly.At(b);
      std::vector<std::pair<double, int>> inside;  // (position along the edge, point)
      for (const int p : all) {
        if (poly.Same(p, a) || poly.Same(p, b) || !poly.OnSegment(poly.At(p), pa, pb)) continue;
        const Vec2 ab = pb - pa, ap = poly.At(p) - pa;
        inside.push_back({(ap.x * ab.x + ap.y * ab.y) / (ab.x * ab.x + ab.y * ab.y), p});
      }
      std::sort(inside.begin(), inside.end());
      split.push_back(a);
      for (const auto& [t, p] : inside) {
        if (!poly.Same(split.back(), p)) split.push_back(p);
      }
    }
    ring = std::move(split);
  }
}

std::vector<int> Places(const PlanePolygon& poly) {
  const size_t n = poly.points.size();
  std::vector<int> by_x(n);
  for (size_t i = 0; i < n; ++i) by_x[i] = static_cast<int>(i);
  std::sort(by_x.begin(), by_x.end(), [&](int a, int b) { return poly.At(a).x < poly.At(b).x; });
  std::vector<int> place(n, -1);
  int next = 0;
  for (size_t i = 0; i < n; ++i) {
    const int p = by_x[i];
    if (place[static_cast<size_t>(p)] >= 0) continue;
    place[static_cast<size_t>(p)] = next;
    for (size_t j = i + 1; j < n && poly.At(by_x[j]).x <= poly.At(p).x + poly.eps_length; ++j) {
      if (place[static_cast<size_t>(by_x[j])] < 0 && poly.Same(p, by_x[j])) {
        place[static_cast<size_t>(by_x[j])] = next;
      }
    }
    ++next;
  }
  return place;
}

std::vector<Component> BoundaryLoops(const PlanePolygon& poly, const std::vector<int>& place) {
  std::vector<std::vector<int>> loops = TraceLoops(poly, place);
  // Outlines and holes
  std::vector<Component> components;
  std::vector<double> areas;
  std::vector<std::vector<int>> holes;
  for (std::vector<int>& loop : loops) {
    const double area = SignedArea(poly, loop);
    if (poly.Sign(2 * area) > 0) {
      components.push_back({std::move(loop)});
      areas.push_back(area);
    } else if (poly.Sign(2 * area) < 0) {
      holes.push_back(std::move(loop));
    }
  }
  for (std::vector<int>& hole : holes) {
    // A point of the hole off the outlines' boundaries: the middle of one of its edges
    std::optional<size_t> owner;
    for (size_t c = 0; c < components.size(); ++c) {
      bool inside = false, decided = false;
      for (size_t k = 0; k < hole.size() && !decided; ++k) {
        const Vec2 a = poly.At(hole[k]), b = poly.At(hole[(k + 1) % hole.size()]);
        const Where where =
            poly.Locate(Vec2{0.5 * (a.x + b.x), 0.5 * (a.y + b.y)}, components[c][0]);
        if (where == Where::kOnBoundary) continue;
        inside = where == Where::kInside, decided = true;
      }
      if (inside && (!owner || areas[c] < areas[*owner])) owner = c;
    }
    if (owner) components[*owner].push_back(std::move(hole));
  }
  return components;
}

// Every triangle lies in the region: its centroid not outside the outline nor inside a hole.
absl::Status CheckTriangles(const PlanePolygon& poly,
                            const std::vector<std::array<int, 3>>& triangles) {
  for (const auto& t : triangles) {
    const Vec2 a = poly.At(t[0]), b = poly.At(t[1]), c = poly.At(t[2]);
    const Vec2 centroid{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3};
    bool outside = poly.Locate(centroid, poly.rings[0]) == Where::kOutside;
    for (size_t h = 1; h < poly.rings.size() && !outside; ++h) {
      outside = poly.Locate(centroid, poly.rings[h]) == Where::kInside;
    }
    if (outside) {
      return Invalid("the polygon cannot be triangulated: its outline or holes touch or cross");
    }
  }
  return absl::OkStatus();
}

}  // namespace fenestra::planar
