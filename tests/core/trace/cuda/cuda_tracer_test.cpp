// The GPU's BVH traversal against the same traversal on the CPU. Skips without a CUDA
// device.
#include "core/trace/cuda/cuda_tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/geometry/scene.h"
#include "core/trace/bvh.h"
#include "core/trace/bvh_intersector.h"
#include "core/trace/trace_geometry.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

TEST(CudaTracerTest, ClosestHitsMatchTheCpu) {
  absl::StatusOr<std::unique_ptr<CudaTracer>> created = CudaTracer::Create(0);
  if (!created.ok()) GTEST_SKIP() << created.status();
  std::unique_ptr<CudaTracer> tracer = *std::move(created);
  const Scene scene = LoadExample("city_office");
  const BlindDesign design = *DesignWithOverrides(scene, {{"alpha", 0.6}, {"spacing", 0.05}});
  absl::StatusOr<TraceGeometry> geometry =
      PrepareTraceGeometry(AssembleMesh(scene, design), scene.materials);
  ASSERT_TRUE(geometry.ok());
  absl::StatusOr<BvhLayout> bvh = BuildBvh(*geometry);
  ASSERT_TRUE(bvh.ok());
  ASSERT_EQ(
      tracer->SetScene(*bvh, geometry->triangle_material.data(), geometry->triangle_material.size(),
                       geometry->materials.data(), geometry->materials.size()),
      absl::OkStatus());

  // Rays from the room and the street, directions uniform on the sphere
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<Vec3f> origins, directions;
  while (origins.size() < 100'000) {
    Vec3f d{u(rng), u(rng), u(rng)};
    if (Dot(d, d) > 1 || Dot(d, d) < 1e-4f) continue;
    directions.push_back(Normalize(d));
    origins.push_back(
        geometry->ToLocal(Vec3d{1.4 * u(rng), -3.0 + 6.0 * u(rng), 7.5 + 1.4 * u(rng)}));
  }
  std::vector<float> gpu(origins.size()), same(origins.size());
  double seconds = 0;
  ASSERT_EQ(tracer->IntersectRays(origins.data(), directions.data(), origins.size(), false,
                                  gpu.data(), &seconds),
            absl::OkStatus());
  ASSERT_EQ(tracer->IntersectRays(origins.data(), directions.data(), origins.size(), true,
                                  same.data(), &seconds),
            absl::OkStatus());
  const BvhIntersector cpu{bvh->nodes.data(), bvh->triangles.data()};
  int hits = 0, disagreements = 0;
  for (size_t i = 0; i < origins.size(); ++i) {
    SurfaceHit hit;
    const float expected = cpu.Intersect(origins[i], directions[i], &hit)
                               ? Length(hit.position - origins[i])
                               : INFINITY;
    hits += std::isfinite(expected);
    const bool agree = std::isinf(expected)
                           ? std::isinf(gpu[i])
                           : std::abs(gpu[i] - expected) <= 1e-5f * std::max(1.0f, expected);
    disagreements += !agree;
    // Every lane of a warp traced the warp's first ray
    const size_t first = i & ~size_t{31};
    EXPECT_TRUE(same[i] == gpu[first] || (std::isinf(same[i]) && std::isinf(gpu[first])))
        << "ray " << i;
  }
  EXPECT_GT(hits, 50'000);
  // Only a ray through a shared edge may differ (the GPU contracts multiply-adds)
  EXPECT_LE(disagreements, 2);
}

}  // namespace
}  // namespace fenestra
