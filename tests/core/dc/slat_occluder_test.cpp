#include "core/trace/slat_occluder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>

#include "core/dc/indoor_replay.h"
#include "core/dc/two_stage.h"
#include "core/trace/embree_scene.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// The slats' occlusion from their layout is the triangle mesh's: for segments from room
// points towards the window (the replays' shadow rays) and every other way, across designs
// at the ends of the city office's ranges (slats touching, in the window plane,
// perpendicular to it, the thinnest and widest), horizontal and vertical, the answers agree
// but for segments that graze an edge within float rounding.
TEST(SlatOccluderTest, AgreesWithTheTriangles) {
  Scene scene = LoadExample("city_office");
  for (const bool vertical : {false, true})
    for (const std::map<std::string, double>& values :
         std::vector<std::map<std::string, double>>{{{"alpha", 0.0}, {"spacing", 0.0}},
                                                    {{"alpha", 0.8}, {"width", 0.05}},
                                                    {{"alpha", 1.5707963}, {"spacing", 0.1}},
                                                    {{"alpha", 0.3}, {"thickness", 0.02}},
                                                    {{"alpha", 1.2}, {"width", 0.15}}}) {
      scene.blind->vertical = vertical;  // slats stacked across the window instead
      absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, values);
      ASSERT_TRUE(design.ok()) << design.status();
      TriangleMesh blind;
      GenerateBlind(scene.window, *scene.blind, *design, 0, blind);
      absl::StatusOr<TraceGeometry> geometry = PrepareTraceGeometry(blind, scene.materials);
      ASSERT_TRUE(geometry.ok()) << geometry.status();
      absl::StatusOr<std::unique_ptr<EmbreeScene>> triangles = EmbreeScene::Build(*geometry);
      ASSERT_TRUE(triangles.ok()) << triangles.status();
      const SlatOccluder slats = LocalSlatsOfBlind(*geometry, scene, *design);
      // Segments between points of a box around the window, inside the room and outside
      const Vec3f middle = geometry->ToLocal(scene.window.center - 0.2 * scene.window.normal);
      std::mt19937 random(7);
      std::uniform_real_distribution<float> u(-1.5f, 1.5f);
      int blocked = 0, differ = 0;
      const int segments = 200'000;
      for (int i = 0; i < segments; ++i) {
        const Vec3f a = middle + Vec3f{u(random), u(random), u(random)};
        const Vec3f b = middle + Vec3f{u(random), u(random), u(random)};
        const float distance = Length(b - a);
        const Vec3f direction = (b - a) / distance;
        const bool by_mesh = (*triangles)->Intersector().Occluded(a, direction, distance);
        blocked += by_mesh ? 1 : 0;
        differ += by_mesh != slats.Occluded(a, direction, distance) ? 1 : 0;
      }
      std::printf("%s, alpha %.2f: %d of %d segments blocked, %d answers differ\n",
                  vertical ? "vertical" : "horizontal", design->tilt_rad, blocked, segments,
                  differ);
      EXPECT_GT(blocked, segments / 50);
      EXPECT_LE(differ, segments / 100'000);
    }
}

}  // namespace
}  // namespace fenestra
