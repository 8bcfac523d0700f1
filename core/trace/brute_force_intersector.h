// A closest-hit intersector without acceleration structure: tests every triangle.
//
// Möller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection", JGT 2(1), 1997.
// Device-safe, so the CUDA build instantiates the shared path code with it, and the CPU
// tests compare it with Embree. Linear in the triangle count: for small scenes only.
#pragma once

#include <math.h>
#include <stdint.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"
#include "core/trace/path.h"
#include "core/trace/ray_offset.h"

namespace fenestra {

struct BruteForceIntersector {
  const Vec3f* vertices;  // 3 per triangle, local frame
  uint32_t triangle_count;

  FENESTRA_CPU_GPU bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    SurfaceHit hit;
    if (!Intersect(origin, direction, &hit)) return false;
    const Vec3f along = hit.position - origin;
    return Dot(along, along) < distance * distance;
  }

  FENESTRA_CPU_GPU bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const {
    float closest = INFINITY;
    uint32_t best = 0;
    float best_u = 0, best_v = 0;
    for (uint32_t i = 0; i < triangle_count; ++i) {
      const Vec3f v0 = vertices[3 * i];
      const Vec3f e1 = vertices[3 * i + 1] - v0;
      const Vec3f e2 = vertices[3 * i + 2] - v0;
      const Vec3f p = Cross(direction, e2);
      const float det = Dot(e1, p);
      if (!(det != 0.0f)) continue;  // parallel or degenerate
      const float inv_det = 1.0f / det;
      const Vec3f s = origin - v0;
      const float u = Dot(s, p) * inv_det;
      if (!(u >= 0.0f && u <= 1.0f)) continue;
      const Vec3f q = Cross(s, e1);
      const float v = Dot(direction, q) * inv_det;
      if (!(v >= 0.0f && u + v <= 1.0f)) continue;
      const float t = Dot(e2, q) * inv_det;
      if (t > 0.0f && t < closest) {
        closest = t;
        best = i;
        best_u = u;
        best_v = v;
      }
    }
    if (!(closest < INFINITY)) return false;
    const Vec3f v0 = vertices[3 * best], v1 = vertices[3 * best + 1], v2 = vertices[3 * best + 2];
    hit->position = SurfacePoint(v0, v1, v2, best_u, best_v);
    hit->normal = Cross(v1 - v0, v2 - v0);
    hit->triangle = best;
    return true;
  }
};

}  // namespace fenestra
