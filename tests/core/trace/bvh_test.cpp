#include "core/trace/bvh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/geometry/scene.h"
#include "core/trace/brute_force_intersector.h"
#include "core/trace/bvh_intersector.h"
#include "core/trace/trace_geometry.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

TraceGeometry Load(const std::string& name) {
  const Scene scene = LoadExample(name);
  absl::StatusOr<TraceGeometry> geometry =
      PrepareTraceGeometry(AssembleMesh(scene, DefaultDesign(scene)), scene.materials);
  EXPECT_TRUE(geometry.ok()) << geometry.status();
  return *geometry;
}

// Every triangle sits in at least one leaf, and the boxes of the leaves holding it cover
// it: a triangle split spatially (a thin tilted slat) may be in several leaves, each box
// holding a piece of it.
void CheckLeafBoxes(BvhQuality quality) {
  const TraceGeometry geometry = Load("city_office");
  absl::StatusOr<BvhLayout> bvh = BuildBvh(geometry, quality);
  ASSERT_TRUE(bvh.ok()) << bvh.status();
  std::vector<std::vector<std::pair<Vec3f, Vec3f>>> boxes(geometry.TriangleCount());
  for (const BvhNode& node : bvh->nodes) {
    for (int i = 0; i < 2; ++i) {
      if (node.child[i] >= 0 || node.child[i] == kBvhEmptyChild) continue;
      const int code = ~node.child[i];
      for (int t = code / kBvhMaxLeafSize; t <= code / kBvhMaxLeafSize + code % kBvhMaxLeafSize;
           ++t) {
        boxes[bvh->triangles[t].index].push_back(
            {Vec3f{node.lo[i][0], node.lo[i][1], node.lo[i][2]},
             Vec3f{node.hi[i][0], node.hi[i][1], node.hi[i][2]}});
      }
    }
  }
  // Points spread over each triangle, its corners included, each inside one of its boxes
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  size_t split = 0;
  for (size_t t = 0; t < geometry.TriangleCount(); ++t) {
    if (!HasArea(geometry, t)) continue;
    ASSERT_FALSE(boxes[t].empty()) << "triangle " << t << " is in no leaf";
    split += boxes[t].size() > 1;
    const Vec3f* v = &geometry.vertices[3 * t];
    for (int k = 0; k < 64; ++k) {
      float b1 = k < 3 ? (k == 1) : u(rng), b2 = k < 3 ? (k == 2) : u(rng);
      if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
      const Vec3f p = v[0] + (v[1] - v[0]) * b1 + (v[2] - v[0]) * b2;
      bool inside = false;
      for (const auto& [lo, hi] : boxes[t]) {
        const float margin = 1e-5f * (1 + std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}));
        inside |= p.x >= lo.x - margin && p.y >= lo.y - margin && p.z >= lo.z - margin &&
                  p.x <= hi.x + margin && p.y <= hi.y + margin && p.z <= hi.z + margin;
      }
      ASSERT_TRUE(inside) << "triangle " << t << " point " << k << " is in none of its boxes";
    }
  }
  EXPECT_LE(bvh->depth, 48);
  std::printf("%zu of %zu triangles split over several leaves\n", split, geometry.TriangleCount());
  if (quality == BvhQuality::kMedium) {
    EXPECT_EQ(split, 0u);
  }
}

TEST(BvhTest, LeafBoxesCoverEveryTriangle) {
  CheckLeafBoxes(BvhQuality::kHigh);
  CheckLeafBoxes(BvhQuality::kMedium);
}

// The BVH traversal finds the same closest hits as testing every triangle.
void CompareWithBruteForce(const std::string& name, BvhQuality quality) {
  const TraceGeometry geometry = Load(name);
  absl::StatusOr<BvhLayout> bvh = BuildBvh(geometry, quality);
  ASSERT_TRUE(bvh.ok()) << bvh.status();
  const BvhIntersector fast{bvh->nodes.data(), bvh->triangles.data()};
  const BruteForceIntersector slow{geometry.vertices.data(),
                                   static_cast<uint32_t>(geometry.TriangleCount())};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(-1, 1);
  int hits = 0, disagreements = 0;
  const int rays = 50000;
  for (int i = 0; i < rays; ++i) {
    // Origins inside the room and outdoors, directions uniform on the sphere
    const Vec3f origin =
        geometry.ToLocal(Vec3d{1.4 * u(rng), -3.0 + 3.1 * u(rng), 1.5 + 1.4 * u(rng)} +
                         Vec3d{0, 0, name == "city_office" ? 6.0 : 0.0});
    Vec3f d{u(rng), u(rng), u(rng)};
    if (Dot(d, d) > 1 || Dot(d, d) < 1e-4f) continue;
    d = Normalize(d);
    SurfaceHit a, b;
    const bool ha = fast.Intersect(origin, d, &a);
    const bool hb = slow.Intersect(origin, d, &b);
    if (ha) ++hits;
    if (ha != hb) {
      ++disagreements;
      continue;
    }
    if (!ha) continue;
    const float ta = Length(a.position - origin), tb = Length(b.position - origin);
    if (std::abs(ta - tb) > 1e-4f * std::max(1.0f, tb)) ++disagreements;
  }
  EXPECT_GT(hits, rays / 4);
  // Only rays through shared edges may differ (Möller-Trumbore is not watertight)
  EXPECT_LE(disagreements, 2) << name;
}

TEST(BvhTest, AgreesWithBruteForceOnTheLightwell) {
  CompareWithBruteForce("lightwell", BvhQuality::kHigh);
  CompareWithBruteForce("lightwell", BvhQuality::kMedium);
}
TEST(BvhTest, AgreesWithBruteForceOnTheCityOffice) {
  CompareWithBruteForce("city_office", BvhQuality::kHigh);
  CompareWithBruteForce("city_office", BvhQuality::kMedium);
}

// Queries the BVH and every triangle for each ray a path asks for, and counts where they
// differ.
struct CheckedIntersector {
  const BvhIntersector* bvh;
  const BruteForceIntersector* every_triangle;
  int* rays;
  int* disagreements;
  bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const {
    SurfaceHit expected{};
    const bool found = bvh->Intersect(origin, direction, hit);
    const bool should = every_triangle->Intersect(origin, direction, &expected);
    const float t = Length(hit->position - origin), t_expected = Length(expected.position - origin);
    ++*rays;
    *disagreements +=
        found != should || (found && std::abs(t - t_expected) > 1e-4f * std::max(1.0f, t_expected));
    return found;
  }
  bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    return bvh->Occluded(origin, direction, distance);
  }
};

struct NoSink {
  void Add(int, double) {}
  void EndPath() {}
};

// The rays paths trace (from points just off surfaces, into corners, 30 bounces): the BVH
// finds the same closest hits as testing every triangle.
TEST(BvhTest, AgreesWithBruteForceOnPathRays) {
  for (const std::string name : {"lightwell", "city_office"}) {
    const Scene scene = LoadExample(name);
    const TraceGeometry geometry = Load(name);
    absl::StatusOr<BvhLayout> bvh = BuildBvh(geometry);
    ASSERT_TRUE(bvh.ok());
    const BvhIntersector fast{bvh->nodes.data(), bvh->triangles.data()};
    const BruteForceIntersector slow{geometry.vertices.data(),
                                     static_cast<uint32_t>(geometry.TriangleCount())};
    int rays = 0, disagreements = 0;
    const CheckedIntersector checked{&fast, &slow, &rays, &disagreements};
    const PathSettings settings{30, true, 0.25f, 1000};
    NoSink sink;
    for (uint32_t s = 0; s < scene.sensors.size(); ++s) {
      const Vec3d n = Normalize(scene.sensors[s].direction);
      OneStageMode<NoSink> mode{geometry.ToLocal(scene.sensors[s].position),
                                Vec3f{float(n.x), float(n.y), float(n.z)}, &sink};
      for (uint64_t p = 0; p < 10'000; ++p) {
        TracePath<CheckedIntersector, OneStageMode<NoSink>, 0>(checked, geometry.Surfaces(),
                                                               settings, PathRandom(1, s, p), mode);
      }
    }
    EXPECT_GT(rays, 100'000) << name;
    EXPECT_LE(disagreements, 2) << name << ": " << rays << " rays";
  }
}

// Rays aimed exactly at the diagonal shared by a quad's two triangles always hit.
TEST(BvhTest, SharedEdgesAreWatertight) {
  TraceGeometry geometry;
  const Vec3f a{0, 0, 0}, b{1, 0, 0}, c{1, 1, 0}, d{0, 1, 0};
  geometry.vertices = {a, b, c, a, c, d};
  geometry.triangle_material = {0, 0};
  geometry.materials = {{0.5f, -1.0f}};
  absl::StatusOr<BvhLayout> bvh = BuildBvh(geometry);
  ASSERT_TRUE(bvh.ok());
  const BvhIntersector fast{bvh->nodes.data(), bvh->triangles.data()};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (int i = 0; i < 20000; ++i) {
    const float s = u(rng);
    const Vec3f target{s, s, 0};
    const Vec3f origin{u(rng) * 4 - 2, u(rng) * 4 - 2, 0.5f + u(rng)};
    SurfaceHit hit;
    ASSERT_TRUE(fast.Intersect(origin, Normalize(target - origin), &hit))
        << "ray through (" << s << ", " << s << ") slipped through the diagonal";
  }
}

TEST(BvhTest, EmptyAndSingleTriangleScenes) {
  TraceGeometry geometry;
  geometry.materials = {{0.5f, -1.0f}};
  absl::StatusOr<BvhLayout> empty = BuildBvh(geometry);
  ASSERT_TRUE(empty.ok());
  SurfaceHit hit;
  EXPECT_FALSE((BvhIntersector{empty->nodes.data(), empty->triangles.data()}.Intersect(
      {0, 0, 0}, {0, 0, 1}, &hit)));

  geometry.vertices = {{-1, -1, 1}, {1, -1, 1}, {0, 1, 1}};
  geometry.triangle_material = {0};
  absl::StatusOr<BvhLayout> one = BuildBvh(geometry);
  ASSERT_TRUE(one.ok());
  const BvhIntersector fast{one->nodes.data(), one->triangles.data()};
  ASSERT_TRUE(fast.Intersect({0, 0, 0}, {0, 0, 1}, &hit));
  EXPECT_FLOAT_EQ(hit.position.z, 1);
  EXPECT_EQ(hit.triangle, 0u);
  EXPECT_FALSE(fast.Intersect({0, 0, 0}, {0, 0, -1}, &hit));
  EXPECT_FALSE(fast.Intersect({0, 0, 2}, {0, 0, 1}, &hit));
}

}  // namespace
}  // namespace fenestra
