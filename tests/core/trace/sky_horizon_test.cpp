#include "core/trace/sky_horizon.h"

#include <gtest/gtest.h>

#include <algorithm>
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

// A window 2 m x 1.5 m in 4 x 3 parts at `center`, facing `normal` (horizontal, unit).
TraceWindow Window(Vec3f center, Vec3f normal) {
  const Vec3f up{0, 0, 1};
  const Vec3f across = Cross(up, normal);
  return {center, across, up, normal, 2.0f, 1.5f, 4, 3};
}

// Random street canyons: boxes in front of the window, a ground slab below it, and boxes
// behind it. Rays above the bound never meet a surface (checked against Embree for random
// points and outward directions), and the bound spares a good share of the upward rays.
TEST(SkyHorizonTest, RaysAboveTheBoundReachTheSky) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int scene = 0; scene < 4; ++scene) {
    const double azimuth = 2 * 3.14159265358979 * u(rng);
    const Vec3f normal{static_cast<float>(std::cos(azimuth)), static_cast<float>(std::sin(azimuth)),
                       0};
    TriangleMesh mesh;
    AddBox(mesh, {-200, -200, -0.1}, {200, 200, 0}, 0);
    for (int b = 0; b < 8; ++b) {
      // Centred 8 to 60 m in front (or behind), up to 40 m aside, 3 to 40 m tall
      const double ahead = (b < 6 ? 1 : -1) * (8 + 52 * u(rng)), aside = 80 * u(rng) - 40;
      const double cx = ahead * normal.x - aside * normal.y, cy = ahead * normal.y + aside * normal.x;
      const double half = 2 + 10 * u(rng), height = 3 + 37 * u(rng);
      AddBox(mesh, {cx - half, cy - half, 0}, {cx + half, cy + half, height}, 0);
    }
    absl::StatusOr<TraceGeometry> geometry = PrepareTraceGeometry(mesh, kMaterials);
    ASSERT_TRUE(geometry.ok()) << geometry.status();
    const TraceWindow window = Window(geometry->ToLocal(Vec3d{0, 0, 7.65}), normal);
    absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*geometry);
    ASSERT_TRUE(embree.ok());
    const EmbreeIntersector intersector = (*embree)->Intersector();
    const std::vector<float> horizon = SkyHorizon(*geometry, window);
    ASSERT_EQ(horizon.size(), 12u * kHorizonAzimuthBins);
    int upward = 0, spared = 0;
    for (int k = 0; k < 200'000; ++k) {
      const float u0 = static_cast<float>(u(rng)), u1 = static_cast<float>(u(rng));
      const Vec3f point = window.Point(u0, u1);
      // A uniform outward direction
      const double z = 2 * u(rng) - 1, phi = 2 * 3.14159265358979 * u(rng);
      const double r = std::sqrt(1 - z * z);
      Vec3f d{static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)),
              static_cast<float>(z)};
      if (Dot(d, normal) < 0) d = d - normal * (2 * Dot(d, normal));
      const OutdoorView<EmbreeIntersector> view{intersector, {0, 0, 0}, horizon.data()};
      const OutdoorView<EmbreeIntersector> traced{intersector, {0, 0, 0}, nullptr};
      const int part = window.PartOf(u0, u1);
      const bool bound = view.Escapes(point, normal, d, part);
      const bool exact = traced.Escapes(point, normal, d, part);
      if (d.z > 0) ++upward;
      if (bound && !exact) {
        ADD_FAILURE() << "scene " << scene << ": a ray above the bound meets a surface";
        return;
      }
      // Where the bound spared the traversal (it held and said sky)
      int bin = static_cast<int>((std::atan2(d.y, d.x) + 3.14159265358979) * kHorizonAzimuthBins /
                                 (2 * 3.14159265358979));
      bin = std::clamp(bin, 0, kHorizonAzimuthBins - 1);
      if (d.z > horizon[part * kHorizonAzimuthBins + bin]) ++spared;
    }
    std::printf("scene %d: the bound spares %.0f%% of the upward rays\n", scene,
                100.0 * spared / upward);
    EXPECT_GT(spared, upward / 5);
  }
}

}  // namespace
}  // namespace fenestra
