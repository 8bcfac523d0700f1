#include "core/trace/embree_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/trace/brute_force_intersector.h"
#include "core/trace/philox.h"
#include "core/trace/sampling.h"
#include "core/trace/trace_geometry.h"
#include "tests/core/trace/test_meshes.h"

namespace fenestra {
namespace {

using testing_meshes::AddBox;
using testing_meshes::Translated;

const std::vector<Material> kMaterials = {{"grey", 0.5, -1}};

TEST(TraceGeometryTest, TranslatesToTheBoxCentre) {
  TriangleMesh mesh;
  AddBox(mesh, {1e4, 1e4, 0}, {1e4 + 3, 1e4 + 6, 3}, 0);
  const absl::StatusOr<TraceGeometry> geometry = PrepareTraceGeometry(mesh, kMaterials);
  ASSERT_TRUE(geometry.ok()) << geometry.status();
  EXPECT_DOUBLE_EQ(geometry->origin.x, 1e4 + 1.5);
  EXPECT_DOUBLE_EQ(geometry->origin.y, 1e4 + 3);
  EXPECT_DOUBLE_EQ(geometry->origin.z, 1.5);
  EXPECT_EQ(geometry->vertices[0].x, -1.5f);
  EXPECT_EQ(geometry->degenerate_triangles, 0u);
}

TEST(TraceGeometryTest, RejectsBadInput) {
  TriangleMesh mesh;
  AddBox(mesh, {0, 0, 0}, {1, 1, 1}, 0);
  EXPECT_FALSE(PrepareTraceGeometry(mesh, {{"white", 1.0, -1}}).ok());
  EXPECT_FALSE(PrepareTraceGeometry(mesh, {{"glass", 0.2, 0.9}}).ok());
  EXPECT_FALSE(PrepareTraceGeometry(mesh, {}).ok());
  TriangleMesh bad = mesh;
  bad.vertices[4].y = std::nan("");
  EXPECT_FALSE(PrepareTraceGeometry(bad, kMaterials).ok());
}

TEST(EmbreeSceneTest, AgreesWithBruteForce) {
  TriangleMesh mesh;
  AddBox(mesh, {-1.5, -6.25, 0}, {1.5, 0, 3}, 0);
  AddBox(mesh, {-0.5, -2, 0.5}, {0.5, -1, 0.8}, 0);  // a table inside
  const TraceGeometry geometry = *PrepareTraceGeometry(mesh, kMaterials);
  const auto scene = EmbreeScene::Build(geometry);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const EmbreeIntersector embree = (*scene)->Intersector();
  const BruteForceIntersector brute{geometry.vertices.data(),
                                    static_cast<uint32_t>(geometry.TriangleCount())};
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const Uniform4 u = PathRandom(11, 0, i).Draw(0, 0);
    const Vec3f origin = geometry.ToLocal({-1.4 + 2.8 * u.u[2], -6.2 + 6.1 * u.u[3], 0.3});
    const Vec3f direction =
        SampleCosineHemisphere(Normalize(Vec3f{0.2f, 0.1f, 1.0f}), u.u[0], u.u[1]);
    SurfaceHit a, b;
    ASSERT_TRUE(embree.Intersect(origin, direction, &a));
    ASSERT_TRUE(brute.Intersect(origin, direction, &b));
    EXPECT_LT(Length(a.position - b.position), 1e-4f);
    const Vec3f na = Normalize(a.normal), nb = Normalize(b.normal);
    EXPECT_GT(std::fabs(Dot(na, nb)), 0.9999f);
    ++hits;
  }
  EXPECT_EQ(hits, 20000);
}

TEST(EmbreeSceneTest, LeavesDegenerateTrianglesOut) {
  TriangleMesh mesh;
  AddBox(mesh, {0, 0, 0}, {1, 1, 1}, 0);
  mesh.Add({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, 0, Side::kIndoor, 0);  // a point
  mesh.Add({0, 0, 0.5}, {1, 1, 0.5}, {2, 2, 0.5}, 0, Side::kIndoor, 0);              // a line
  const TraceGeometry geometry = *PrepareTraceGeometry(mesh, kMaterials);
  EXPECT_EQ(geometry.degenerate_triangles, 2u);
  const auto scene = EmbreeScene::Build(geometry);
  ASSERT_TRUE(scene.ok());
  EXPECT_EQ((*scene)->PrimitiveCount(), 12u);
  // A ray along the line's plane and through the point hits the box, not them
  SurfaceHit hit;
  ASSERT_TRUE((*scene)->Intersector().Intersect(geometry.ToLocal({0.1, 0.1, 0.5}),
                                                Normalize(Vec3f{1, 1, 0}), &hit));
  EXPECT_LT(hit.triangle, 12u);
}

TEST(EmbreeSceneTest, EmptySceneHasNoHits) {
  const TraceGeometry geometry = *PrepareTraceGeometry(TriangleMesh{}, kMaterials);
  const auto scene = EmbreeScene::Build(geometry);
  ASSERT_TRUE(scene.ok());
  SurfaceHit hit;
  EXPECT_FALSE((*scene)->Intersector().Intersect({0, 0, 0}, {0, 0, 1}, &hit));
}

TEST(EmbreeSceneTest, FarFromTheOriginHitsTheSamePoints) {
  TriangleMesh near_mesh;
  AddBox(near_mesh, {-1.5, -6.25, 0}, {1.5, 0, 3}, 0);
  const TriangleMesh far_mesh = Translated(near_mesh, {1e4, 1e4, 0});
  const TraceGeometry near_geometry = *PrepareTraceGeometry(near_mesh, kMaterials);
  const TraceGeometry far_geometry = *PrepareTraceGeometry(far_mesh, kMaterials);
  // The local frames coincide exactly
  for (size_t i = 0; i < near_geometry.vertices.size(); ++i) {
    EXPECT_EQ(near_geometry.vertices[i].x, far_geometry.vertices[i].x);
    EXPECT_EQ(near_geometry.vertices[i].y, far_geometry.vertices[i].y);
    EXPECT_EQ(near_geometry.vertices[i].z, far_geometry.vertices[i].z);
  }
  EXPECT_EQ(near_geometry.ToLocal({0, -1, 0.7}).y, far_geometry.ToLocal({1e4, 1e4 - 1, 0.7}).y);
}

}  // namespace
}  // namespace fenestra
