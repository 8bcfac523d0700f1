#include "core/geometry/rad_geometry.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <tuple>

namespace fenestra {
namespace {

// Relative tolerance of the polygon checks, BuildScene's (scene.cpp).
constexpr double kRadShapeTolerance = 1e-6;

using RadPointKey = std::tuple<double, double, double>;
RadPointKey KeyOfRadPoint(Vec3d p) { return {p.x, p.y, p.z}; }

// Where SplitRadSeams starts walking the polygon: at its least vertex (x, then y, then z),
// which lies on the outline, not on a hole; of several occurrences (a seam's end), the one
// after a vertex that occurs once, an outline vertex, so that no seam runs across the start.
size_t SeamWalkStart(const std::vector<Vec3d>& v, const std::map<RadPointKey, int>& count) {
  const auto least = std::min_element(
      v.begin(), v.end(), [](Vec3d a, Vec3d b) { return KeyOfRadPoint(a) < KeyOfRadPoint(b); });
  const RadPointKey key = KeyOfRadPoint(*least);
  const size_t n = v.size();
  for (size_t k = 0; k < n; ++k) {
    if (KeyOfRadPoint(v[k]) == key && count.at(KeyOfRadPoint(v[(k + n - 1) % n])) == 1) return k;
  }
  return static_cast<size_t>(least - v.begin());
}

}  // namespace

RadRings SplitRadSeams(const std::vector<Vec3d>& v) {
  RadRings rings;
  if (v.empty()) return rings;
  std::map<RadPointKey, int> count;
  for (const Vec3d& p : v) ++count[KeyOfRadPoint(p)];
  const size_t n = v.size(), start = SeamWalkStart(v, count);
  // Walk the polygon onto a stack; a vertex H that comes back right before the vertex A
  // preceding its last visit closes the run A, H, ..., H, A: the run from H is a hole
  std::vector<Vec3d>& stack = rings.outline;
  std::map<RadPointKey, std::vector<size_t>> on_stack;  // each point's places in `stack`
  for (size_t k = 0; k < n; ++k) {
    const Vec3d p = v[(start + k) % n];
    const auto seen = on_stack.find(KeyOfRadPoint(p));
    if (seen != on_stack.end() && !seen->second.empty() && k + 1 < n) {
      const size_t s = seen->second.back();
      if (s > 0 && KeyOfRadPoint(stack[s - 1]) == KeyOfRadPoint(v[(start + k + 1) % n])) {
        std::vector<Vec3d> hole(stack.begin() + static_cast<std::ptrdiff_t>(s), stack.end());
        for (size_t q = stack.size(); q-- > s;) on_stack[KeyOfRadPoint(stack[q])].pop_back();
        stack.resize(s);
        if (hole.size() >= 3) rings.holes.push_back(std::move(hole));  // else a slit
        ++k;  // the run's return to A, which is on the stack
        continue;
      }
    }
    on_stack[KeyOfRadPoint(p)].push_back(stack.size());
    stack.push_back(p);
  }
  return rings;
}

RadRectangle RadRectangleOf(const std::vector<Vec3d>& v, Vec3d normal, const Vec3d* inside) {
  RadRectangle r;
  r.center = 0.25 * (v[0] + v[1] + v[2] + v[3]);
  r.normal = inside && Dot(normal, *inside - r.center) > 0 ? -normal : normal;
  const Vec3d edges[2] = {v[1] - v[0], v[2] - v[1]};
  const Vec3d unit[2] = {Normalize(edges[0]), Normalize(edges[1])};
  const int axis = std::max(std::abs(unit[0].z), std::abs(unit[1].z)) > kRadShapeTolerance ? 2 : 1;
  const int along = std::abs(unit[1][axis]) > std::abs(unit[0][axis]) ? 1 : 0;
  const Vec3d up = unit[along][axis] < 0 ? -unit[along] : unit[along];
  r.up = Normalize(up - Dot(up, r.normal) * r.normal);
  r.height_m = Length(edges[along]);
  r.width_m = Length(edges[1 - along]);
  return r;
}

}  // namespace fenestra
