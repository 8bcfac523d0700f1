#include "core/geometry/scene_proto.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/geometry/material.h"
#include "core/geometry/scene.h"
#include "google/protobuf/util/json_util.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

void ExpectSameVector(const Vec3d& a, const Vec3d& b) {
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.z, b.z);
}

// The same kind and parts, bit for bit.
void ExpectSameParts(const Material& a, const Material& b) {
  SCOPED_TRACE(a.name);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.reflectance, b.reflectance);
  EXPECT_EQ(a.transmittance, b.transmittance);
  EXPECT_EQ(a.specular, b.specular);
  EXPECT_EQ(a.roughness, b.roughness);
  EXPECT_EQ(a.through, b.through);
}

// The rebuilt scene has the same triangles (vertices, materials, sides, part names), window,
// sensors, blind and location, and no weather file.
void ExpectSameScene(const Scene& original, const Scene& rebuilt) {
  const TriangleMesh a = AssembleMesh(original, DefaultDesign(original));
  const TriangleMesh b = AssembleMesh(rebuilt, DefaultDesign(rebuilt));
  ASSERT_EQ(a.TriangleCount(), b.TriangleCount());
  for (size_t t = 0; t < a.TriangleCount(); ++t) {
    for (int k = 0; k < 3; ++k) ExpectSameVector(a.vertices[3 * t + k], b.vertices[3 * t + k]);
    EXPECT_EQ(original.materials[a.material[t]].name, rebuilt.materials[b.material[t]].name);
    EXPECT_EQ(a.side[t], b.side[t]);
    EXPECT_EQ(a.part_names[a.part[t]], b.part_names[b.part[t]]);
  }
  ASSERT_EQ(original.materials.size(), rebuilt.materials.size());
  for (size_t m = 0; m < original.materials.size(); ++m) {
    ExpectSameParts(original.materials[m], rebuilt.materials[m]);
  }
  ExpectSameVector(original.window().center, rebuilt.window().center);
  ExpectSameVector(original.window().up, rebuilt.window().up);
  EXPECT_EQ(original.window().depth_m, rebuilt.window().depth_m);
  ASSERT_EQ(original.sensors.size(), rebuilt.sensors.size());
  for (size_t s = 0; s < original.sensors.size(); ++s) {
    EXPECT_EQ(original.sensors[s].name, rebuilt.sensors[s].name);
    ExpectSameVector(original.sensors[s].position, rebuilt.sensors[s].position);
  }
  ASSERT_EQ(original.blind().has_value(), rebuilt.blind().has_value());
  if (original.blind()) {
    EXPECT_EQ(original.blind()->slat_width_m.max, rebuilt.blind()->slat_width_m.max);
    EXPECT_EQ(original.blind()->wall_gap_m, rebuilt.blind()->wall_gap_m);
    EXPECT_EQ(original.blind()->vertical, rebuilt.blind()->vertical);
    EXPECT_EQ(original.blind()->material, rebuilt.blind()->material);
    EXPECT_EQ(original.blind()->outer_material, rebuilt.blind()->outer_material);
  }
  EXPECT_EQ(original.site.latitude_deg, rebuilt.site.latitude_deg);
  EXPECT_EQ(original.site.ground_reflectance, rebuilt.site.ground_reflectance);
  EXPECT_EQ(rebuilt.site.weather_file, "");
}

TEST(SceneProtoTest, CityOfficeRebuildsTheSameScene) {
  absl::StatusOr<Scene> scene = LoadScene(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const v1::Scene proto = SelfContainedSceneProto(*scene);
  EXPECT_NE(scene->site.weather_file, "");
  EXPECT_EQ(proto.site().weather_file(), "");  // no paths
  absl::StatusOr<Scene> rebuilt = BuildScene(proto, "rebuilt.json");
  ASSERT_TRUE(rebuilt.ok()) << rebuilt.status();
  ExpectSameScene(*scene, *rebuilt);
}

// OBJ meshes become triangles, sensor grids sensors, vertical blinds stay vertical
TEST(SceneProtoTest, ObjMeshesAndGridsAreInlined) {
  const fs::path dir =
      fs::temp_directory_path() / ("fenestra_scene_proto_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "box.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng top\nf 1 2 3 4\n";
  std::ofstream(dir / "scene.json") << R"({
    "materials": [{"name": "wall", "reflectance": 0.5},
                  {"name": "glass", "reflectance": 0.1, "transmittance": 0.6}],
    "surfaces": [{"name": "mesh", "material": "wall", "side": "SIDE_INDOOR",
                  "obj": {"path": "box.obj", "groupMaterials": {"top": "glass"}}}],
    "window": {"center": {"x": 0, "y": 1, "z": 1}, "outwardNormal": {"x": 0, "y": 1, "z": 0},
               "up": {"x": 0, "y": 0, "z": 1}, "widthM": 1, "heightM": 1, "depthM": 0.2},
    "sensorGrids": [{"name": "g", "zM": 0.8, "xMinM": 0, "xMaxM": 1, "yMinM": 0, "yMaxM": 0.5,
                     "spacingM": 0.25}],
    "blind": {"material": "wall", "orientation": "VERTICAL",
              "tiltRad": {"value": 0.3, "min": 0, "max": 1},
              "slatWidthM": {"value": 0.05}, "slatSpacingM": {"value": 0.01},
              "slatThicknessM": {"value": 0.002}, "sideMarginM": 0.02}
  })";
  absl::StatusOr<Scene> scene = LoadScene((dir / "scene.json").string());
  fs::remove_all(dir);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const v1::Scene proto = SelfContainedSceneProto(*scene);
  EXPECT_EQ(proto.surfaces_size(), 2);
  EXPECT_TRUE(proto.surfaces(0).has_polygon());
  EXPECT_EQ(proto.sensors_size(), 8);
  EXPECT_EQ(proto.sensor_grids_size(), 0);
  absl::StatusOr<Scene> rebuilt = BuildScene(proto, "rebuilt.json");
  ASSERT_TRUE(rebuilt.ok()) << rebuilt.status();
  ExpectSameScene(*scene, *rebuilt);
  EXPECT_EQ(rebuilt->blind()->side_margin_m, 0.02);
}

// Radiance's materials go back as their kinds with the parameters the scene gave, through
// the message and through its JSON, and so does the slats' outer material.
TEST(SceneProtoTest, RadianceMaterialsAndOuterSlatFacesRoundTrip) {
  absl::StatusOr<v1::Scene> proto =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(proto.ok()) << proto.status();
  const std::string slat = proto->blind().material();
  for (v1::Material& m : *proto->mutable_materials()) {
    if (m.name() != slat) continue;
    m.clear_reflectance();
    m.mutable_metal()->set_reflectance(0.8);
    m.mutable_metal()->set_specularity(0.9);
    m.mutable_metal()->set_roughness(0.05);
  }
  const auto add = [&](const char* name) {
    v1::Material& m = *proto->add_materials();
    m.set_name(name);
    return &m;
  };
  v1::Material::Plastic& paint = *add("paint")->mutable_plastic();
  paint.set_reflectance(0.7), paint.set_specularity(0.03), paint.set_roughness(0.1);
  v1::Material::Trans& fabric = *add("fabric")->mutable_trans();
  fabric.set_reflectance(0.6), fabric.set_specularity(0.02), fabric.set_roughness(0.2);
  fabric.set_transmissivity(0.3), fabric.set_transmitted_specular(0.1);
  add("pane")->mutable_glass()->set_transmittance(0.88);
  add("black");  // Lambertian, reflectance 0
  proto->mutable_blind()->set_outer_material("fabric");
  absl::StatusOr<Scene> scene = BuildScene(*proto, "scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();

  const v1::Scene written = SelfContainedSceneProto(*scene);
  std::string json;
  ASSERT_TRUE(google::protobuf::util::MessageToJsonString(written, &json).ok());
  v1::Scene parsed;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(json, &parsed).ok()) << json;
  for (const v1::Scene& back : {written, parsed}) {
    absl::StatusOr<Scene> rebuilt = BuildScene(back, "rebuilt.json");
    ASSERT_TRUE(rebuilt.ok()) << rebuilt.status();
    ExpectSameScene(*scene, *rebuilt);
    EXPECT_EQ(back.blind().outer_material(), "fabric");
    const auto material = [&](const std::string& name) -> const v1::Material& {
      for (const v1::Material& m : back.materials()) {
        if (m.name() == name) return m;
      }
      ADD_FAILURE() << name;
      return back.materials(0);
    };
    const v1::Material& metal = material(slat);
    EXPECT_FALSE(metal.has_reflectance());
    EXPECT_EQ(metal.metal().reflectance(), 0.8);
    EXPECT_EQ(metal.metal().specularity(), 0.9);
    EXPECT_EQ(metal.metal().roughness(), 0.05);
    EXPECT_EQ(material("paint").plastic().reflectance(), 0.7);
    EXPECT_EQ(material("fabric").trans().transmissivity(), 0.3);
    EXPECT_EQ(material("fabric").trans().transmitted_specular(), 0.1);
    EXPECT_EQ(material("pane").glass().transmittance(), 0.88);
    EXPECT_EQ(material("black").kind_case(), v1::Material::KIND_NOT_SET);
  }
}

// Every plastic, metal and trans MaterialOfKind makes gives parameters that make it again, bit
// for bit (a scene written back and read again is the same scene).
TEST(SceneProtoTest, ParametersOfKindGiveThePartsBack) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0, 1);
  int exact = 0;
  for (int i = 0; i < 3000; ++i) {
    RadianceParameters p{unit(rng), unit(rng), unit(rng), unit(rng), unit(rng)};
    if (i % 3 == 0) {  // values as people write them
      for (double* v : {&p.colour, &p.specularity, &p.transmissivity, &p.transmitted_specular}) {
        *v = std::round(*v * 100) / 100;
      }
    }
    if (p.specularity >= 1) continue;
    for (const MaterialKind kind :
         {MaterialKind::kPlastic, MaterialKind::kMetal, MaterialKind::kTrans}) {
      const Material made = MaterialOfKind(kind, p);
      const Material again = MaterialOfKind(kind, ParametersOfKind(made));
      ExpectSameParts(made, again);
      if (testing::Test::HasFailure())
        FAIL() << "kind " << static_cast<int>(kind) << " colour " << p.colour;
      ++exact;
    }
  }
  EXPECT_GT(exact, 8000);
}

TEST(SceneProtoTest, SliversAreLeftOut) {
  EXPECT_TRUE(IsDegenerateTriangle({0, 0, 0}, {1, 0, 0}, {2, 1e-9, 0}));
  EXPECT_FALSE(IsDegenerateTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
}

}  // namespace
}  // namespace fenestra
