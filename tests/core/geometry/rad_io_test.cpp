#include "core/geometry/rad_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

#include "core/geometry/material.h"
#include "core/trace/glass.h"

namespace fenestra {
namespace {

// Glazing goes to Radiance as `trans` whose diffuse reflection and straight transmission are
// the material's: colour rho + tau, transmissivity tau / (rho + tau), all of it specular.
TEST(RadIoTest, GlazingIsTransWithTheSameLight) {
  Scene scene;
  scene.name = "pane";
  scene.materials = {{"clear glass", 0.08, 0.72}, {"wall", 0.5, -1}};
  scene.fixed.part_names = {"p"};
  scene.fixed.Add({0, 0, 0}, {1, 0, 0}, {1, 1, 0}, 0, Side::kIndoor, 0);
  scene.fixed.Add({0, 0, 1}, {1, 0, 1}, {1, 1, 1}, 1, Side::kIndoor, 0);
  const std::string path =
      (std::filesystem::temp_directory_path() / "fenestra_rad_io_test.rad").string();
  absl::StatusOr<size_t> written = WriteSceneRad(path, scene, BlindDesign{});
  ASSERT_TRUE(written.ok()) << written.status();
  EXPECT_EQ(*written, 2u);
  std::ifstream in(path);
  const std::string text(std::istreambuf_iterator<char>(in), {});
  std::filesystem::remove(path);
  EXPECT_NE(text.find("void trans m0_clear_glass\n0\n0\n7 0.8 0.8 0.8 0 0 0.9 1\n"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("void plastic m1_wall\n0\n0\n5 0.5 0.5 0.5 0 0\n"), std::string::npos);
  EXPECT_NE(text.find("m0_clear_glass polygon t0\n0\n0\n9 0 0 0 1 0 0 1 1 0\n"), std::string::npos);
  EXPECT_NE(text.find("m1_wall polygon t1\n0\n0\n9 0 0 1 1 0 1 1 1 1\n"), std::string::npos);
  EXPECT_EQ(RadianceName(7, "a b/c\"d"), "m7_a_b_c_d");
}

std::string Exported(const Scene& scene, const BlindDesign& design) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "fenestra_rad_io_kinds_test.rad").string();
  const absl::StatusOr<size_t> written = WriteSceneRad(path, scene, design);
  EXPECT_TRUE(written.ok()) << written.status();
  std::ifstream in(path);
  const std::string text(std::istreambuf_iterator<char>(in), {});
  std::filesystem::remove(path);
  return text;
}

// Radiance's materials go back as themselves with the scene's parameters, each grey colour three
// times; a glass with the transmissivity of the tracer's pane. The slats' outer faces take the
// outer material.
TEST(RadIoTest, RadianceMaterialsAndOuterSlatFaces) {
  absl::StatusOr<Scene> scene = LoadScene(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const auto add = [&](const char* name, MaterialKind kind, RadianceParameters p) {
    Material m = MaterialOfKind(kind, p);
    m.name = name;
    scene->materials.push_back(m);
    return static_cast<uint32_t>(scene->materials.size() - 1);
  };
  const uint32_t metal = add("alu", MaterialKind::kMetal, {0.8, 0.9, 0.05});
  add("paint", MaterialKind::kPlastic, {0.7, 0.03, 0.1});
  const uint32_t fabric = add("fabric", MaterialKind::kTrans, {0.6, 0.02, 0.2, 0.3, 0.1});
  Material pane{"pane", 0, 0.88};
  pane.kind = MaterialKind::kGlass;
  scene->materials.push_back(pane);
  scene->blind()->material = metal;
  scene->blind()->outer_material = fabric;
  const std::string text = Exported(*scene, DefaultDesign(*scene));

  EXPECT_NE(text.find("void metal m4_alu\n0\n0\n5 0.8 0.8 0.8 0.9 0.05\n"), std::string::npos)
      << text.substr(0, 1200);
  EXPECT_NE(text.find("void plastic m5_paint\n0\n0\n5 0.7 0.7 0.7 0.03 0.1\n"), std::string::npos);
  EXPECT_NE(text.find("void trans m6_fabric\n0\n0\n7 0.6 0.6 0.6 0.02 0.2 0.3 0.1\n"),
            std::string::npos);
  EXPECT_NE(text.find("void plastic m0_office\n0\n0\n5 0.8 0.8 0.8 0 0\n"), std::string::npos);
  // Glass: the transmissivity whose pane transmits 0.88 at normal incidence, three times
  const std::string glass = "void glass m7_pane\n0\n0\n3 ";
  const size_t at = text.find(glass);
  ASSERT_NE(at, std::string::npos);
  std::istringstream values(text.substr(at + glass.size()));
  double t[3];
  values >> t[0] >> t[1] >> t[2];
  EXPECT_EQ(t[0], t[1]);
  EXPECT_EQ(t[0], t[2]);
  EXPECT_NEAR(GlassPane{static_cast<float>(t[0])}.Transmittance(1), 0.88, 1e-6);
  EXPECT_NEAR(t[0], 0.96, 0.002);  // Radiance's 1.0895 factor

  // 10 slats: 2 triangles of each are the outer face's, in the trans; the other 10 in the metal
  size_t outer = 0, slat = 0;
  for (size_t from = 0; (from = text.find(" polygon t", from)) != std::string::npos; ++from) {
    const size_t line = text.rfind('\n', from) + 1;
    const std::string modifier = text.substr(line, from - line);
    outer += modifier == "m6_fabric";
    slat += modifier == "m4_alu";
  }
  EXPECT_EQ(outer, 20u);
  EXPECT_EQ(slat, 100u);
}

}  // namespace
}  // namespace fenestra
