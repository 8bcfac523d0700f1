#include "core/geometry/rad_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

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

}  // namespace
}  // namespace fenestra
