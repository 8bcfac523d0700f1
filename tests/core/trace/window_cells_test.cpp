#include "core/trace/window_cells.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "core/trace/embree_scene.h"
#include "core/trace/trace_geometry.h"
#include "tests/core/trace/test_meshes.h"

namespace fenestra {
namespace {

using testing_meshes::AddBox;

const std::vector<Material> kMaterials = {{"grey", 0.5, -1}};

// Random street canyons in front of a window 2 m x 1.5 m in 4 x 3 parts, facing a random
// horizontal direction (and boxes behind it, and a ground slab): from every window cell
// said to meet a surface, random rays (a uniform point of the part, a direction uniform in
// the cell) all meet one, checked against Embree; and most cells that look at the street
// or the buildings across it qualify.
TEST(WindowCellsTest, EveryViewFromAMetCellMeetsASurface) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  const HemisphereBasis basis = Beckers288();
  for (int scene = 0; scene < 4; ++scene) {
    const double azimuth = 2 * 3.14159265358979 * u(rng);
    const Vec3f normal{static_cast<float>(std::cos(azimuth)), static_cast<float>(std::sin(azimuth)),
                       0};
    TriangleMesh mesh;
    AddBox(mesh, {-200, -200, -0.1}, {200, 200, 0}, 0);
    for (int b = 0; b < 8; ++b) {
      // Centred 8 to 60 m in front (or behind), up to 40 m aside, 3 to 40 m tall
      const double ahead = (b < 6 ? 1 : -1) * (8 + 52 * u(rng)), aside = 80 * u(rng) - 40;
      const double cx = ahead * normal.x - aside * normal.y,
                   cy = ahead * normal.y + aside * normal.x;
      const double half = 2 + 10 * u(rng), height = 3 + 37 * u(rng);
      AddBox(mesh, {cx - half, cy - half, 0}, {cx + half, cy + half, height}, 0);
    }
    absl::StatusOr<TraceGeometry> geometry = PrepareTraceGeometry(mesh, kMaterials);
    ASSERT_TRUE(geometry.ok()) << geometry.status();
    const Vec3f up{0, 0, 1};
    const TraceWindow window{
        geometry->ToLocal(Vec3d{0, 0, 7.65}), Cross(up, normal), up, normal, 2.0f, 1.5f, 4, 3};
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*geometry);
    ASSERT_TRUE(embree.ok());
    const EmbreeIntersector intersector = (*embree)->Intersector();
    const std::vector<uint8_t> met = WindowCellsMeetingSurfaces(*geometry, window, basis);
    ASSERT_EQ(met.size(), 12u * 288u);
    int flagged = 0, downward = 0, downward_flagged = 0;
    for (size_t cell = 0; cell < met.size(); ++cell) {
      const int part = static_cast<int>(cell / 288), direction = static_cast<int>(cell % 288);
      const bool down = window.ToWorld(SampleBasisCell(basis, direction, 0.5f, 0.5f)).z < -0.1f;
      downward += down;
      if (!met[cell]) continue;
      ++flagged;
      downward_flagged += down;
      for (int k = 0; k < 200; ++k) {
        const Vec3f point =
            window.PartPoint(part, static_cast<float>(u(rng)), static_cast<float>(u(rng)));
        const Vec3f d = window.ToWorld(SampleBasisCell(basis, direction, static_cast<float>(u(rng)),
                                                       static_cast<float>(u(rng))));
        ASSERT_TRUE(intersector.Occluded(OffsetRayOrigin(point, normal), d, INFINITY))
            << "scene " << scene << ", window cell " << cell << ": a view reaches the sky";
      }
    }
    std::printf("scene %d: %d of %zu window cells meet a surface (%d of %d looking down)\n", scene,
                flagged, met.size(), downward_flagged, downward);
    EXPECT_GT(downward_flagged, downward * 8 / 10);
  }
}

}  // namespace
}  // namespace fenestra
