#pragma once

#include "absl/status/statusor.h"
#include "core/trace/bvh_layout.h"

namespace fenestra {

struct TraceGeometry;

// Builds a binned-SAH BVH over the geometry's triangles with Embree's BVH builder
// (rtcBuildBVH, high quality), flattened for traversal on the CPU or the GPU.
absl::StatusOr<BvhLayout> BuildBvh(const TraceGeometry& geometry);

}  // namespace fenestra
