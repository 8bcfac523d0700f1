// Closest-hit traversal of a flattened BVH (core/trace/bvh.h), for the CPU and the GPU.
//
// Stack-based, nearer child first. Triangles use the watertight ray/triangle test of
// S. Woop, C. Benthin, I. Wald, "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013:
// edges shared by two triangles are hit by exactly one of them, so no ray slips through a
// seam; a ray exactly on an edge falls back to double precision as the paper prescribes.
// Box tests are conservative (the slab distances are widened by a few ulps), so a ray
// grazing a box is never culled. Hit points are placed as the CPU backend places them
// (SurfacePoint, core/trace/ray_offset.h).
#pragma once

#include <math.h>
#include <stdint.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"
#include "core/trace/bvh_layout.h"
#include "core/trace/path.h"
#include "core/trace/ray_offset.h"

namespace fenestra {

// A ray prepared for the watertight test: the axis of largest direction component becomes z.
struct WatertightRay {
  Vec3f origin;
  int kx, ky, kz;
  float sx, sy, sz;

  FENESTRA_CPU_GPU explicit WatertightRay(Vec3f o, Vec3f d) : origin(o) {
    const float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    kx = kz == 2 ? 0 : kz + 1;
    ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0.0f) {
      const int swap = kx;
      kx = ky;
      ky = swap;
    }
    sx = d[kx] / d[kz];
    sy = d[ky] / d[kz];
    sz = 1.0f / d[kz];
  }
};

// Watertight test; on a hit closer than *t_best sets *t_best and the barycentric weights
// (of v0, v1, v2) and returns true.
FENESTRA_CPU_GPU inline bool IntersectWatertight(const WatertightRay& ray, Vec3f v0, Vec3f v1,
                                                 Vec3f v2, float* t_best, float* b0, float* b1,
                                                 float* b2) {
  const Vec3f a = v0 - ray.origin, b = v1 - ray.origin, c = v2 - ray.origin;
  const float ax = a[ray.kx] - ray.sx * a[ray.kz], ay = a[ray.ky] - ray.sy * a[ray.kz];
  const float bx = b[ray.kx] - ray.sx * b[ray.kz], by = b[ray.ky] - ray.sy * b[ray.kz];
  const float cx = c[ray.kx] - ray.sx * c[ray.kz], cy = c[ray.ky] - ray.sy * c[ray.kz];
  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
  if (u == 0.0f || v == 0.0f || w == 0.0f) {
    u = static_cast<float>(static_cast<double>(cx) * by - static_cast<double>(cy) * bx);
    v = static_cast<float>(static_cast<double>(ax) * cy - static_cast<double>(ay) * cx);
    w = static_cast<float>(static_cast<double>(bx) * ay - static_cast<double>(by) * ax);
  }
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
  const float det = u + v + w;
  if (det == 0.0f) return false;
  const float az = ray.sz * a[ray.kz], bz = ray.sz * b[ray.kz], cz = ray.sz * c[ray.kz];
  const float t_scaled = u * az + v * bz + w * cz;
  // t = t_scaled / det must lie in (0, t_best)
  if (det > 0.0f ? (t_scaled <= 0.0f || t_scaled >= *t_best * det)
                 : (t_scaled >= 0.0f || t_scaled <= *t_best * det)) {
    return false;
  }
  const float inv_det = 1.0f / det;
  *t_best = t_scaled * inv_det;
  *b0 = u * inv_det;
  *b1 = v * inv_det;
  *b2 = w * inv_det;
  return true;
}

struct BvhIntersector {
  static constexpr int kStackSize = 64;
  const BvhNode* nodes;
  const BvhTriangle* triangles;

  FENESTRA_CPU_GPU bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const {
    return Traverse(origin, direction, INFINITY, false, hit);
  }

  FENESTRA_CPU_GPU bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    return Traverse(origin, direction, distance, true, nullptr);
  }

  // Closest hit below t_max; with any_hit, stops at the first hit (and fills no `hit`).
  FENESTRA_CPU_GPU bool Traverse(Vec3f origin, Vec3f direction, float t_max, bool any_hit,
                                 SurfaceHit* hit) const {
    const WatertightRay ray(origin, direction);
    const float inv[3] = {1.0f / direction.x, 1.0f / direction.y, 1.0f / direction.z};
    const float o[3] = {origin.x, origin.y, origin.z};
    // Slab distances are widened by 2 ulps each way (Ize, "Robust BVH Ray Traversal", 2013)
    const float kWiden = 1.0f + 4.0f * 5.96e-8f;
    float t_best = t_max;
    float best_b[3] = {0, 0, 0};
    int32_t best = -1;
    int32_t stack[kStackSize];
    int sp = 0;
    int32_t node = 0;
    for (;;) {
      const BvhNode& n = nodes[node];
      float t_near[2];
      bool enter[2];
      for (int i = 0; i < 2; ++i) {
        enter[i] = false;
        t_near[i] = 0.0f;
        if (n.child[i] == kBvhEmptyChild) continue;
        float t0 = 0.0f, t1 = t_best;
        for (int k = 0; k < 3; ++k) {
          float near_t = (n.lo[i][k] - o[k]) * inv[k];
          float far_t = (n.hi[i][k] - o[k]) * inv[k];
          if (near_t > far_t) {
            const float s = near_t;
            near_t = far_t;
            far_t = s;
          }
          // NaN (0 * inf for a ray in a slab plane) leaves the limits as they are
          t0 = near_t > t0 ? near_t : t0;
          t1 = far_t * kWiden < t1 ? far_t * kWiden : t1;
        }
        enter[i] = t0 <= t1;
        t_near[i] = t0;
      }
      // Visit leaves at once; push the farther inner child, descend into the nearer
      int32_t next[2];
      int count = 0;
      const int first = (enter[0] && enter[1] && t_near[1] < t_near[0]) ? 1 : 0;
      for (int k = 0; k < 2; ++k) {
        const int i = k == 0 ? first : 1 - first;
        if (!enter[i]) continue;
        const int32_t child = n.child[i];
        if (child >= 0) {
          next[count++] = child;
          continue;
        }
        const int32_t code = ~child;
        const int32_t begin = code / kBvhMaxLeafSize;
        const int32_t end = begin + code % kBvhMaxLeafSize + 1;
        for (int32_t t = begin; t < end; ++t) {
          const BvhTriangle& tri = triangles[t];
          float b0, b1, b2;
          if (IntersectWatertight(ray, tri.v0, tri.v1, tri.v2, &t_best, &b0, &b1, &b2)) {
            if (any_hit) return true;
            best = t;
            best_b[0] = b0, best_b[1] = b1, best_b[2] = b2;
          }
        }
      }
      if (count == 2) {
        if (sp < kStackSize) stack[sp++] = next[1];
        node = next[0];
      } else if (count == 1) {
        node = next[0];
      } else if (sp > 0) {
        node = stack[--sp];
      } else {
        break;
      }
    }
    if (best < 0) return false;
    const BvhTriangle& tri = triangles[best];
    hit->position = SurfacePoint(tri.v0, tri.v1, tri.v2, best_b[1], best_b[2]);
    hit->normal = Cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
    hit->triangle = tri.index;
    return true;
  }
};

}  // namespace fenestra
