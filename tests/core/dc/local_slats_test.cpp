#include "core/trace/local_slats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/dc/indoor_replay.h"
#include "core/dc/two_stage.h"
#include "core/trace/bvh.h"
#include "core/trace/bvh_intersector.h"
#include "core/trace/embree_scene.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// The designs the tests take: at the ends of the city office's ranges (slats touching, in
// the window plane, perpendicular to it, the thinnest and widest).
std::vector<std::map<std::string, double>> EdgeDesigns() {
  return {{{"alpha", 0.0}, {"spacing", 0.0}},
          {{"alpha", 0.8}, {"width", 0.05}},
          {{"alpha", 1.5707963}, {"spacing", 0.1}},
          {{"alpha", 0.3}, {"thickness", 0.02}},
          {{"alpha", 1.2}, {"width", 0.15}}};
}

// Random offsets within a 3 m cube, and points that far from `middle` (by the window), from
// a fixed seed.
class AroundWindow {
 public:
  AroundWindow(Vec3f middle, unsigned seed) : middle_(middle), random_(seed) {}
  Vec3f Offset() { return Vec3f{u_(random_), u_(random_), u_(random_)}; }
  Vec3f Point() { return middle_ + Offset(); }

 private:
  Vec3f middle_;
  std::mt19937 random_;
  std::uniform_real_distribution<float> u_{-1.5f, 1.5f};
};

// The slats' occlusion from their layout is the triangle mesh's: for segments from room
// points towards the window (the replays' shadow rays) and every other way, across designs
// at the ends of the city office's ranges (slats touching, in the window plane,
// perpendicular to it, the thinnest and widest), horizontal and vertical, the answers agree
// but for segments that graze an edge within float rounding. So do the answers the replays
// get for segments that cross the envelope's depth, from their line across it.
TEST(LocalSlatsTest, AgreesWithTheTriangles) {
  Scene scene = LoadExample("city_office");
  for (const bool vertical : {false, true})
    for (const std::map<std::string, double>& values : EdgeDesigns()) {
      scene.blind()->vertical = vertical;  // slats stacked across the window instead
      absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, values);
      ASSERT_TRUE(design.ok()) << design.status();
      TriangleMesh blind;
      GenerateBlind(scene.window(), *scene.blind(), *design, 0, blind);
      absl::StatusOr<TraceGeometry> geometry = PrepareTraceGeometry(blind, scene.materials);
      ASSERT_TRUE(geometry.ok()) << geometry.status();
      absl::StatusOr<std::unique_ptr<EmbreeScene>> triangles = EmbreeScene::Build(*geometry);
      ASSERT_TRUE(triangles.ok()) << triangles.status();
      const LocalSlats slats = LocalSlatsOfBlind(*geometry, scene, *design);
      // The replays' frame: the envelope of every design's slats, and this design's shift
      const LocalEnvelope e = LocalEnvelopeOfBlind(*geometry, scene);
      const Vec3f shift = slats.ShiftFrom(e.center);
      // Segments between points of a box around the window, inside the room and outside
      AroundWindow around(geometry->ToLocal(scene.window().center - 0.2 * scene.window().normal),
                          7);
      int blocked = 0, differ = 0, crossing_count = 0, crossings_differ = 0;
      const int segments = 200'000;
      for (int i = 0; i < segments; ++i) {
        const Vec3f a = around.Point();
        const Vec3f b = around.Point();
        const float distance = Length(b - a);
        const Vec3f direction = (b - a) / distance;
        const bool by_mesh = (*triangles)->Intersector().Occluded(a, direction, distance);
        blocked += by_mesh ? 1 : 0;
        differ += by_mesh != slats.Occluded(a, direction, distance) ? 1 : 0;
        // As the replays test them: by the line of a segment that crosses the envelope
        ReplayCrossing crossing;
        if (CrossingOf(e, ReplayConnection{a, direction, distance, 0, 0.0}, &crossing)) {
          ++crossing_count;
          crossings_differ += by_mesh == Clear(slats, shift, e, crossing) ? 1 : 0;
        }
      }
      std::printf(
          "%s, alpha %.2f: %d of %d segments blocked, %d answers differ; %d cross the "
          "envelope, %d of those differ by their line\n",
          vertical ? "vertical" : "horizontal", design->tilt_rad, blocked, segments, differ,
          crossing_count, crossings_differ);
      EXPECT_GT(blocked, segments / 50);
      EXPECT_GT(crossing_count, segments / 10);
      EXPECT_LE(differ, segments / 100'000);
      EXPECT_LE(crossings_differ, segments / 100'000);
    }
}

// The room's BVH with the slats put beside it (BvhWithSlats) holds the mesh's triangles: for
// rays from points around the window every way, across the same designs, horizontal and
// vertical, its closest hits are those of a BVH built over the room with the blind's mesh
// (the same triangle, at the same point, or where touching slats share a face, either
// slat's at the same distance) but for rays through an edge shared by two triangles, which
// either may take. Here for rays from points around `window` of `scene` at
// `design`.
void ExpectHitsOfTheMesh(const Scene& scene, const BlindDesign& design, const Window& window,
                         const char* what) {
  absl::StatusOr<TraceGeometry> room =
      PrepareTraceGeometry(SelectSide(scene.fixed, Side::kIndoor), scene.materials);
  ASSERT_TRUE(room.ok()) << room.status();
  absl::StatusOr<TraceGeometry> full = PrepareTraceGeometry(
      SelectSide(AssembleMesh(scene, design), Side::kIndoor), scene.materials, &room->origin);
  ASSERT_TRUE(full.ok()) << full.status();
  absl::StatusOr<BvhLayout> room_bvh = BuildBvh(*room, BvhQuality::kHigh);
  absl::StatusOr<BvhLayout> built = BuildBvh(*full, BvhQuality::kMedium);
  ASSERT_TRUE(room_bvh.ok() && built.ok());
  std::vector<int> slats_per_blind;
  const std::vector<Vec3f> corners = LocalSlatCorners(*room, scene, design, &slats_per_blind);
  const BvhLayout beside = BvhWithSlats(
      *room_bvh, corners, static_cast<uint32_t>(room->TriangleCount()), slats_per_blind);
  ASSERT_EQ(beside.triangles.size(), built->triangles.size());
  const BvhIntersector a{built->nodes.data(), built->triangles.data()};
  const BvhIntersector b{beside.nodes.data(), beside.triangles.data()};
  AroundWindow around(room->ToLocal(window.center - 0.3 * window.normal), 11);
  int on_slats = 0, differ = 0;
  const int rays = 100'000;
  for (int i = 0; i < rays; ++i) {
    const Vec3f origin = around.Point();
    const Vec3f toward = around.Offset();
    const Vec3f direction = toward / Length(toward);
    SurfaceHit by_build, by_beside;
    const bool hit_a = a.Intersect(origin, direction, &by_build);
    const bool hit_b = b.Intersect(origin, direction, &by_beside);
    on_slats += hit_a && by_build.triangle >= room->TriangleCount() ? 1 : 0;
    // Touching slats (spacing 0) share a face: a hit there may be on either slat's triangle
    const auto on_slat = [&](const SurfaceHit& h) { return h.triangle >= room->TriangleCount(); };
    const bool tie =
        on_slat(by_build) && on_slat(by_beside) &&
        std::abs(Length(by_build.position - origin) - Length(by_beside.position - origin)) < 1e-6f;
    const bool same = hit_a == hit_b && (!hit_a || tie ||
                                         (by_build.triangle == by_beside.triangle &&
                                          Length(by_build.position - by_beside.position) == 0.0f));
    const bool occluded_same =
        a.Occluded(origin, direction, 1.0f) == b.Occluded(origin, direction, 1.0f);
    differ += same && occluded_same ? 0 : 1;
  }
  std::printf("%s, alpha %.2f: %d of %d rays end on a slat, %d differ\n", what, design.tilt_rad,
              on_slats, rays, differ);
  EXPECT_GT(on_slats, rays / 50);
  EXPECT_LE(differ, rays / 10'000);
}

TEST(BvhWithSlatsTest, HitsAreTheMeshes) {
  Scene scene = LoadExample("city_office");
  for (const bool vertical : {false, true})
    for (const std::map<std::string, double>& values : EdgeDesigns()) {
      scene.blind()->vertical = vertical;
      absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, values);
      ASSERT_TRUE(design.ok()) << design.status();
      ExpectHitsOfTheMesh(scene, *design, scene.window(), vertical ? "vertical" : "horizontal");
    }
}

// With two blinds (the corner office's), each a subtree of its own: around either window.
TEST(BvhWithSlatsTest, HitsOfTwoBlindsAreTheMeshes) {
  const Scene scene = LoadExample("corner_office");
  for (const std::map<std::string, double>& values : EdgeDesigns()) {
    if (values.count("width") > 0 && values.at("width") > 0.1) continue;  // beyond its range
    absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, values);
    ASSERT_TRUE(design.ok()) << design.status();
    for (const SceneWindow& w : scene.windows) {
      ExpectHitsOfTheMesh(scene, *design, w.window, w.name.c_str());
    }
  }
}

}  // namespace
}  // namespace fenestra
