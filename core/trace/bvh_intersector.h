// Closest-hit traversal of a flattened BVH (core/trace/bvh.h), for the CPU and the GPU.
//
// Stack-based, nearer child first, in the while-while form of T. Aila and S. Laine,
// "Understanding the Efficiency of Ray Traversal on GPUs", HPG 2009, ordered: a leaf met is
// held back while the ray has inner nodes nearer than it to visit, then tested before
// anything farther. The lanes of a warp so test their leaves together instead of each
// leaving the others idle, and the closest hit found so far still culls every node beyond
// it (a waiting node keeps the distance at which the ray enters it). Triangles use the
// watertight ray/triangle test of S. Woop, C. Benthin, I. Wald, "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013: edges shared by two triangles are hit by exactly one of
// them, so no ray slips through a seam; a ray exactly on an edge falls back to double
// precision as the paper prescribes. Box tests are conservative (the slab distances are
// widened by a few ulps), so a ray grazing a box is never culled. Hit points are placed as
// the CPU backend places them (SurfacePoint, core/trace/ray_offset.h).
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

// Node and triangle fetches: on the GPU as 16-byte loads through the read-only cache.
FENESTRA_CPU_GPU inline BvhNode LoadNode(const BvhNode* node) {
#if defined(__CUDA_ARCH__)
  const float4* p = reinterpret_cast<const float4*>(node);
  const float4 a = __ldg(p), b = __ldg(p + 1), c = __ldg(p + 2), d = __ldg(p + 3);
  BvhNode n;
  n.lo[0][0] = a.x, n.lo[0][1] = a.y, n.lo[0][2] = a.z, n.lo[1][0] = a.w;
  n.lo[1][1] = b.x, n.lo[1][2] = b.y, n.hi[0][0] = b.z, n.hi[0][1] = b.w;
  n.hi[0][2] = c.x, n.hi[1][0] = c.y, n.hi[1][1] = c.z, n.hi[1][2] = c.w;
  n.child[0] = __float_as_int(d.x), n.child[1] = __float_as_int(d.y);
  return n;
#else
  return *node;
#endif
}

FENESTRA_CPU_GPU inline void LoadTriangle(const BvhTriangle* triangle, Vec3f* v0, Vec3f* v1,
                                          Vec3f* v2) {
#if defined(__CUDA_ARCH__)
  const float4* p = reinterpret_cast<const float4*>(triangle);
  const float4 a = __ldg(p), b = __ldg(p + 1), c = __ldg(p + 2);
  *v0 = {a.x, a.y, a.z}, *v1 = {a.w, b.x, b.y}, *v2 = {b.z, b.w, c.x};
#else
  *v0 = triangle->v0, *v1 = triangle->v1, *v2 = triangle->v2;
#endif
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

  // Closest hit below t_max; with any_hit, stops at the first hit (and fills no `hit`). On
  // the GPU a kernel calls one copy of it: the indoor stage queries at three places (its
  // rays, its window connections, their outdoor test), and inlined at each it took twice
  // as long (bench/README.md); the one-stage kernel loses 5% of its rays per second.
#if defined(__CUDA_ARCH__)
  __noinline__
#endif
      FENESTRA_CPU_GPU bool
      Traverse(Vec3f origin, Vec3f direction, float t_max, bool any_hit, SurfaceHit* hit) const {
    const WatertightRay ray(origin, direction);
    // A zero direction component becomes a tiny one: its slab test then needs no NaN case
    // (0 x inf), and it stays conservative (a ray in a slab's plane enters the box)
    const Vec3f inv = {1.0f / (direction.x != 0.0f ? direction.x : 1e-30f),
                       1.0f / (direction.y != 0.0f ? direction.y : 1e-30f),
                       1.0f / (direction.z != 0.0f ? direction.z : 1e-30f)};
    float t_best = t_max;
    float best_b1 = 0, best_b2 = 0;
    int32_t best = -1;
    TraversalStack stack;
    int32_t node = 0;  // the next node to visit: inner (>= 0), a leaf (< 0) or kDone
    float node_near = 0;
    int32_t leaf = 0;  // a leaf held back (< 0), or none
    float leaf_near = INFINITY;
    while (node != TraversalStack::kDone) {
      if (node < 0 && leaf == 0) {
        leaf = node, leaf_near = node_near;
        stack.Pop(t_best, &node, &node_near);
      }
      // Inner nodes, as long as they lie nearer than the leaf held back
      while (node >= 0 && node != TraversalStack::kDone && !(leaf != 0 && node_near >= leaf_near)) {
        const BvhNode n = LoadNode(nodes + node);
        float near0 = 0, near1 = 0;
        const bool enter0 = n.child[0] != kBvhEmptyChild && Slab(n, 0, origin, inv, t_best, &near0);
        const bool enter1 = n.child[1] != kBvhEmptyChild && Slab(n, 1, origin, inv, t_best, &near1);
        if (!enter0 && !enter1) {
          stack.Pop(t_best, &node, &node_near);
        } else {
          // The nearer child next, the other waits
          const bool take1 = !enter0 || (enter1 && near1 < near0);
          node = take1 ? n.child[1] : n.child[0], node_near = take1 ? near1 : near0;
          if (enter0 && enter1) stack.Push(take1 ? n.child[0] : n.child[1], take1 ? near0 : near1);
        }
        if (node < 0 && leaf == 0) {
          leaf = node, leaf_near = node_near;
          stack.Pop(t_best, &node, &node_near);
        }
      }
      // The leaf held back, before anything farther
      if (leaf < 0) {
        if (Leaf(ray, leaf, any_hit, &t_best, &best, &best_b1, &best_b2) && any_hit) return true;
        leaf = 0, leaf_near = INFINITY;
      }
      if (node != TraversalStack::kDone && node_near > t_best) stack.Pop(t_best, &node, &node_near);
    }
    if (best < 0) return false;
    const BvhTriangle& tri = triangles[best];
    hit->position = SurfacePoint(tri.v0, tri.v1, tri.v2, best_b1, best_b2);
    hit->normal = Cross(tri.v1 - tri.v0, tri.v2 - tri.v0);
    hit->triangle = tri.index;
    return true;
  }

  // Nodes waiting to be visited with the distance at which the ray enters them; kDone at the
  // bottom ends the traversal.
  struct TraversalStack {
    static constexpr int32_t kDone = INT32_MAX;
    int32_t node[kStackSize];
    float near[kStackSize];
    int size = 1;
    FENESTRA_CPU_GPU TraversalStack() {
      node[0] = kDone;
      near[0] = -INFINITY;
    }
    FENESTRA_CPU_GPU void Push(int32_t n, float t) {
      if (size < kStackSize) node[size] = n, near[size++] = t;
    }
    // The last pushed node the ray enters before t_best (those beyond it are dropped
    // unfetched), or kDone.
    FENESTRA_CPU_GPU void Pop(float t_best, int32_t* n, float* t) {
      while (near[size - 1] > t_best) --size;
      --size;
      *n = node[size], *t = near[size];
    }
  };

  // Whether the ray meets child i's box before t_best; *t_near = where it enters. Slab
  // distances are widened by 2 ulps each way (Ize, "Robust BVH Ray Traversal", 2013).
  FENESTRA_CPU_GPU static bool Slab(const BvhNode& n, int i, Vec3f o, Vec3f inv, float t_best,
                                    float* t_near) {
    const float kWiden = 1.0f + 4.0f * 5.96e-8f;
    const float ax = (n.lo[i][0] - o.x) * inv.x, bx = (n.hi[i][0] - o.x) * inv.x;
    const float ay = (n.lo[i][1] - o.y) * inv.y, by = (n.hi[i][1] - o.y) * inv.y;
    const float az = (n.lo[i][2] - o.z) * inv.z, bz = (n.hi[i][2] - o.z) * inv.z;
    const float t0 = fmaxf(fmaxf(0.0f, fminf(ax, bx)), fmaxf(fminf(ay, by), fminf(az, bz)));
    const float t1 = fminf(fminf(t_best, fmaxf(ax, bx) * kWiden),
                           fminf(fmaxf(ay, by) * kWiden, fmaxf(az, bz) * kWiden));
    *t_near = t0;
    return t0 <= t1;
  }

  // Tests the triangles of leaf `child`; true when one is hit closer than *t_best.
  FENESTRA_CPU_GPU bool Leaf(const WatertightRay& ray, int32_t child, bool any_hit, float* t_best,
                             int32_t* best, float* best_b1, float* best_b2) const {
    const int32_t code = ~child;
    const int32_t begin = code / kBvhMaxLeafSize;
    const int32_t end = begin + code % kBvhMaxLeafSize + 1;
    bool found = false;
    for (int32_t t = begin; t < end; ++t) {
      Vec3f v0, v1, v2;
      LoadTriangle(triangles + t, &v0, &v1, &v2);
      float b0, b1, b2;
      if (IntersectWatertight(ray, v0, v1, v2, t_best, &b0, &b1, &b2)) {
        *best = t, *best_b1 = b1, *best_b2 = b2;
        found = true;
        if (any_hit) break;
      }
    }
    return found;
  }
};

}  // namespace fenestra
