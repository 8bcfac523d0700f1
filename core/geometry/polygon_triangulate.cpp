#include "core/geometry/polygon_triangulate.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <optional>
#include <tuple>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geometry/polygon_rings.h"

namespace fenestra {
namespace {

// A merged convex piece may turn back by this much (relative to its longest edge squared):
// a thousandth of what a scene's convexity check allows.
constexpr double kMergeTurn = 1e-9;
// Point tests the ear clipping may make before giving up: well above the few full passes a
// polygon of kMaxTriangulatedVertices needs.
constexpr int64_t kEarWork = 100'000'000;

using planar::Component;
using planar::Distance;
using planar::Orient;
using planar::PlanePolygon;
using planar::Vec2;

absl::Status Invalid(const std::string& reason) { return absl::InvalidArgumentError(reason); }

// The rings joined into one by bridges, then cut into ears.
class EarClipper {
 public:
  // `rings`: an outline (counterclockwise) and its holes (clockwise), as point indices;
  // `place`: per point, the id of its place (points within eps_length of each other share it).
  EarClipper(const PlanePolygon& poly, std::vector<std::vector<int>> rings,
             const std::vector<int>& place)
      : poly_(poly),
        rings_(std::move(rings)),
        place_(place),
        count_(static_cast<size_t>(*std::max_element(place.begin(), place.end())) + 1, 0),
        bridged_(rings_.size(), false) {}

  absl::StatusOr<std::vector<std::array<int, 3>>> Run() {
    start_ = AddRing(rings_[0], -1);
    // Holes from the rightmost one in, so that each bridge runs to what lies right of it
    std::vector<std::pair<double, size_t>> order;
    for (size_t h = 1; h < rings_.size(); ++h) order.push_back({-RightmostX(h), h});
    std::sort(order.begin(), order.end());
    for (const auto& [unused, h] : order) FENESTRA_RETURN_IF_ERROR(Bridge(h));
    FENESTRA_RETURN_IF_ERROR(Clip());
    return std::move(triangles_);
  }

 private:
  struct Node {
    int point;
    int prev, next;
    bool removed;
  };

  Vec2 At(int node) const { return poly_.At(nodes_[static_cast<size_t>(node)].point); }
  // The number of live nodes at `node`'s place.
  int& Count(int node) {
    return count_[static_cast<size_t>(place_[static_cast<size_t>(N(node).point)])];
  }
  Node& N(int node) { return nodes_[static_cast<size_t>(node)]; }
  const Node& N(int node) const { return nodes_[static_cast<size_t>(node)]; }

  // Appends ring points as a circular list (after node `after` when >= 0); returns the first.
  int AddRing(const std::vector<int>& points, int after) {
    int first = -1, last = after;
    for (const int p : points) {
      const int node = static_cast<int>(nodes_.size());
      nodes_.push_back({p, node, node, false});
      ++Count(node);
      if (last >= 0) {
        N(node).next = N(last).next;
        N(node).prev = last;
        N(N(last).next).prev = node;
        N(last).next = node;
      }
      if (first < 0) first = node;
      last = node;
    }
    live_ += static_cast<int>(points.size());
    return first;
  }

  double RightmostX(size_t h) const {
    double x = -HUGE_VAL;
    for (const int p : rings_[h]) x = std::max(x, poly_.At(p).x);
    return x;
  }

  // Whether `p` lies within the angle the ring makes at `node` (its inside).
  bool LocallyInside(int node, Vec2 p) const {
    const Vec2 a = At(N(node).prev), b = At(node), c = At(N(node).next);
    if (Orient(a, b, c) >= 0) return Orient(a, b, p) >= 0 && Orient(b, c, p) >= 0;
    return Orient(a, b, p) >= 0 || Orient(b, c, p) >= 0;
  }

  // The outer ring's node that hole h's rightmost vertex M sees (Eberly): the nearest edge
  // a ray from M towards +x meets, its end further right, or the vertex inside the triangle
  // of M, the hit and that end that lies closest in angle to the ray.
  absl::StatusOr<int> VisibleNode(Vec2 m) const {
    int edge = -1;
    double best = HUGE_VAL;
    for (int node = start_, k = 0; k < live_; node = N(node).next, ++k) {
      const Vec2 a = At(node), b = At(N(node).next);
      if (a.y == b.y || std::min(a.y, b.y) > m.y || std::max(a.y, b.y) < m.y) continue;
      const double x = a.x + (m.y - a.y) * (b.x - a.x) / (b.y - a.y);
      if (x >= m.x - poly_.eps_length && x < best) {
        best = x;
        edge = node;
      }
    }
    if (edge < 0) return Invalid("a hole lies outside the outline");
    const Vec2 hit{std::max(best, m.x), m.y};
    const int a = edge, b = N(edge).next;
    if (Distance(hit, At(a)) <= poly_.eps_length) return Occurrence(a, m);
    if (Distance(hit, At(b)) <= poly_.eps_length) return Occurrence(b, m);
    int chosen = At(a).x > At(b).x ? a : b;
    const Vec2 p = At(chosen);
    double best_distance = Distance(p, m), best_cos = (p.x - m.x) / best_distance;
    for (int node = start_, k = 0; k < live_; node = N(node).next, ++k) {
      const Vec2 r = At(node);
      if (node == chosen || Distance(r, m) <= poly_.eps_length) continue;
      const double o1 = Orient(m, hit, r), o2 = Orient(hit, p, r), o3 = Orient(p, m, r);
      const bool inside = (o1 > 0 && o2 > 0 && o3 > 0) || (o1 < 0 && o2 < 0 && o3 < 0);
      // On the way to the end, it hides the end
      if (!inside && !(poly_.OnSegment(r, m, p) && Distance(r, p) > poly_.eps_length)) continue;
      const double distance = Distance(r, m);
      const double cos = (r.x - m.x) / distance;
      if (cos > best_cos || (cos == best_cos && distance < best_distance)) {
        best_cos = cos;
        best_distance = distance;
        chosen = node;
      }
    }
    return Occurrence(chosen, m);
  }

  // Whether a bridge from hole h's vertex k (point m) to `node` is sound: it starts into the
  // region at both ends, and crosses or touches no edge of the ring or of a hole.
  bool BridgeSound(size_t h, size_t k, int node) {
    const std::vector<int>& hole = rings_[h];
    const Vec2 m = poly_.At(hole[k]), p = At(node);
    if (Distance(m, p) <= poly_.eps_length) return true;  // the hole touches the ring there
    const Vec2 before = poly_.At(hole[(k + hole.size() - 1) % hole.size()]);
    const Vec2 after = poly_.At(hole[(k + 1) % hole.size()]);
    const bool convex = Orient(before, m, after) >= 0;
    const bool leaves = convex ? Orient(before, m, p) >= 0 && Orient(m, after, p) >= 0
                               : Orient(before, m, p) >= 0 || Orient(m, after, p) >= 0;
    if (!leaves || !LocallyInside(node, m)) return false;
    work_ += live_;
    const auto clear = [&](Vec2 a, Vec2 b) {
      if (poly_.Cross(m, p, a, b)) return false;
      return !(!poly_.Near(a, m) && !poly_.Near(a, p) && poly_.OnSegment(a, m, p));
    };
    int other = start_;
    for (int i = 0; i < live_; ++i, other = N(other).next) {
      if (!clear(At(other), At(N(other).next))) return false;
    }
    for (size_t g = 1; g < rings_.size(); ++g) {
      if (bridged_[g] && g != h) continue;  // in the ring already
      const std::vector<int>& ring = rings_[g];
      for (size_t i = 0; i < ring.size(); ++i) {
        if (!clear(poly_.At(ring[i]), poly_.At(ring[(i + 1) % ring.size()]))) return false;
      }
    }
    return true;
  }

  // Of the nodes at `node`'s point (a bridge repeats them), the one whose inside holds m.
  int Occurrence(int node, Vec2 m) const {
    for (int other = start_, k = 0; k < live_; other = N(other).next, ++k) {
      if (poly_.Same(N(other).point, N(node).point) && LocallyInside(other, m)) return other;
    }
    return node;
  }

  // Joins hole h to the outer ring: ..., P, M, the hole from M round to M, P, ... M is the
  // hole's rightmost vertex and P the one it sees (Eberly); where touching holes hide that
  // one, the nearest sound bridge from any of the hole's vertices.
  absl::Status Bridge(size_t h) {
    const std::vector<int>& hole = rings_[h];
    size_t m = 0;
    for (size_t k = 1; k < hole.size(); ++k) {
      if (poly_.At(hole[k]).x > poly_.At(hole[m]).x) m = k;
    }
    FENESTRA_ASSIGN_OR_RETURN(p, VisibleNode(poly_.At(hole[m])));
    if (!BridgeSound(h, m, p)) {
      double nearest = HUGE_VAL;
      std::optional<std::pair<size_t, int>> best;
      for (size_t k = 0; k < hole.size(); ++k) {
        int node = start_;
        for (int i = 0; i < live_; ++i, node = N(node).next) {
          if (work_ > kEarWork) return Invalid("the polygon is too intricate to triangulate");
          const double d = Distance(poly_.At(hole[k]), At(node));
          if (d < nearest && BridgeSound(h, k, node)) {
            nearest = d;
            best = std::pair{k, node};
          }
        }
      }
      if (!best) return Invalid(absl::StrCat("hole ", h - 1, " cannot be joined to the outline"));
      std::tie(m, p) = *best;
    }
    std::vector<int> spliced;
    for (size_t k = 0; k <= hole.size(); ++k) spliced.push_back(hole[(m + k) % hole.size()]);
    spliced.push_back(N(p).point);
    AddRing(spliced, p);
    bridged_[h] = true;
    return absl::OkStatus();
  }

  void Remove(int node) {
    N(node).removed = true;
    --Count(node);
    N(N(node).prev).next = N(node).next;
    N(N(node).next).prev = N(node).prev;
    if (start_ == node) start_ = N(node).next;
    --live_;
  }

  // A node that adds nothing: at its successor's point, the tip of a spike of no width (its
  // neighbours at one point), or on the straight line through its neighbours where no other
  // part of the ring touches.
  bool Idle(int node) {
    const int prev = N(node).prev, next = N(node).next;
    return poly_.Same(N(node).point, N(next).point) || poly_.Same(N(prev).point, N(next).point) ||
           (Count(node) == 1 && poly_.Sign(Orient(At(prev), At(node), At(next))) == 0);
  }

  // Removes `node` when idle, then those that become idle as their neighbours go.
  void Settle(int node) {
    std::vector<int> todo{node};
    while (!todo.empty() && live_ > 2) {
      const int here = todo.back();
      todo.pop_back();
      if (N(here).removed || !Idle(here)) continue;
      todo.push_back(N(here).prev);
      todo.push_back(N(here).next);
      Remove(here);
    }
  }

  // Removes every idle node; returns whether any went.
  bool SettleAll() {
    bool any = false;
    for (bool changed = true; changed && live_ > 2;) {
      changed = false;
      int node = start_;
      for (int k = 0, count = live_; k < count && live_ > 2; ++k) {
        const int next = N(node).next;
        if (Idle(node)) {
          Remove(node);
          changed = any = true;
        }
        node = next;
      }
    }
    return any;
  }

  // Whether the triangle at `node` is an ear: convex, and no other vertex (but those at its
  // corners' points) inside it, or on it when `strict`.
  absl::StatusOr<bool> IsEar(int node, bool strict) {
    const int prev = N(node).prev, next = N(node).next;
    const Vec2 a = At(prev), b = At(node), c = At(next);
    if (poly_.Sign(Orient(a, b, c)) <= 0) return false;
    work_ += live_;
    if (work_ > kEarWork) return Invalid("the polygon is too intricate to triangulate");
    for (int other = N(next).next; other != prev; other = N(other).next) {
      const Vec2 p = At(other);
      if (poly_.Near(p, a) || poly_.Near(p, b) || poly_.Near(p, c)) continue;
      const int s1 = poly_.Sign(Orient(a, b, p)), s2 = poly_.Sign(Orient(b, c, p)),
                s3 = poly_.Sign(Orient(c, a, p));
      if (strict ? (s1 >= 0 && s2 >= 0 && s3 >= 0) : (s1 > 0 && s2 > 0 && s3 > 0)) return false;
      if (!strict && poly_.OnSegment(p, c, a)) return false;  // the cut would touch it
    }
    // No edge crosses the cut from a to c: an edge from a corner's place (a seam) may enter
    // the triangle without a vertex in it
    for (int other = next; other != prev; other = N(other).next) {
      const Vec2 p = At(other), q = At(N(other).next);
      if (poly_.Cross(a, c, p, q)) return false;
      // Nor runs through it from side to side (its ends on the triangle's sides)
      const Vec2 mid{0.5 * (p.x + q.x), 0.5 * (p.y + q.y)};
      if (poly_.Sign(Orient(a, b, mid)) > 0 && poly_.Sign(Orient(b, c, mid)) > 0 &&
          poly_.Sign(Orient(c, a, mid)) > 0) {
        return false;
      }
    }
    // Then the triangle lies wholly inside the ring or wholly outside it (beside a seam, or
    // in a hole that touches the ring): its centroid tells which
    return InsideRing(Vec2{(a.x + b.x + c.x) / 3, (a.y + b.y + c.y) / 3});
  }

  // Whether `p` lies inside the live ring (crossing number: edges run along a seam both
  // ways and cancel).
  bool InsideRing(Vec2 p) const {
    bool inside = false;
    int node = start_;
    for (int k = 0; k < live_; ++k, node = N(node).next) {
      const Vec2 a = At(node), b = At(N(node).next);
      if ((a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y)) {
        inside = !inside;
      }
    }
    return inside;
  }

  // Cuts the ear at `node`; returns a live node beside it, to go on from.
  int CutEar(int node) {
    const int prev = N(node).prev, next = N(node).next;
    triangles_.push_back({N(prev).point, N(node).point, N(next).point});
    Remove(node);
    Settle(prev);
    Settle(next);
    return !N(prev).removed ? prev : (!N(next).removed ? next : start_);
  }

  // Cuts ears until a triangle is left; when no ear is found, drops idle nodes, then takes
  // an ear that only touches other vertices.
  absl::Status Clip() {
    SettleAll();
    int node = start_, misses = 0;
    while (live_ > 3) {
      FENESTRA_ASSIGN_OR_RETURN(ear, IsEar(node, true));
      if (ear) {
        node = CutEar(node);
        misses = 0;
        continue;
      }
      node = N(node).next;
      if (++misses < live_) continue;
      misses = 0;
      if (SettleAll()) {
        node = start_;
        continue;
      }
      std::optional<int> weak;
      for (int k = 0, candidate = start_; k < live_; ++k, candidate = N(candidate).next) {
        FENESTRA_ASSIGN_OR_RETURN(touching, IsEar(candidate, false));
        if (touching) {
          weak = candidate;
          break;
        }
      }
      if (!weak) return Invalid("the polygon cannot be triangulated: its outline or holes cross");
      node = CutEar(*weak);
    }
    if (live_ == 3 && poly_.Sign(Orient(At(N(start_).prev), At(start_), At(N(start_).next))) > 0) {
      triangles_.push_back({N(N(start_).prev).point, N(start_).point, N(N(start_).next).point});
    }
    return absl::OkStatus();
  }

  const PlanePolygon& poly_;
  std::vector<std::vector<int>> rings_;
  const std::vector<int>& place_;  // point -> id of its place
  std::vector<int> count_;         // place -> live nodes there
  std::vector<bool> bridged_;
  std::vector<Node> nodes_;
  int start_ = 0;
  int live_ = 0;
  int64_t work_ = 0;
  std::vector<std::array<int, 3>> triangles_;
};

absl::StatusOr<std::pair<PlanePolygon, std::vector<std::array<int, 3>>>> Triangulate(
    std::span<const Vec3d> outline, std::span<const std::vector<Vec3d>> holes) {
  FENESTRA_ASSIGN_OR_RETURN(poly, planar::ToPlane(outline, holes));
  FENESTRA_RETURN_IF_ERROR(planar::CheckRings(poly));
  planar::SplitAtTouches(poly);
  const std::vector<int> place = planar::Places(poly);
  std::vector<std::array<int, 3>> triangles;
  for (Component& component : planar::BoundaryLoops(poly, place)) {
    EarClipper clipper(poly, std::move(component), place);
    FENESTRA_ASSIGN_OR_RETURN(part, clipper.Run());
    triangles.insert(triangles.end(), part.begin(), part.end());
  }
  FENESTRA_RETURN_IF_ERROR(planar::CheckTriangles(poly, triangles));
  return std::pair{std::move(poly), std::move(triangles)};
}

// Merges pieces (counterclockwise lists of point indices) across shared edges while the
// union stays convex: Hertel and Mehlhorn.
class ConvexMerger {
 public:
  ConvexMerger(const PlanePolygon& poly, const std::vector<std::array<int, 3>>& triangles)
      : poly_(poly) {
    // Points at the same place (a seam's repeats) are one point
    std::map<std::pair<double, double>, int> canonical;
    for (size_t i = 0; i < poly.points.size(); ++i) {
      const Vec2 p = poly.points[i];
      id_.push_back(canonical.emplace(std::pair{p.x, p.y}, static_cast<int>(i)).first->second);
    }
    for (const auto& t : triangles) pieces_.push_back({id_[t[0]], id_[t[1]], id_[t[2]]});
    for (size_t i = 0; i < pieces_.size(); ++i) Index(i);
  }

  std::vector<std::vector<int>> Run() {
    for (size_t i = 0; i < pieces_.size(); ++i) {
      for (size_t k = 0; !pieces_[i].empty() && k < pieces_[i].size(); ++k) {
        const int u = pieces_[i][k], v = pieces_[i][(k + 1) % pieces_[i].size()];
        auto other = edges_.find({v, u});
        if (other == edges_.end() || other->second == i) continue;
        if (Merge(i, other->second, u, v)) k = static_cast<size_t>(-1);  // scan i again
      }
    }
    std::vector<std::vector<int>> out;
    for (auto& piece : pieces_) {
      if (!piece.empty()) out.push_back(std::move(piece));
    }
    return out;
  }

 private:
  void Index(size_t i) {
    const std::vector<int>& piece = pieces_[i];
    for (size_t k = 0; k < piece.size(); ++k) edges_[{piece[k], piece[(k + 1) % piece.size()]}] = i;
  }
  void Unindex(size_t i) {
    const std::vector<int>& piece = pieces_[i];
    for (size_t k = 0; k < piece.size(); ++k) {
      auto it = edges_.find({piece[k], piece[(k + 1) % piece.size()]});
      if (it != edges_.end() && it->second == i) edges_.erase(it);
    }
  }

  // Piece i with edge u -> v, piece j with v -> u: their union when convex at u and v.
  bool Merge(size_t i, size_t j, int u, int v) {
    const std::vector<int>& a = pieces_[i];
    const std::vector<int>& b = pieces_[j];
    const size_t au = static_cast<size_t>(std::find(a.begin(), a.end(), u) - a.begin());
    const size_t bv = static_cast<size_t>(std::find(b.begin(), b.end(), v) - b.begin());
    // a from v round to u, then b from u (exclusive) round to v (exclusive)
    std::vector<int> merged;
    for (size_t k = 1; k <= a.size(); ++k) merged.push_back(a[(au + k) % a.size()]);
    for (size_t k = 2; k < b.size(); ++k) merged.push_back(b[(bv + k) % b.size()]);
    std::vector<int> sorted = merged;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) return false;
    double longest = 0;
    for (size_t k = 0; k < merged.size(); ++k) {
      longest = std::max(longest,
                         Distance(poly_.At(merged[k]), poly_.At(merged[(k + 1) % merged.size()])));
    }
    for (size_t k = 0; k < merged.size(); ++k) {
      const int here = merged[k];
      if (here != u && here != v) continue;
      const Vec2 prev = poly_.At(merged[(k + merged.size() - 1) % merged.size()]);
      const Vec2 next = poly_.At(merged[(k + 1) % merged.size()]);
      if (Orient(prev, poly_.At(here), next) < -kMergeTurn * longest * longest) return false;
    }
    Unindex(i);
    Unindex(j);
    pieces_[i] = std::move(merged);
    pieces_[j].clear();
    Index(i);
    return true;
  }

  const PlanePolygon& poly_;
  std::vector<int> id_;
  std::vector<std::vector<int>> pieces_;
  std::map<std::pair<int, int>, size_t> edges_;
};

}  // namespace

absl::StatusOr<std::vector<std::array<Vec3d, 3>>> TriangulatePlanarPolygon(
    std::span<const Vec3d> outline, std::span<const std::vector<Vec3d>> holes) {
  FENESTRA_ASSIGN_OR_RETURN(result, Triangulate(outline, holes));
  const auto& [poly, triangles] = result;
  std::vector<std::array<Vec3d, 3>> out;
  out.reserve(triangles.size());
  for (const auto& t : triangles) {
    out.push_back({poly.points3[static_cast<size_t>(t[0])], poly.points3[static_cast<size_t>(t[1])],
                   poly.points3[static_cast<size_t>(t[2])]});
  }
  return out;
}

absl::StatusOr<std::vector<std::vector<Vec3d>>> ConvexPiecesOfPlanarPolygon(
    std::span<const Vec3d> outline, std::span<const std::vector<Vec3d>> holes) {
  FENESTRA_ASSIGN_OR_RETURN(result, Triangulate(outline, holes));
  const auto& [poly, triangles] = result;
  std::vector<std::vector<Vec3d>> out;
  for (const std::vector<int>& piece : ConvexMerger(poly, triangles).Run()) {
    std::vector<Vec3d> vertices;
    for (const int i : piece) vertices.push_back(poly.points3[static_cast<size_t>(i)]);
    out.push_back(std::move(vertices));
  }
  return out;
}

PolygonShape ShapeOfPolygon(const std::vector<Vec3d>& v) {
  PolygonShape shape;
  Vec3d normal{0, 0, 0};
  double size = 0;
  for (size_t k = 0; k < v.size(); ++k) {
    const Vec3d a = v[k], b = v[(k + 1) % v.size()];
    normal += Cross(a, b);
    size = std::max(size, Length(b - a));
  }
  shape.area = 0.5 * Length(normal) > kPolygonShapeTolerance * size * size;
  if (!shape.area) return shape;
  shape.normal = Normalize(normal);
  shape.planar = true;
  for (size_t k = 1; k < v.size(); ++k) {
    if (std::abs(Dot(v[k] - v[0], shape.normal)) > kPolygonShapeTolerance * size && shape.planar) {
      shape.planar = false;
      shape.off_plane = static_cast<int>(k);
    }
  }
  shape.convex = true;
  double turning = 0;  // the corners' turns summed [rad]
  for (size_t k = 0; k < v.size(); ++k) {
    const Vec3d a = v[k], b = v[(k + 1) % v.size()], c = v[(k + 2) % v.size()];
    if (Dot(Cross(b - a, c - b), shape.normal) < -kPolygonShapeTolerance * size * size &&
        shape.convex) {
      shape.convex = false;
      shape.concave = static_cast<int>((k + 1) % v.size());
    }
    turning += std::atan2(Dot(Cross(b - a, c - b), shape.normal), Dot(b - a, c - b));
  }
  // A star turns one way at every corner, but twice round
  if (std::abs(turning) > 3 * std::numbers::pi) shape.convex = false;
  return shape;
}

}  // namespace fenestra
