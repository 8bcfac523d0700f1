#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
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

// `room`'s BVH with a Venetian blind's slats beside it under a new root, without a build:
// `slat_corners` holds 8 corners per slat in SlatBoxes::Corner's order
// (core/geometry/slat_boxes.h, in `room`'s frame); each slat's faces become triangles as
// GenerateBlind meshes them, indices from `first_index` on (12 per slat, in the mesh's
// order), in two leaves under a node of their own, and the slats a balanced tree in stack
// order (neighbours in the stack are neighbours in space). For a design's indoor replay on
// the GPU: microseconds, where a build of the room with the blind takes a tenth of a
// millisecond, and the same triangles.
// With several blinds, `slats_per_blind` gives each one's count (their corners one blind
// after the other): the slats of one blind are a subtree of their own.
BvhLayout BvhWithSlats(const BvhLayout& room, const std::vector<Vec3f>& slat_corners,
                       uint32_t first_index, const std::vector<int>& slats_per_blind = {});

}  // namespace fenestra
