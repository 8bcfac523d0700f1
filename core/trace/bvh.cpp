#include "core/trace/bvh.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <memory>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "core/geometry/slat_boxes.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {
namespace {

// Embree-side nodes, allocated by Embree's thread-local allocator during the build.
struct BuildNode {
  bool leaf;
};
struct BuildInner : BuildNode {
  BuildNode* children[2];
  RTCBounds bounds[2];
  int child_count;
};
struct BuildLeaf : BuildNode {
  uint32_t count;
  uint32_t primitives[kBvhMaxLeafSize];
};

void* CreateNode(RTCThreadLocalAllocator alloc, unsigned int child_count, void*) {
  void* memory = rtcThreadLocalAlloc(alloc, sizeof(BuildInner), 16);
  auto* node = new (memory) BuildInner;
  node->leaf = false;
  node->child_count = static_cast<int>(child_count);
  node->children[0] = node->children[1] = nullptr;
  return node;
}

void SetNodeChildren(void* node_ptr, void** children, unsigned int child_count, void*) {
  auto* node = static_cast<BuildInner*>(node_ptr);
  for (unsigned int i = 0; i < child_count; ++i)
    node->children[i] = static_cast<BuildNode*>(children[i]);
}

void SetNodeBounds(void* node_ptr, const RTCBounds** bounds, unsigned int child_count, void*) {
  auto* node = static_cast<BuildInner*>(node_ptr);
  for (unsigned int i = 0; i < child_count; ++i) node->bounds[i] = *bounds[i];
}

void* CreateLeaf(RTCThreadLocalAllocator alloc, const RTCBuildPrimitive* primitives, size_t count,
                 void*) {
  void* memory = rtcThreadLocalAlloc(alloc, sizeof(BuildLeaf), 16);
  auto* leaf = new (memory) BuildLeaf;
  leaf->leaf = true;
  leaf->count = static_cast<uint32_t>(count);
  for (size_t i = 0; i < count; ++i) leaf->primitives[i] = primitives[i].primID;
  return leaf;
}

// The bounds of the parts of primitive p's triangle on either side of the plane
// x[dimension] = position, clipped to p's bounds (p may already be a piece of a split
// triangle): the spatial splits of a high-quality build (Stich, Friedrich and Dietrich,
// "Spatial Splits in Bounding Volume Hierarchies", HPG 2009). Thin tilted slats, whose boxes
// would overlap their neighbours', get tight boxes this way.
void SplitPrimitive(const RTCBuildPrimitive* p, unsigned int dimension, float position,
                    RTCBounds* left, RTCBounds* right, void* user) {
  const auto& geometry = *static_cast<const TraceGeometry*>(user);
  const Vec3f* v = &geometry.vertices[3 * static_cast<size_t>(p->primID)];
  const float inf = std::numeric_limits<float>::infinity();
  float lo[2][3] = {{inf, inf, inf}, {inf, inf, inf}};
  float hi[2][3] = {{-inf, -inf, -inf}, {-inf, -inf, -inf}};
  auto grow = [&](int side, const Vec3f& q) {
    for (int k = 0; k < 3; ++k) {
      lo[side][k] = std::min(lo[side][k], q[k]);
      hi[side][k] = std::max(hi[side][k], q[k]);
    }
  };
  for (int i = 0; i < 3; ++i) {
    const Vec3f& a = v[i];
    const Vec3f& b = v[(i + 1) % 3];
    const float da = a[static_cast<int>(dimension)], db = b[static_cast<int>(dimension)];
    if (da <= position) grow(0, a);
    if (da >= position) grow(1, a);
    // An edge that crosses the plane adds the crossing point to both sides
    if ((da < position && db > position) || (da > position && db < position)) {
      const float f = (position - da) / (db - da);
      Vec3f q = a + (b - a) * f;
      if (dimension == 0) q.x = position;
      if (dimension == 1) q.y = position;
      if (dimension == 2) q.z = position;
      grow(0, q);
      grow(1, q);
    }
  }
  const float box_lo[3] = {p->lower_x, p->lower_y, p->lower_z};
  const float box_hi[3] = {p->upper_x, p->upper_y, p->upper_z};
  RTCBounds* out[2] = {left, right};
  for (int side = 0; side < 2; ++side) {
    float l[3], h[3];
    for (int k = 0; k < 3; ++k) {
      l[k] = std::max(lo[side][k], box_lo[k]);
      h[k] = std::min(hi[side][k], box_hi[k]);
    }
    // The split plane bounds each side exactly
    if (side == 0) h[dimension] = std::min(h[dimension], position);
    if (side == 1) l[dimension] = std::max(l[dimension], position);
    *out[side] = RTCBounds{l[0], l[1], l[2], 0, h[0], h[1], h[2], 0};
  }
}

// Primitive references a high-quality build may make per triangle, spatial splits included.
constexpr size_t kSplitCapacity = 2;

// One Embree device per thread for every build (creating one per build costs more than
// building a small scene's BVH).
RTCDevice BuilderDevice() {
  thread_local std::unique_ptr<RTCDeviceTy, void (*)(RTCDevice)> device(rtcNewDevice("threads=1"),
                                                                        rtcReleaseDevice);
  return device.get();
}

class Flattener {
 public:
  Flattener(const TraceGeometry& geometry, BvhLayout& layout)
      : geometry_(geometry), layout_(layout) {}

  // Emits the leaf's triangles and returns its encoded child reference.
  int32_t Leaf(const BuildLeaf& leaf) {
    const uint32_t first = static_cast<uint32_t>(layout_.triangles.size());
    for (uint32_t k = 0; k < leaf.count; ++k) {
      const uint32_t t = leaf.primitives[k];
      layout_.triangles.push_back({geometry_.vertices[3 * t],
                                   geometry_.vertices[3 * t + 1],
                                   geometry_.vertices[3 * t + 2],
                                   t,
                                   {0, 0}});
    }
    return ~static_cast<int32_t>(first * kBvhMaxLeafSize + (leaf.count - 1));
  }

  // Emits `node` (and its subtree) as node `index`; returns the subtree's depth.
  int Inner(const BuildInner& node, size_t index) {
    int depth = 0;
    for (int i = 0; i < 2; ++i) {
      BvhNode& out = layout_.nodes[index];
      if (i >= node.child_count || node.children[i] == nullptr) {
        SetEmpty(out, i);
        continue;
      }
      const RTCBounds& b = node.bounds[i];
      out.lo[i][0] = b.lower_x, out.lo[i][1] = b.lower_y, out.lo[i][2] = b.lower_z;
      out.hi[i][0] = b.upper_x, out.hi[i][1] = b.upper_y, out.hi[i][2] = b.upper_z;
      const BuildNode* child = node.children[i];
      if (child->leaf) {
        layout_.nodes[index].child[i] = Leaf(*static_cast<const BuildLeaf*>(child));
        depth = std::max(depth, 1);
      } else {
        const size_t child_index = layout_.nodes.size();
        layout_.nodes.push_back({});
        layout_.nodes[index].child[i] = static_cast<int32_t>(child_index);
        depth = std::max(depth, Inner(*static_cast<const BuildInner*>(child), child_index));
      }
    }
    return depth + 1;
  }

  static void SetEmpty(BvhNode& node, int i) {
    for (int k = 0; k < 3; ++k) {
      node.lo[i][k] = std::numeric_limits<float>::infinity();
      node.hi[i][k] = -std::numeric_limits<float>::infinity();
    }
    node.child[i] = kBvhEmptyChild;
  }

 private:
  const TraceGeometry& geometry_;
  BvhLayout& layout_;
};

}  // namespace

absl::StatusOr<BvhLayout> BuildBvh(const TraceGeometry& geometry, BvhQuality quality) {
  std::vector<RTCBuildPrimitive> primitives;
  for (size_t t = 0; t < geometry.TriangleCount(); ++t) {
    if (!HasArea(geometry, t)) continue;  // never hit
    const Vec3f a = geometry.vertices[3 * t], b = geometry.vertices[3 * t + 1],
                c = geometry.vertices[3 * t + 2];
    RTCBuildPrimitive p;
    p.lower_x = std::min({a.x, b.x, c.x});
    p.lower_y = std::min({a.y, b.y, c.y});
    p.lower_z = std::min({a.z, b.z, c.z});
    p.upper_x = std::max({a.x, b.x, c.x});
    p.upper_y = std::max({a.y, b.y, c.y});
    p.upper_z = std::max({a.z, b.z, c.z});
    p.geomID = 0;
    p.primID = static_cast<unsigned int>(t);
    primitives.push_back(p);
  }
  BvhLayout layout;
  layout.nodes.push_back({});
  if (primitives.empty()) {
    Flattener::SetEmpty(layout.nodes[0], 0);
    Flattener::SetEmpty(layout.nodes[0], 1);
    layout.depth = 1;
    return layout;
  }

  RTCDevice device = BuilderDevice();
  if (!device) return absl::InternalError("Embree: cannot create a device for the BVH builder");
  std::unique_ptr<RTCBVHTy, void (*)(RTCBVH)> bvh(rtcNewBVH(device), rtcReleaseBVH);
  RTCBuildArguments args = rtcDefaultBuildArguments();
  const bool high = quality == BvhQuality::kHigh;
  args.buildQuality = high ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;
  args.maxBranchingFactor = 2;
  args.maxDepth = 48;
  args.minLeafSize = 1;
  args.maxLeafSize = kBvhMaxLeafSize;
  args.traversalCost = 1.0f;
  args.intersectionCost = 1.0f;
  args.bvh = bvh.get();
  // Room for the pieces of spatial splits
  const size_t count = primitives.size();
  primitives.resize((high ? kSplitCapacity : 1) * count);
  args.primitives = primitives.data();
  args.primitiveCount = count;
  args.primitiveArrayCapacity = primitives.size();
  args.splitPrimitive = high ? SplitPrimitive : nullptr;
  args.userPtr = const_cast<TraceGeometry*>(&geometry);
  args.createNode = CreateNode;
  args.setNodeChildren = SetNodeChildren;
  args.setNodeBounds = SetNodeBounds;
  args.createLeaf = CreateLeaf;
  const BuildNode* root = static_cast<const BuildNode*>(rtcBuildBVH(&args));
  if (!root) {
    return absl::InternalError(
        absl::StrCat("Embree BVH builder failed (error ", rtcGetDeviceError(device), ")"));
  }

  // Flatten depth-first; a root that is a leaf becomes a node with one child
  Flattener flatten(geometry, layout);
  if (root->leaf) {
    const auto& leaf = *static_cast<const BuildLeaf*>(root);
    BvhNode& node = layout.nodes[0];
    Vec3f lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
             std::numeric_limits<float>::infinity()};
    Vec3f hi = -lo;
    for (size_t i = 0; i < count; ++i) {
      const RTCBuildPrimitive& p = primitives[i];
      lo = {std::min(lo.x, p.lower_x), std::min(lo.y, p.lower_y), std::min(lo.z, p.lower_z)};
      hi = {std::max(hi.x, p.upper_x), std::max(hi.y, p.upper_y), std::max(hi.z, p.upper_z)};
    }
    node.lo[0][0] = lo.x, node.lo[0][1] = lo.y, node.lo[0][2] = lo.z;
    node.hi[0][0] = hi.x, node.hi[0][1] = hi.y, node.hi[0][2] = hi.z;
    node.child[0] = flatten.Leaf(leaf);
    Flattener::SetEmpty(node, 1);
    layout.depth = 2;
  } else {
    layout.depth = flatten.Inner(*static_cast<const BuildInner*>(root), 0);
  }
  return layout;
}

namespace {

// An axis-aligned box, grown point by point.
struct Bounds {
  Vec3f lo{std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
           std::numeric_limits<float>::infinity()};
  Vec3f hi = -lo;
  void Grow(Vec3f p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void Grow(const Bounds& b) {
    Grow(b.lo);
    Grow(b.hi);
  }
};

// Child i of `node`: `child` in `box`.
void SetChild(BvhNode& node, int i, int32_t child, const Bounds& box) {
  node.lo[i][0] = box.lo.x, node.lo[i][1] = box.lo.y, node.lo[i][2] = box.lo.z;
  node.hi[i][0] = box.hi.x, node.hi[i][1] = box.hi.y, node.hi[i][2] = box.hi.z;
  node.child[i] = child;
}

// Where slats [first, last) split into two subtrees: at the start of a blind (`blind_starts`,
// ascending) inside the range closest to its middle, else at the middle.
int SplitOfSlats(int first, int last, const std::vector<int>& blind_starts) {
  const int middle = first + (last - first) / 2;
  int split = middle;
  for (const int start : blind_starts) {
    if (start <= first || start >= last) continue;
    if (split == middle || std::abs(start - middle) < std::abs(split - middle)) split = start;
  }
  return split;
}

// Appends slats [first, last) as a subtree of `layout`, never a node's leaves across two blinds
// (`blind_starts`); returns its node and box and sets *depth to its depth in nodes.
int32_t AppendSlats(const std::vector<Vec3f>& corners, uint32_t first_index, int first, int last,
                    const std::vector<int>& blind_starts, BvhLayout& layout, Bounds* box,
                    int* depth) {
  const int32_t index = static_cast<int32_t>(layout.nodes.size());
  layout.nodes.emplace_back();
  if (last - first == 1) {
    // The slat's faces: the ends and the edges across its width in one leaf (8 triangles),
    // its two sides in the other (4)
    const int k = first;
    for (const auto& [face_begin, face_end, i] : {std::tuple{0, 4, 0}, std::tuple{4, 6, 1}}) {
      const uint32_t leaf_first = static_cast<uint32_t>(layout.triangles.size());
      Bounds leaf;
      for (int f = face_begin; f < face_end; ++f) {
        const Vec3f* c = &corners[8 * static_cast<size_t>(k)];
        const Vec3f a = c[SlatBoxes::FaceCorner(f, 0)], b = c[SlatBoxes::FaceCorner(f, 1)];
        const Vec3f d = c[SlatBoxes::FaceCorner(f, 2)], e = c[SlatBoxes::FaceCorner(f, 3)];
        const uint32_t triangle = first_index + 12 * static_cast<uint32_t>(k) + 2 * f;
        layout.triangles.push_back({a, b, d, triangle, {0, 0}});
        layout.triangles.push_back({a, d, e, triangle + 1, {0, 0}});
        for (const Vec3f p : {a, b, d, e}) leaf.Grow(p);
      }
      const uint32_t count = static_cast<uint32_t>(layout.triangles.size()) - leaf_first;
      SetChild(layout.nodes[index], i,
               ~static_cast<int32_t>(leaf_first * kBvhMaxLeafSize + (count - 1)), leaf);
      box->Grow(leaf);
    }
    *depth = 2;
    return index;
  }
  const int middle = SplitOfSlats(first, last, blind_starts);
  Bounds left, right;
  int left_depth = 0, right_depth = 0;
  const int32_t a =
      AppendSlats(corners, first_index, first, middle, blind_starts, layout, &left, &left_depth);
  const int32_t b =
      AppendSlats(corners, first_index, middle, last, blind_starts, layout, &right, &right_depth);
  SetChild(layout.nodes[index], 0, a, left);
  SetChild(layout.nodes[index], 1, b, right);
  box->Grow(left);
  box->Grow(right);
  *depth = 1 + std::max(left_depth, right_depth);
  return index;
}

}  // namespace

BvhLayout BvhWithSlats(const BvhLayout& room, const std::vector<Vec3f>& slat_corners,
                       uint32_t first_index, const std::vector<int>& slats_per_blind) {
  BvhLayout layout;
  layout.triangles = room.triangles;  // their leaves keep their places
  // Node 0 the new root, then the room's nodes one place on, then the slats'
  layout.nodes.resize(1 + room.nodes.size());
  Bounds room_box;
  for (size_t n = 0; n < room.nodes.size(); ++n) {
    BvhNode node = room.nodes[n];
    for (int i = 0; i < 2; ++i) {
      if (node.child[i] >= 0) ++node.child[i];
    }
    layout.nodes[1 + n] = node;
  }
  for (int i = 0; i < 2 && !room.nodes.empty(); ++i) {
    if (room.nodes[0].child[i] == kBvhEmptyChild) continue;
    room_box.Grow(Vec3f{room.nodes[0].lo[i][0], room.nodes[0].lo[i][1], room.nodes[0].lo[i][2]});
    room_box.Grow(Vec3f{room.nodes[0].hi[i][0], room.nodes[0].hi[i][1], room.nodes[0].hi[i][2]});
  }
  SetChild(layout.nodes[0], 0, 1, room_box);
  const int slats = static_cast<int>(slat_corners.size() / 8);
  if (slats == 0) {
    Flattener::SetEmpty(layout.nodes[0], 1);
    layout.depth = room.depth + 1;
    return layout;
  }
  Bounds slat_box;
  int slat_depth = 0;
  std::vector<int> blind_starts;
  int start = 0;
  for (const int count : slats_per_blind) blind_starts.push_back(start += count);
  const int32_t top = AppendSlats(slat_corners, first_index, 0, slats, blind_starts, layout,
                                  &slat_box, &slat_depth);
  SetChild(layout.nodes[0], 1, top, slat_box);
  layout.depth = 1 + std::max(room.depth, slat_depth);
  return layout;
}

}  // namespace fenestra
