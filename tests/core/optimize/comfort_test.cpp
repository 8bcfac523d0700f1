// Comfort in the search (core/optimize/comfort.h): the solar gain of an open window against
// the irradiance through its opening computed by hand, the glare metrics of a job against the
// one-stage glare of its best design, and what the door refuses. Tolerances are in standard
// errors; seeds are fixed.
#include "core/optimize/comfort.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/geometry/scene_proto.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/job.h"
#include "core/optimize/view_glare.h"
#include "core/sky/epw.h"
#include "core/sky/sky_patches.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

const std::string kOfficeScene = FENESTRA_SOURCE_DIR "/examples/sunny_office/scene.json";

// The sunny office without its blind and without anything outdoors (the sky's ground bin
// below the horizon), its reveals black: its window is a bare opening in a 0.25 m wall.
Scene BareOpening() {
  absl::StatusOr<v1::Scene> proto = ReadSceneProto(kOfficeScene);
  EXPECT_TRUE(proto.ok()) << proto.status();
  proto->clear_blind();
  v1::Material& black = *proto->add_materials();
  black.set_name("black");
  black.set_reflectance(0);
  google::protobuf::RepeatedPtrField<v1::Surface> kept;
  for (const v1::Surface& s : proto->surfaces()) {
    if (s.side() == v1::SIDE_OUTDOOR) continue;
    v1::Surface& k = *kept.Add() = s;
    if (s.name().rfind("reveal", 0) == 0) k.set_material("black");
  }
  proto->mutable_surfaces()->Swap(&kept);
  absl::StatusOr<Scene> scene = ValidateScene(*proto, kOfficeScene);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *std::move(scene);
}

// `sky` with only the steps `keep` lit (the others dark, without a sun).
SkyMatrix OnlySteps(SkyMatrix sky, const std::vector<int>& keep) {
  for (size_t s = 0; s < sky.steps.size(); ++s) {
    if (std::find(keep.begin(), keep.end(), static_cast<int>(s)) != keep.end()) continue;
    sky.radiance.col(static_cast<Eigen::Index>(s)).setZero();
    sky.steps[s].direct_normal = 0;
  }
  return sky;
}

// The solar power through the opening at step `s` [W], by quadrature: the inner face's area on
// a grid, the directions towards the outside cosine-weighted on a grid; a line counts where it
// leaves through the outer face (the reveals black); the diffuse sky and the ground bin from
// `diffuse` (a matrix without the sun), the sun's beam by the opening's sunlit share.
double PowerThroughOpening(const Window& w, const SkyMatrix& diffuse, const SkyMatrix& solar,
                           int s) {
  const SkyPatches patches = *SkyPatches::Reinhart(1);
  const Vec3d inner = w.center - w.depth_m * w.normal;
  const auto leaves = [&](Vec3d x, Vec3d d) {
    const double cos_n = Dot(d, w.normal);
    if (cos_n <= 0) return false;
    const Vec3d p = x + (w.depth_m / cos_n) * d - w.center;
    return std::abs(Dot(p, w.across)) <= 0.5 * w.width_m &&
           std::abs(Dot(p, w.up)) <= 0.5 * w.height_m;
  };
  constexpr int kArea = 24, kDirections = 96;
  double diffuse_w = 0;
  for (int i = 0; i < kArea; ++i) {
    for (int j = 0; j < kArea; ++j) {
      const Vec3d x = inner + ((i + 0.5) / kArea - 0.5) * w.width_m * w.across +
                      ((j + 0.5) / kArea - 0.5) * w.height_m * w.up;
      double sum = 0;
      for (int a = 0; a < kDirections; ++a) {
        for (int b = 0; b < kDirections; ++b) {
          const double u1 = (a + 0.5) / kDirections, u2 = (b + 0.5) / kDirections;
          const double r = std::sqrt(u1), phi = 2 * std::numbers::pi * u2;
          const Vec3d d = r * std::cos(phi) * w.across + r * std::sin(phi) * w.up +
                          std::sqrt(1 - u1) * w.normal;
          if (leaves(x, d)) sum += diffuse.radiance(patches.Bin(d), s);
        }
      }
      // E = pi x the mean radiance under cosine-weighted directions
      diffuse_w += std::numbers::pi * sum / (kDirections * kDirections);
    }
  }
  diffuse_w *= w.width_m * w.height_m / (kArea * kArea);
  const SkyStep& step = solar.steps[s];
  const Vec3d sun = SunDirection(step);
  const double cos_n = Dot(sun, w.normal);
  double beam_w = 0;
  if (cos_n > 0 && step.direct_normal > 0) {
    const double lit_across =
        std::max(0.0, 1 - w.depth_m * std::abs(Dot(sun, w.across)) / cos_n / w.width_m);
    const double lit_up =
        std::max(0.0, 1 - w.depth_m * std::abs(Dot(sun, w.up)) / cos_n / w.height_m);
    beam_w = step.direct_normal * cos_n * w.width_m * w.height_m * lit_across * lit_up;
  }
  return diffuse_w + beam_w;
}

// Clear hours of Phoenix: three in June (morning, noon, afternoon) and one December noon; the
// gain of the bare opening over them against the hand's, within 3 standard errors and 2% (the
// two-stage method's 288 direction cells and the 64 points that sample the beam on the plane).
TEST(ComfortTest, SolarGainOfAnOpenWindowIsTheIrradianceThroughIt) {
  const Scene scene = BareOpening();
  absl::StatusOr<EpwData> epw = ReadEpw(scene.site.weather_file);
  ASSERT_TRUE(epw.ok()) << epw.status();
  SkyMatrixOptions options;
  options.ground_reflectance = scene.site.ground_reflectance;
  options.quantity = SkyQuantity::kSolar;
  absl::StatusOr<SkyMatrix> solar = BuildSkyMatrix(*epw, options);
  ASSERT_TRUE(solar.ok()) << solar.status();
  options.include_sun = false;
  absl::StatusOr<SkyMatrix> diffuse = BuildSkyMatrix(*epw, options);
  ASSERT_TRUE(diffuse.ok()) << diffuse.status();
  options.quantity = SkyQuantity::kVisible;
  options.include_sun = true;
  absl::StatusOr<SkyMatrix> visible = BuildSkyMatrix(*epw, options);
  ASSERT_TRUE(visible.ok()) << visible.status();
  std::vector<int> hours;
  for (size_t s = 0; s < solar->steps.size(); ++s) {
    const SkyStep& step = solar->steps[s];
    const bool june = step.month == 6 && step.day == 21 &&
                      (step.hour == 9.5 || step.hour == 12.5 || step.hour == 15.5);
    const bool december = step.month == 12 && step.day == 21 && step.hour == 12.5;
    if ((june || december) && step.direct_normal > 500) hours.push_back(static_cast<int>(s));
  }
  ASSERT_EQ(hours.size(), 4u);
  double hand_wh = 0;
  for (const int s : hours) hand_wh += PowerThroughOpening(scene.window(), *diffuse, *solar, s);

  v1::Sampling sampling;
  sampling.set_outdoor_paths(400000);
  sampling.set_outdoor_bounces(-1);
  sampling.set_seed(5);
  sampling.set_basis_cells(288);
  sampling.set_window_columns(1);
  sampling.set_window_rows(1);
  sampling.set_batches(8);
  sampling.set_backend("cpu");
  absl::StatusOr<OutdoorMatrix> outdoor = ComputeOutdoorMatrix(scene, sampling, {}, false);
  ASSERT_TRUE(outdoor.ok()) << outdoor.status();
  IndoorOptions indoor;
  indoor.paths_per_sensor = kGainPathsDivisor * 8192;  // 8192 per gain point
  indoor.seed = 5;
  indoor.parts = {1, 1};
  indoor.batches = 8;
  const std::vector<bool> occupied(solar->steps.size(), true);
  absl::StatusOr<ComfortSky> sky =
      MakeComfortSky(OnlySteps(*visible, hours), OnlySteps(*solar, hours), hours, occupied,
                     kDefaultGlareThreshold, DefaultCoolingSeason(scene.site.latitude_deg));
  ASSERT_TRUE(sky.ok()) << sky.status();
  std::unique_ptr<DcBackend> cpu = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<DesignComfort>> comfort =
      DesignComfort::Start(scene, indoor, *cpu, {.gains = true});
  ASSERT_TRUE(comfort.ok()) << comfort.status();
  ASSERT_TRUE((*comfort)
                  ->SetSky(outdoor->batches, std::make_shared<const ComfortSky>(*std::move(sky)))
                  .ok());
  absl::StatusOr<ComfortEstimate> gain = (*comfort)->Evaluate(DefaultDesign(scene));
  ASSERT_TRUE(gain.ok()) << gain.status();
  const double hand_kwh = hand_wh / 1000;
  const double ours = gain->value.solar_gain_kwh, se = gain->standard_error.solar_gain_kwh;
  EXPECT_GT(se, 0.0);
  std::printf("solar gain over %zu hours: %.4f +- %.4f kWh, by hand %.4f kWh (%+.2f%%)\n",
              hours.size(), ours, se, hand_kwh, 100 * (ours / hand_kwh - 1));
  EXPECT_NEAR(ours, hand_kwh, 3 * se + 0.02 * hand_kwh) << "hand " << hand_kwh << " kWh";
  // Three of the four hours are in the cooling season (May-September, north)
  EXPECT_LT(gain->value.cooling_solar_gain_kwh, ours);
  EXPECT_GT(gain->value.cooling_solar_gain_kwh, 0.0);
}

// Points of the gain plane: behind the blind's space, over the opening and a margin; the
// room is black but for the window's zone.
TEST(ComfortTest, GainPointsLieBehindTheBlindOverTheOpening) {
  absl::StatusOr<Scene> scene = LoadValidScene(kOfficeScene);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const GainPoints points = GainPointsOf(*scene);
  ASSERT_EQ(points.sensors.size(), static_cast<size_t>(kGainPointsPerWindow));
  const Window& w = scene->window();
  double area = 0;
  for (size_t p = 0; p < points.sensors.size(); ++p) {
    const Vec3d x = points.sensors[p].position;
    const double depth = Dot(w.center - x, w.normal);
    EXPECT_GT(depth, w.depth_m + 0.05);  // behind the slats (0.15 m wide) and the wall gap
    EXPECT_LT(depth, w.depth_m + 0.2);
    EXPECT_EQ(points.sensors[p].direction.y, w.normal.y);
    area += points.area_m2[p];
  }
  EXPECT_GT(area, w.width_m * w.height_m);  // the margin
  const Scene gains = GainScene(*scene, points);
  int black = 0;
  for (const uint32_t m : gains.fixed.material) black += gains.materials[m].name == "gain black";
  EXPECT_GT(black, 0);
  EXPECT_LT(black, static_cast<int>(gains.fixed.TriangleCount()));
}

}  // namespace
}  // namespace fenestra
