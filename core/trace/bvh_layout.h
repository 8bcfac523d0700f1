#pragma once

// The flattened BVH that the traversal (bvh_intersector.h) reads, on the CPU or the GPU.
#include <cstdint>
#include <vector>

#include "core/common/vec3.h"

namespace fenestra {

// A binary BVH node holding both children's boxes (one fetch decides both), 64 bytes.
// child[i] >= 0: an inner node; child[i] < 0: a leaf, ~child[i] = first * 8 + (count - 1)
// into BvhLayout::triangles; child[i] == kBvhEmptyChild: no child.
struct alignas(16) BvhNode {
  float lo[2][3];
  float hi[2][3];
  int32_t child[2];
  int32_t pad[2];
};
static_assert(sizeof(BvhNode) == 64);

inline constexpr int kBvhMaxLeafSize = 8;
inline constexpr int32_t kBvhEmptyChild = INT32_MIN;

// A triangle in leaf order, 48 bytes: its vertices and its index in the TraceGeometry.
struct alignas(16) BvhTriangle {
  Vec3f v0, v1, v2;
  uint32_t index;
  uint32_t pad[2];
};
static_assert(sizeof(BvhTriangle) == 48);

// A flattened BVH: node 0 is the root (depth-first order).
struct BvhLayout {
  std::vector<BvhNode> nodes;
  std::vector<BvhTriangle> triangles;
  int depth = 0;  // longest root-to-leaf path, in nodes
};

}  // namespace fenestra
