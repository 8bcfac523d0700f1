#pragma once

#include "absl/status/statusor.h"
#include "core/trace/bvh_layout.h"

namespace fenestra {

struct TraceGeometry;

// How much a BVH build may spend to make traversal faster.
enum class BvhQuality {
  kMedium,  // binned SAH: a room with a blind in well under a millisecond (a design per build)
  kHigh,    // binned SAH with spatial splits: tight boxes around thin tilted slats
};

// Builds a BVH over the geometry's triangles with Embree's BVH builder (rtcBuildBVH),
// flattened for traversal on the CPU or the GPU.
absl::StatusOr<BvhLayout> BuildBvh(const TraceGeometry& geometry,
                                   BvhQuality quality = BvhQuality::kHigh);

}  // namespace fenestra
