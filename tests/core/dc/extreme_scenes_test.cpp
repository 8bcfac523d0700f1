// Stiff and extreme scenes: each must give finite, sensible coefficients. Tolerances are in
// standard errors; seeds are fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/dc/one_stage.h"
#include "core/geometry/blind.h"
#include "core/geometry/scene.h"
#include "tests/core/trace/test_meshes.h"

namespace fenestra {
namespace {

using testing_meshes::AddBox;
using testing_meshes::AddQuad;
using testing_meshes::AddSquare;
using testing_meshes::Translated;

constexpr double kPi = 3.14159265358979323846;

Scene Lightwell() {
  absl::StatusOr<Scene> scene =
      LoadScene(std::string(FENESTRA_SOURCE_DIR) + "/examples/lightwell/scene.json");
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *std::move(scene);
}

OneStageOptions Options(int64_t paths, int max_bounces, uint64_t seed) {
  OneStageOptions options;
  options.paths_per_sensor = paths;
  options.max_bounces = max_bounces;
  options.seed = seed;
  return options;
}

void ExpectFinite(const OneStageResult& r) {
  EXPECT_TRUE(r.coefficients.allFinite());
  EXPECT_TRUE(r.standard_error.allFinite());
  EXPECT_GE(r.coefficients.minCoeff(), 0.0);
  EXPECT_LE(r.max_path_weight, 1.0);
  EXPECT_EQ(r.truncated_paths, 0u);
}

// |a - b| <= k combined standard errors, per sensor sky sum.
void ExpectSameSums(const OneStageResult& a, const OneStageResult& b, double k) {
  for (Eigen::Index s = 0; s < a.sky_sum.size(); ++s) {
    EXPECT_NEAR(a.sky_sum(s), b.sky_sum(s),
                k * std::hypot(a.sky_sum_standard_error(s), b.sky_sum_standard_error(s)))
        << "sensor " << s;
  }
}

TEST(ExtremeScenesTest, NearlyWhiteLightwellWith1000Bounces) {
  Scene scene = Lightwell();
  const OneStageResult grey =
      *ComputeOneStage(scene, DefaultDesign(scene), Options(20000, 1000, 1));
  for (Material& m : scene.materials) m.reflectance = 0.99;
  const auto white = ComputeOneStage(scene, DefaultDesign(scene), Options(20000, 1000, 1));
  ASSERT_TRUE(white.ok()) << white.status();
  ExpectFinite(*white);
  for (int s = 0; s < 3; ++s) {
    EXPECT_EQ(white->coefficients(s, 0), 0.0);
    // Far more light than with reflectance 0.8 / 0.2, and still below an unobstructed pi
    EXPECT_GT(white->sky_sum(s), 5 * grey.sky_sum(s));
    EXPECT_LT(white->sky_sum(s), kPi);
  }
  // Without roulette every path runs to 1000 reflections or escapes: same answer
  OneStageOptions no_roulette = Options(2000, 1000, 2);
  no_roulette.russian_roulette = false;
  const auto plain = ComputeOneStage(scene, DefaultDesign(scene), no_roulette);
  ASSERT_TRUE(plain.ok()) << plain.status();
  ExpectFinite(*plain);
  ExpectSameSums(*white, *plain, 4);
  std::printf(
      "reflectance 0.99: sky sums %.4f %.4f %.4f (grey %.2e %.2e %.2e), %.1f rays per "
      "path with roulette, %.1f without\n",
      white->sky_sum(0), white->sky_sum(1), white->sky_sum(2), grey.sky_sum(0), grey.sky_sum(1),
      grey.sky_sum(2), white->rays_traced / 60000.0, plain->rays_traced / 6000.0);
}

// The Sobol draws (OneStageOptions::sequence) in the stiffest case: the nearly white
// lightwell stays finite and gives the pseudo-random draws' sums within 4 combined standard
// errors (the Sobol run's from its batches).
TEST(ExtremeScenesTest, NearlyWhiteLightwellWithSobolDraws) {
  Scene scene = Lightwell();
  for (Material& m : scene.materials) m.reflectance = 0.99;
  const auto pseudo = ComputeOneStage(scene, DefaultDesign(scene), Options(20000, 1000, 1));
  OneStageOptions options = Options(20000, 1000, 4);
  options.sequence = Sequence::kSobol;
  const auto sobol = ComputeOneStage(scene, DefaultDesign(scene), options);
  ASSERT_TRUE(pseudo.ok() && sobol.ok()) << sobol.status();
  ExpectFinite(*sobol);
  EXPECT_EQ(sobol->batch_coefficients.size(), static_cast<size_t>(kSobolBatches));
  ExpectSameSums(*pseudo, *sobol, 4);
}

// A room x in [-1.5, 1.5], y in [-6.25, 0], z in [0, 3] whose north wall (0.25 m thick) has an
// opening x in [-1, 1], z in [0.9, 2.4], closed by ten 0.15 m slats of zero spacing: boxes
// that touch each other and the reveals, face on face.
TriangleMesh RoomWithClosedSlats() {
  TriangleMesh mesh;
  AddQuad(mesh, {-1.5, -6.25, 0}, {1.5, -6.25, 0}, {1.5, 0, 0}, {-1.5, 0, 0}, 1);  // floor
  AddQuad(mesh, {-1.5, -6.25, 3}, {1.5, -6.25, 3}, {1.5, 0, 3}, {-1.5, 0, 3}, 0);  // ceiling
  AddQuad(mesh, {-1.5, -6.25, 0}, {1.5, -6.25, 0}, {1.5, -6.25, 3}, {-1.5, -6.25, 3}, 0);
  AddQuad(mesh, {-1.5, -6.25, 0}, {-1.5, 0, 0}, {-1.5, 0, 3}, {-1.5, -6.25, 3}, 0);
  AddQuad(mesh, {1.5, -6.25, 0}, {1.5, 0, 0}, {1.5, 0, 3}, {1.5, -6.25, 3}, 0);
  // North wall's room face around the opening, and the reveals
  for (double y : {0.0, 0.25}) {
    AddQuad(mesh, {-1.5, y, 0}, {1.5, y, 0}, {1.5, y, 0.9}, {-1.5, y, 0.9}, 0);
    AddQuad(mesh, {-1.5, y, 2.4}, {1.5, y, 2.4}, {1.5, y, 3}, {-1.5, y, 3}, 0);
    AddQuad(mesh, {-1.5, y, 0.9}, {-1, y, 0.9}, {-1, y, 2.4}, {-1.5, y, 2.4}, 0);
    AddQuad(mesh, {1, y, 0.9}, {1.5, y, 0.9}, {1.5, y, 2.4}, {1, y, 2.4}, 0);
  }
  AddQuad(mesh, {-1, 0, 0.9}, {1, 0, 0.9}, {1, 0.25, 0.9}, {-1, 0.25, 0.9}, 0);
  AddQuad(mesh, {-1, 0, 2.4}, {1, 0, 2.4}, {1, 0.25, 2.4}, {-1, 0.25, 2.4}, 0);
  AddQuad(mesh, {-1, 0, 0.9}, {-1, 0.25, 0.9}, {-1, 0.25, 2.4}, {-1, 0, 2.4}, 0);
  AddQuad(mesh, {1, 0, 0.9}, {1, 0.25, 0.9}, {1, 0.25, 2.4}, {1, 0, 2.4}, 0);
  for (int k = 0; k < 10; ++k) {
    AddBox(mesh, {-1, 0.1, 0.9 + 0.15 * k}, {1, 0.11, 0.9 + 0.15 * (k + 1)}, 2);
  }
  return mesh;
}

TEST(ExtremeScenesTest, ClosedTouchingSlatsLetNoLightThrough) {
  const TriangleMesh mesh = RoomWithClosedSlats();
  const std::vector<Material> materials = {
      {"wall", 0.8, -1}, {"floor", 0.2, -1}, {"slat", 0.8, -1}};
  const std::vector<Sensor> sensors = {{"near", {0, -0.3, 1.5}, {0, 1, 0}},
                                       {"centre", {0, -3, 0.7}, {0, 0, 1}}};
  const auto result =
      ComputeOneStage(mesh, materials, sensors, Options(200000, kUnlimitedBounces, 3));
  ASSERT_TRUE(result.ok()) << result.status();
  ExpectFinite(*result);
  EXPECT_EQ(result->coefficients.maxCoeff(), 0.0);
  EXPECT_EQ(result->escaped_paths, 0u);
  OneStageOptions sobol = Options(200000, kUnlimitedBounces, 3);
  sobol.sequence = Sequence::kSobol;
  const auto closed = ComputeOneStage(mesh, materials, sensors, sobol);
  ASSERT_TRUE(closed.ok()) << closed.status();
  ExpectFinite(*closed);
  EXPECT_EQ(closed->coefficients.maxCoeff(), 0.0);  // Sobol draws too

  // The same room with the slats removed lets light in
  TriangleMesh open = mesh;
  const size_t keep = open.TriangleCount() - 10 * 12;
  open.vertices.resize(3 * keep);
  open.material.resize(keep);
  open.side.resize(keep);
  open.part.resize(keep);
  const auto lit = ComputeOneStage(open, materials, sensors, Options(20000, kUnlimitedBounces, 3));
  ASSERT_TRUE(lit.ok());
  EXPECT_GT(lit->sky_sum(0), 0.05);
}

TEST(ExtremeScenesTest, GeneratedBlindsWithZeroSpacingStayFinite) {
  const Scene scene = Lightwell();
  BlindSpec spec;
  spec.material = 0;  // the walls' 0.8
  double closed_sum = 0;
  for (double tilt : {0.0, 0.3, kPi / 2}) {
    TriangleMesh mesh = AssembleMesh(scene, DefaultDesign(scene));
    const BlindDesign design{true, tilt, 0.15, 0.0, 0.01, {}};
    const BlindLayout layout = GenerateBlind(scene.window(), spec, design,
                                             static_cast<uint32_t>(mesh.part_names.size()), mesh);
    const auto result =
        ComputeOneStage(mesh, scene.materials, scene.sensors, Options(50000, 29, 4));
    ASSERT_TRUE(result.ok()) << result.status();
    ExpectFinite(*result);
    for (int s = 0; s < 3; ++s) EXPECT_EQ(result->coefficients(s, 0), 0.0);
    std::printf("blind tilt %.2f, spacing 0: %d slats, pitch %.3f m; S1 sky sum %.3e +- %.1e\n",
                tilt, layout.slat_count, layout.pitch_m, result->sky_sum(0),
                result->sky_sum_standard_error(0));
    if (tilt == 0.0) {
      closed_sum = result->sky_sum(0);  // closed plate: only the 1 cm wall gap leaks around it
    } else if (tilt == kPi / 2) {
      EXPECT_GT(result->sky_sum(0), 3 * closed_sum);  // open slats let in much more
    }
  }
}

TEST(ExtremeScenesTest, SensorsLyingOnSurfaces) {
  // On an endless ground, facing up: nothing but sky, exactly pi
  TriangleMesh ground;
  AddSquare(ground, 0, 0, 1e4, 0, 0);
  const auto on_ground =
      ComputeOneStage(ground, {{"ground", 0.2, -1}}, {{"s", {3.25, -7.5, 0}, {0, 0, 1}}},
                      Options(100000, kUnlimitedBounces, 5));
  ASSERT_TRUE(on_ground.ok());
  EXPECT_NEAR(on_ground->sky_sum(0), kPi, 1e-12);
  EXPECT_EQ(on_ground->coefficients(0, 0), 0.0);

  // In the lightwell, on the floor and on a wall: as just off them
  const Scene scene = Lightwell();
  const TriangleMesh mesh = AssembleMesh(scene, DefaultDesign(scene));
  const std::vector<Sensor> on = {{"floor", {0, -3, 0}, {0, 0, 1}},
                                  {"wall", {1.5, -2, 1.5}, {-1, 0, 0}},
                                  {"ceiling", {0, -1, 3}, {0, 0, -1}}};
  const std::vector<Sensor> off = {{"floor", {0, -3, 1e-3}, {0, 0, 1}},
                                   {"wall", {1.5 - 1e-3, -2, 1.5}, {-1, 0, 0}},
                                   {"ceiling", {0, -1, 3 - 1e-3}, {0, 0, -1}}};
  const auto a = ComputeOneStage(mesh, scene.materials, on, Options(300000, 29, 6));
  const auto b = ComputeOneStage(mesh, scene.materials, off, Options(300000, 29, 7));
  ASSERT_TRUE(a.ok() && b.ok());
  ExpectFinite(*a);
  for (int s = 0; s < 3; ++s) {
    EXPECT_GT(a->sky_sum(s), 0);
    EXPECT_EQ(a->coefficients(s, 0), 0.0);
  }
  ExpectSameSums(*a, *b, 4);
}

TEST(ExtremeScenesTest, FarFromTheOriginGivesTheSameCoefficients) {
  const Scene scene = Lightwell();
  const TriangleMesh mesh = AssembleMesh(scene, DefaultDesign(scene));
  const Vec3d shift{1e4, 1e4, 0};
  std::vector<Sensor> far_sensors = scene.sensors;
  for (Sensor& s : far_sensors) s.position = s.position + shift;
  const OneStageOptions options = Options(200000, 29, 8);
  const auto near = ComputeOneStage(mesh, scene.materials, scene.sensors, options);
  const auto far = ComputeOneStage(Translated(mesh, shift), scene.materials, far_sensors, options);
  ASSERT_TRUE(near.ok() && far.ok());
  ExpectFinite(*far);
  ExpectSameSums(*near, *far, 1);
  // Within 1 standard error per coefficient (the local frames coincide: in fact equal)
  EXPECT_TRUE(((near->coefficients - far->coefficients).cwiseAbs().array() <=
               near->standard_error.array() + 1e-15)
                  .all());
  for (int s = 0; s < 3; ++s) EXPECT_EQ(far->coefficients(s, 0), 0.0);
}

TEST(ExtremeScenesTest, DegenerateTrianglesChangeNothing) {
  const Scene scene = Lightwell();
  const TriangleMesh mesh = AssembleMesh(scene, DefaultDesign(scene));
  // Zero-area triangles first (shifting every index): a point, a line through the room,
  // a sliver along the floor, and one of 1e-10 m sides
  TriangleMesh degenerate;
  degenerate.part_names = {"degenerate"};
  degenerate.Add({0, -3, 1}, {0, -3, 1}, {0, -3, 1}, 0, Side::kIndoor, 0);
  degenerate.Add({-1.5, -6, 1.5}, {0, -3, 1.5}, {1.5, 0, 1.5}, 0, Side::kIndoor, 0);
  degenerate.Add({-1.5, -6, 0}, {1.5, -6, 0}, {0, -6, 0}, 0, Side::kIndoor, 0);
  degenerate.Add({0, -2, 2}, {1e-10, -2, 2}, {0, -2 + 1e-10, 2}, 0, Side::kIndoor, 0);
  degenerate.Append(mesh);
  const OneStageOptions options = Options(200000, 29, 9);
  const auto clean = ComputeOneStage(mesh, scene.materials, scene.sensors, options);
  const auto dirty = ComputeOneStage(degenerate, scene.materials, scene.sensors, options);
  ASSERT_TRUE(clean.ok() && dirty.ok()) << dirty.status();
  ExpectFinite(*dirty);
  EXPECT_TRUE(((clean->coefficients - dirty->coefficients).cwiseAbs().array() <=
               clean->standard_error.array() + 1e-15)
                  .all());
  ExpectSameSums(*clean, *dirty, 1);
}

}  // namespace
}  // namespace fenestra
