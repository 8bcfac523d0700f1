#include "core/dc/direct_sun.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/metrics/illuminance.h"
#include "core/optimize/hourly_illuminance.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"
#include "core/sky/sky_patches.h"
#include "core/trace/embree_scene.h"
#include "core/trace/trace_geometry.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

constexpr double kDegree = std::numbers::pi / 180;

// Whether the straight line from `sensor` towards `direction` leaves `mesh` without meeting
// a triangle: an Embree trace through every triangle, the blind's included, in a frame about
// `frame`.
bool LineClear(const TriangleMesh& mesh, const std::vector<Material>& materials,
               const Sensor& sensor, Vec3d direction, Vec3d frame) {
  absl::StatusOr<TraceGeometry> geometry = PrepareTraceGeometry(mesh, materials, &frame);
  EXPECT_TRUE(geometry.ok()) << geometry.status();
  absl::StatusOr<std::unique_ptr<EmbreeScene>> embree = EmbreeScene::Build(*geometry);
  EXPECT_TRUE(embree.ok()) << embree.status();
  const auto f = [](Vec3d v) {
    return Vec3f{static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
  };
  return !(*embree)->Intersector().Occluded(geometry->ToLocal(sensor.position), f(direction), 1e4f);
}

// A column of sensors just behind the city office's blind, facing the window (+y), from the
// sill up: lines from them to a sun in the window's normal plane cross the slats.
std::vector<Sensor> SensorsBehindBlind(const Scene& scene) {
  std::vector<Sensor> sensors;
  const double sill = scene.window().center.z - 0.5 * scene.window().height_m;
  for (int k = 0; k < 12; ++k) {
    Sensor s;
    s.name = "behind " + std::to_string(k);
    s.position = {0.1 * k - 0.5, scene.window().center.y - scene.window().depth_m - 0.2,
                  sill + 0.013 + 0.017 * k};
    s.direction = {0, 1, 0};
    sensors.push_back(s);
  }
  return sensors;
}

// Horizontal slats perpendicular to the window (alpha = pi/2) of width w, gap s and thickness
// t pass no straight line steeper than the cut-off profile angle, atan((w + s - t) / w): the
// direct sun reaches a sensor behind them in exactly the hours whose lines the slats leave
// clear, which below the cut-off an Embree trace through the blind's triangles confirms line
// by line, and above it in none, though the bare window lets those lines through.
TEST(DirectSunTest, SlatsCutTheSunOffAboveTheirCutOffAngle) {
  Scene scene = LoadExample("city_office");
  scene.sensors = SensorsBehindBlind(scene);
  const double w = 0.15, s = 0.05, t = 0.01;
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(
      scene, {{"alpha", std::numbers::pi / 2}, {"width", w}, {"spacing", s}, {"thickness", t}});
  ASSERT_TRUE(design.ok()) << design.status();
  const double cut_off = std::atan((w + s - t) / w);  // 51.7 degrees
  // One sun per "hour", in the window's normal plane, profile angles 20..72 degrees
  std::vector<SunColumn> suns;
  std::vector<double> angles;
  for (double a = 20; a <= 72; a += 0.5) {
    const double phi = a * kDegree;
    suns.push_back({static_cast<int>(suns.size()), {0, std::cos(phi), std::sin(phi)}, 50000});
    angles.push_back(phi);
  }
  absl::StatusOr<std::unique_ptr<DirectSun>> sun =
      DirectSun::Trace(scene, suns, static_cast<int>(suns.size()));
  ASSERT_TRUE(sun.ok()) << sun.status();
  const Matrix with_blind = (*sun)->Illuminance(*design);
  const Matrix bare = (*sun)->Illuminance(*design, /*blind=*/false);
  const TriangleMesh mesh = AssembleMesh(scene, *design);
  int lit_below = 0, bare_above = 0;
  for (size_t h = 0; h < suns.size(); ++h) {
    for (size_t i = 0; i < scene.sensors.size(); ++i) {
      const bool reached = with_blind(i, h) > 0;
      // The value is the beam's: normal illuminance times the cosine at the sensor
      if (reached) {
        EXPECT_NEAR(with_blind(i, h), 50000 * std::cos(angles[h]), 1e-6);
      }
      if (angles[h] > cut_off) {
        EXPECT_FALSE(reached) << "sensor " << i << " at " << angles[h] / kDegree << " degrees";
        bare_above += bare(i, h) > 0;
      } else {
        EXPECT_EQ(reached, LineClear(mesh, scene.materials, scene.sensors[i], suns[h].direction,
                                     scene.window().center))
            << "sensor " << i << " at " << angles[h] / kDegree << " degrees";
        lit_below += reached;
      }
    }
  }
  // Neither side is empty: the slats, not the room, stop the steep lines
  EXPECT_GT(lit_below, 100);
  EXPECT_GT(bare_above, 100);
}

// Stiff cases: closed slats (touching, in the window plane) let no line through at any angle;
// a grazing sun (0.01 degrees above the horizon, or lying along the sensor's plane) gives
// finite, non-negative values; a sun behind the sensor nothing; bad suns are refused.
TEST(DirectSunTest, ClosedSlatsGrazingSunsAndBadInput) {
  Scene scene = LoadExample("city_office");
  scene.sensors = SensorsBehindBlind(scene);
  absl::StatusOr<BlindDesign> closed = DesignWithOverrides(
      scene, {{"alpha", 0}, {"width", 0.15}, {"spacing", 0}, {"thickness", 0.01}});
  ASSERT_TRUE(closed.ok()) << closed.status();
  std::vector<SunColumn> suns;
  for (double a = 0.01; a < 89; a += 1.0) {
    const double phi = a * kDegree;
    suns.push_back({static_cast<int>(suns.size()), {0, std::cos(phi), std::sin(phi)}, 1e5});
  }
  suns.push_back({static_cast<int>(suns.size()), {0, -1, 0}, 1e5});  // behind the sensors
  suns.push_back({static_cast<int>(suns.size()), {1, 0, 0}, 1e5});   // along their plane
  absl::StatusOr<std::unique_ptr<DirectSun>> sun =
      DirectSun::Trace(scene, suns, static_cast<int>(suns.size()));
  ASSERT_TRUE(sun.ok()) << sun.status();
  EXPECT_TRUE((*sun)->Entries(*closed).empty());
  const Matrix bare = (*sun)->Illuminance(*closed, /*blind=*/false);
  EXPECT_TRUE(bare.allFinite());
  EXPECT_GE(bare.minCoeff(), 0.0);
  EXPECT_GT(bare.maxCoeff(), 0.0);  // the bare window lets some of those lines in
  EXPECT_EQ(bare.col(suns.size() - 2).sum(), 0.0);
  EXPECT_EQ(bare.col(suns.size() - 1).sum(), 0.0);
  // A column out of range, a direction that is not unit, negative light
  EXPECT_FALSE(DirectSun::Trace(scene, {{5, {0, 0, 1}, 1}}, 5).ok());
  EXPECT_FALSE(DirectSun::Trace(scene, {{0, {0, 0, 2}, 1}}, 1).ok());
  EXPECT_FALSE(DirectSun::Trace(scene, {{0, {0, 0, 1}, -1}}, 1).ok());
}

// Suns due north at altitudes 5, 10, ..., 75 degrees, 10^5 lx each, one column each.
std::vector<SunColumn> NorthernSunFan() {
  std::vector<SunColumn> suns;
  for (double a = 5; a < 80; a += 5) {
    const double phi = a * kDegree;
    suns.push_back({static_cast<int>(suns.size()), {0, std::cos(phi), std::sin(phi)}, 1e5});
  }
  return suns;
}

// Adds a Lambertian (or glazing) material to `scene`; its index.
uint32_t AddMaterial(Scene& scene, const char* name, double reflectance, double transmittance) {
  scene.materials.push_back({name, reflectance, transmittance});
  return static_cast<uint32_t>(scene.materials.size() - 1);
}

// Slats of glazing let the sun through by their transmittance; slats whose outer faces'
// material transmits otherwise than the rest count as opaque (which face a line meets first
// is not kept), and ones whose two materials transmit alike pass it as one.
TEST(DirectSunTest, SlatsWhoseFacesTransmitOtherwiseAreOpaque) {
  Scene scene = LoadExample("city_office");
  scene.sensors = SensorsBehindBlind(scene);
  const auto add = [&](const char* name, double reflectance, double transmittance) {
    return AddMaterial(scene, name, reflectance, transmittance);
  };
  const uint32_t half = add("half", 0.1, 0.5), alike = add("alike", 0.3, 0.5),
                 less = add("less", 0.1, 0.3);
  absl::StatusOr<BlindDesign> closed = DesignWithOverrides(
      scene, {{"alpha", 0}, {"width", 0.15}, {"spacing", 0}, {"thickness", 0.01}});
  ASSERT_TRUE(closed.ok()) << closed.status();
  const std::vector<SunColumn> suns = NorthernSunFan();
  const auto through = [&](uint32_t material, std::optional<uint32_t> outer) {
    scene.blind()->material = material;
    scene.blind()->outer_material = outer;
    absl::StatusOr<std::unique_ptr<DirectSun>> sun =
        DirectSun::Trace(scene, suns, static_cast<int>(suns.size()));
    EXPECT_TRUE(sun.ok()) << sun.status();
    const double bare = (*sun)->Illuminance(*closed, /*blind=*/false).sum();
    EXPECT_GT(bare, 0);
    return (*sun)->Illuminance(*closed).sum() / bare;
  };
  EXPECT_NEAR(through(half, std::nullopt), 0.5, 1e-6);
  EXPECT_NEAR(through(half, alike), 0.5, 1e-6);
  EXPECT_EQ(through(half, less), 0.0);
}

// One trace serves every finish: a design's finish gives the slats its materials' straight
// transmittance, as a scene whose blind is of those materials does (bit for bit); without one
// the scene's slats hold.
TEST(DirectSunTest, DesignFinishGivesTheSlatsTransmittance) {
  Scene scene = LoadExample("city_office");
  scene.sensors = SensorsBehindBlind(scene);
  const auto add = [&](const char* name, double reflectance, double transmittance) {
    return AddMaterial(scene, name, reflectance, transmittance);
  };
  const uint32_t opaque = scene.blind()->material, half = add("half", 0.1, 0.5),
                 less = add("less", 0.1, 0.3);
  absl::StatusOr<BlindDesign> closed = DesignWithOverrides(
      scene, {{"alpha", 0}, {"width", 0.15}, {"spacing", 0}, {"thickness", 0.01}});
  ASSERT_TRUE(closed.ok()) << closed.status();
  const std::vector<SunColumn> suns = NorthernSunFan();
  const auto traced = [&](const Scene& s) {
    absl::StatusOr<std::unique_ptr<DirectSun>> sun =
        DirectSun::Trace(s, suns, static_cast<int>(suns.size()));
    EXPECT_TRUE(sun.ok()) << sun.status();
    return sun.ok() ? *std::move(sun) : nullptr;
  };
  const std::unique_ptr<DirectSun> sun = traced(scene);
  ASSERT_NE(sun, nullptr);
  const double bare = sun->Illuminance(*closed, /*blind=*/false).sum();
  ASSERT_GT(bare, 0);
  EXPECT_EQ(sun->Illuminance(*closed).sum(), 0.0);  // the scene's opaque slats
  for (const SlatFinish finish : {SlatFinish{half, half}, SlatFinish{less, less},
                                  SlatFinish{half, less}, SlatFinish{opaque, opaque}}) {
    BlindDesign design = *closed;
    design.finish = finish;
    Scene alike = scene;
    alike.blind()->material = finish.material;
    alike.blind()->outer_material = finish.outer_material;
    const std::unique_ptr<DirectSun> of_scene = traced(alike);
    ASSERT_NE(of_scene, nullptr);
    const Matrix e = sun->Illuminance(design);
    EXPECT_EQ(e, of_scene->Illuminance(*closed));
    const double share = finish.material != finish.outer_material ? 0.0
                         : finish.material == half                ? 0.5
                         : finish.material == less                ? 0.3
                                                                  : 0.0;
    EXPECT_NEAR(e.sum() / bare, share, 1e-6) << finish.material << " " << finish.outer_material;
  }
}

// Where nothing can cut the sun, the direct sun traced to its position is the beam's
// E_dn sin(altitude) at an upward sensor, and the coefficients' direct part through the sky
// matrix's sun patches (D_0 S_sun, the sun smeared over 4 patches), from the same paths as
// D, is the patches' own integral of the cosine, within 4 standard errors of D_0's batches:
// an upward sensor above an open ground, the whole year of Montevideo. What the patches
// smear differs from the beam by about a percent over the year.
TEST(DirectSunTest, ReplacesTheSunPatchesOfAnOpenSensor) {
  Scene scene;
  scene.materials = {{"ground", 0.2, -1}};
  for (const auto& [a, b, c] :
       {std::tuple{Vec3d{-50, -50, 0}, Vec3d{50, -50, 0}, Vec3d{50, 50, 0}},
        std::tuple{Vec3d{-50, -50, 0}, Vec3d{50, 50, 0}, Vec3d{-50, 50, 0}}}) {
    scene.fixed.vertices.insert(scene.fixed.vertices.end(), {a, b, c});
    scene.fixed.material.push_back(0);
    scene.fixed.side.push_back(Side::kOutdoor);
    scene.fixed.part.push_back(0);
  }
  scene.fixed.part_names = {"ground"};
  scene.sensors = {{"open", {0, 0, 1}, {0, 0, 1}}};
  absl::StatusOr<EpwData> weather =
      ReadEpw(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw");
  ASSERT_TRUE(weather.ok()) << weather.status();
  absl::StatusOr<SkyMatrix> sky = BuildSkyMatrix(*weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  const std::vector<int> lit = LitColumns(sky->radiance);
  absl::StatusOr<Matrix> split = SplitSkyColumnsInLux(*sky, lit);
  ASSERT_TRUE(split.ok()) << split.status();
  absl::StatusOr<std::unique_ptr<DirectSun>> sun =
      DirectSun::Trace(scene, SunColumnsOf(*sky, lit), static_cast<int>(lit.size()));
  ASSERT_TRUE(sun.ok()) << sun.status();
  const double traced = (*sun)->Illuminance(BlindDesign{}).sum();
  // The beam by hand
  double beam = 0;
  for (const int t : lit) {
    const SkyStep& step = sky->steps[t];
    if (step.solar_altitude_rad > 0) {
      beam += kWhiteEfficacyLumensPerWatt * step.direct_normal * std::sin(step.solar_altitude_rad);
    }
  }
  EXPECT_NEAR(traced, beam, 1e-6 * beam);

  // The patches' integral of the cosine: over a band of altitudes [lo, hi], Omega (sin lo +
  // sin hi) / 2 (the zenith cap's too, from 84 to 90 degrees)
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  Eigen::RowVectorXd d0(kDaylightBins);
  d0(0) = 0;
  for (int j = 1; j < kDaylightBins; ++j) {
    const SkyPatch& p = (*patches)[j];
    const double lo = p.altitude_rad - 6 * kDegree;
    const double hi = std::min(p.altitude_rad + 6 * kDegree, std::numbers::pi / 2);
    d0(j) = p.solid_angle_sr * (std::sin(lo) + std::sin(hi)) / 2;
  }
  const Matrix sun_patches = -split->bottomRows(kDaylightBins);
  const double smeared = (d0 * sun_patches).sum();

  OneStageOptions options;
  options.paths_per_sensor = 400000;
  options.batches = 8;
  options.seed = 11;
  std::unique_ptr<DcBackend> backend = MakeEmbreeBackend();
  absl::StatusOr<OneStageResult> d = ComputeOneStage(scene, BlindDesign{}, options, backend.get());
  ASSERT_TRUE(d.ok()) << d.status();
  std::vector<double> batches;
  for (const Matrix& b : d->batch_direct_coefficients) batches.push_back((b * sun_patches).sum());
  double mean = 0, spread = 0;
  for (double v : batches) mean += v / batches.size();
  for (double v : batches) spread += (v - mean) * (v - mean);
  const double se = std::sqrt(spread / (batches.size() * (batches.size() - 1)));
  std::printf("annual direct sun [lx h]: beam %.6g, patches %.6g, D_0 S_sun %.6g +- %.3g\n", traced,
              smeared, mean, se);
  EXPECT_GT(traced, 1e7);
  EXPECT_LT(std::abs(mean - smeared), 4 * se);
  EXPECT_LT(std::abs(smeared - traced), 0.03 * traced);
  // Nothing reflects into the sensor's view: D_0 is the whole sky view, its sum pi
  EXPECT_NEAR(d->direct_coefficients.rightCols(kDaylightBins - 1).sum(), std::numbers::pi, 0.01);
}

}  // namespace
}  // namespace fenestra
