#include "core/geometry/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace fenestra {
namespace {

const std::string kLightwell = FENESTRA_SOURCE_DIR "/examples/lightwell/scene.json";
const std::string kCityOffice = FENESTRA_SOURCE_DIR "/examples/city_office/scene.json";

double Area(const TriangleMesh& mesh, size_t t) {
  const Vec3d a = mesh.vertices[3 * t], b = mesh.vertices[3 * t + 1], c = mesh.vertices[3 * t + 2];
  return 0.5 * Length(Cross(b - a, c - a));
}

struct Box3 {
  Vec3d lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  void Add(Vec3d v) {
    lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
    hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
  }
};

void ExpectBox(const Box3& box, Vec3d lo, Vec3d hi) {
  EXPECT_DOUBLE_EQ(box.lo.x, lo.x);
  EXPECT_DOUBLE_EQ(box.lo.y, lo.y);
  EXPECT_DOUBLE_EQ(box.lo.z, lo.z);
  EXPECT_DOUBLE_EQ(box.hi.x, hi.x);
  EXPECT_DOUBLE_EQ(box.hi.y, hi.y);
  EXPECT_DOUBLE_EQ(box.hi.z, hi.z);
}

TEST(SceneTest, LightwellHas42TrianglesMatchingItsDescription) {
  absl::StatusOr<Scene> scene = LoadScene(kLightwell);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const TriangleMesh mesh = AssembleMesh(*scene, DefaultDesign(*scene));
  ASSERT_EQ(mesh.TriangleCount(), 42u);

  // Area per reflectance: walls 0.8, floors 0.2 (room floor + well ground)
  std::map<double, double> area_by_reflectance;
  Box3 box;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    area_by_reflectance[scene->materials[mesh.material[t]].reflectance] += Area(mesh, t);
    for (int k = 0; k < 3; ++k) box.Add(mesh.vertices[3 * t + k]);
  }
  const double floors = 3 * 6.25 + 3 * 3;
  const double walls = 3 * 6.25 /*ceiling*/ + 3 * 3 /*back*/ + 2 * 6.25 * 3 /*sides*/ +
                       (9 - 3) /*window wall, room*/ + (2 * 2 * 0.25 + 2 * 1.5 * 0.25) /*reveals*/ +
                       (3 * 20 - 3) /*window wall, well*/ + 3 * 20 + 2 * 3 * 20 /*well walls*/;
  EXPECT_NEAR(area_by_reflectance[0.2], floors, 1e-9);
  EXPECT_NEAR(area_by_reflectance[0.8], walls, 1e-9);
  ExpectBox(box, {-1.5, -6.25, 0}, {1.5, 3.25, 20});

  // The opening is empty: no triangle overlaps the window rectangle's interior
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    Box3 tri;
    for (int k = 0; k < 3; ++k) tri.Add(mesh.vertices[3 * t + k]);
    const bool inside_opening = tri.lo.x > -1 - 1e-12 && tri.hi.x < 1 + 1e-12 &&
                                tri.lo.z > 0.9 - 1e-12 && tri.hi.z < 2.4 + 1e-12 && tri.lo.y >= 0 &&
                                tri.hi.y <= 0.25 && tri.lo.y == tri.hi.y;
    EXPECT_FALSE(inside_opening) << "triangle " << t << " covers the opening";
  }
  ASSERT_EQ(scene->sensors.size(), 3u);
  EXPECT_DOUBLE_EQ(scene->sensors[2].position.y, -5);
  EXPECT_DOUBLE_EQ(scene->window().Area(), 3.0);
  EXPECT_FALSE(scene->blind().has_value());
}

TEST(SceneTest, CityOfficeMatchesItsTable) {
  absl::StatusOr<Scene> scene = LoadScene(kCityOffice);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const TriangleMesh& mesh = scene->fixed;
  std::map<std::string, Box3> boxes;
  std::map<std::string, int> counts;
  double outdoor_area = 0, indoor_area = 0;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    const std::string& name = mesh.part_names[mesh.part[t]];
    ++counts[name];
    for (int k = 0; k < 3; ++k) boxes[name].Add(mesh.vertices[3 * t + k]);
    (mesh.side[t] == Side::kOutdoor ? outdoor_area : indoor_area) += Area(mesh, t);
  }
  ExpectBox(boxes["ground"], {-200, -200, -0.1}, {200, 200, 0});
  ExpectBox(boxes["north row west"], {-60, 14.25, 0}, {-4, 34.25, 21});
  ExpectBox(boxes["north row east"], {4, 14.25, 0}, {60, 34.25, 27});
  ExpectBox(boxes["tower north-east"], {25, 50, 0}, {45, 70, 60});
  ExpectBox(boxes["block west"], {-60, -20, 0}, {-28, 6, 12});
  ExpectBox(boxes["block east"], {28, -20, 0}, {60, 6, 18});
  ExpectBox(boxes["far south"], {-60, -80, 0}, {60, -40, 30});
  for (const char* b : {"ground", "north row west", "north row east", "tower north-east",
                        "block west", "block east", "far south"}) {
    EXPECT_EQ(counts[b], 12) << b;
  }
  ExpectBox(boxes["room floor"], {-1.5, -6.25, 6}, {1.5, 0, 6});
  ExpectBox(boxes["reveal sill"], {-1, 0, 6.9}, {1, 0.25, 6.9});
  ExpectBox(boxes["reveal head"], {-1, 0, 8.4}, {1, 0.25, 8.4});
  // Indoor: room (2*3*6.25 + 2*6.25*3 + 3*3 + 9 - 3) and reveals (1.75)
  EXPECT_NEAR(indoor_area, 2 * 18.75 + 37.5 + 9 + 6 + 1.75, 1e-9);
  // Office block exterior (no bottom face) and its north face less the opening
  const double block = 40 * 20.25 + 2 * 20.25 * 15 + 40 * 15 + (40 * 15 - 3);
  auto box_area = [](double dx, double dy, double dz) { return 2 * (dx * dy + dy * dz + dz * dx); };
  const double boxes_area = box_area(400, 400, 0.1) + box_area(56, 20, 21) + box_area(56, 20, 27) +
                            box_area(20, 20, 60) + box_area(32, 26, 12) + box_area(32, 26, 18) +
                            box_area(120, 40, 30);
  EXPECT_NEAR(outdoor_area, block + boxes_area, 1e-6);
  EXPECT_EQ(mesh.TriangleCount(), 26u + 16u + 7u * 12u);
  ASSERT_EQ(scene->sensors.size(), 9u);
  EXPECT_DOUBLE_EQ(scene->sensors[8].position.x, 1);
  EXPECT_DOUBLE_EQ(scene->sensors[8].position.y, -5);
  EXPECT_DOUBLE_EQ(scene->sensors[8].position.z, 6.7);
  ASSERT_TRUE(scene->blind().has_value());
  EXPECT_DOUBLE_EQ(scene->blind()->slat_width_m.value, 0.15);
  EXPECT_NEAR(scene->site.latitude_deg, -34.83, 1e-12);

  // The default blind: 10 slats of 12 triangles
  EXPECT_EQ(AssembleMesh(*scene, DefaultDesign(*scene)).TriangleCount(),
            mesh.TriangleCount() + 120);
}

TEST(SceneTest, DesignOverridesAreChecked) {
  absl::StatusOr<Scene> scene = LoadScene(kCityOffice);
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<BlindDesign> design =
      DesignWithOverrides(*scene, {{"alpha", 0.5}, {"width", 0.12}});
  ASSERT_TRUE(design.ok()) << design.status();
  EXPECT_DOUBLE_EQ(design->tilt_rad, 0.5);
  EXPECT_DOUBLE_EQ(design->slat_width_m, 0.12);
  EXPECT_DOUBLE_EQ(design->slat_thickness_m, 0.01);

  design = DesignWithOverrides(*scene, {{"width", 0.2}});
  ASSERT_FALSE(design.ok());
  EXPECT_NE(design.status().message().find("width = 0.2 is outside its range [0.05, 0.15]"),
            std::string::npos)
      << design.status();
  design = DesignWithOverrides(*scene, {{"colour", 1}});
  ASSERT_FALSE(design.ok());
  EXPECT_NE(design.status().message().find("unknown design variable 'colour'"), std::string::npos);
}

}  // namespace
}  // namespace fenestra
