#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
#include "core/trace/path.h"
#include "core/trace/ray_offset.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {

// Closest-hit queries against an EmbreeScene, one ray at a time (rtcIntersect1). Cheap to
// copy; valid while its scene lives. Satisfies TracePath's Intersector contract.
struct EmbreeIntersector {
  RTCScene scene;
  const Vec3f* vertices;               // 3 per Embree primitive, local frame
  const uint32_t* primitive_triangle;  // Embree primitive -> mesh triangle

  bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray;
    ray.org_x = origin.x;
    ray.org_y = origin.y;
    ray.org_z = origin.z;
    ray.tnear = 0.0f;
    ray.dir_x = direction.x;
    ray.dir_y = direction.y;
    ray.dir_z = direction.z;
    ray.time = 0.0f;
    ray.tfar = distance;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(scene, &context, &ray);
    return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
  }

  bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit query;
    query.ray.org_x = origin.x;
    query.ray.org_y = origin.y;
    query.ray.org_z = origin.z;
    query.ray.tnear = 0.0f;
    query.ray.dir_x = direction.x;
    query.ray.dir_y = direction.y;
    query.ray.dir_z = direction.z;
    query.ray.time = 0.0f;
    query.ray.tfar = INFINITY;
    query.ray.mask = 0xFFFFFFFFu;
    query.ray.id = 0;
    query.ray.flags = 0;
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &query);
    if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;

    // The hit point from barycentrics (never origin + t * direction)
    const uint32_t prim = query.hit.primID;
    hit->position = SurfacePoint(vertices[3 * prim], vertices[3 * prim + 1], vertices[3 * prim + 2],
                                 query.hit.u, query.hit.v);
    hit->normal = {query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z};
    hit->triangle = primitive_triangle[prim];
    return true;
  }
};

// All triangles of a TraceGeometry with nonzero area in one Embree scene (robust mode,
// high build quality). Degenerate triangles are left out; they could never be hit.
class EmbreeScene {
 public:
  // Builds the scene; Internal error if Embree fails.
  static absl::StatusOr<std::unique_ptr<EmbreeScene>> Build(const TraceGeometry& geometry);
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  EmbreeIntersector Intersector() const {
    return {scene_, vertices_.data(), primitive_triangle_.data()};
  }
  size_t PrimitiveCount() const { return primitive_triangle_.size(); }

 private:
  EmbreeScene() = default;

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<Vec3f> vertices_;
  std::vector<uint32_t> primitive_triangle_;
};

}  // namespace fenestra
