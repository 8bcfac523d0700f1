#include "core/trace/path.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/trace/brute_force_intersector.h"
#include "core/trace/ray_offset.h"
#include "core/trace/sampling.h"

namespace fenestra {
namespace {

// Collects the escapes of the paths it sees.
// Sums per sky bin (both blocks of OneStageBin) and, apart, the unreflected block's.
struct RecordingSink {
  std::vector<double> sum = std::vector<double>(kTregenzaBinCount, 0.0);
  std::vector<double> unreflected = std::vector<double>(kTregenzaBinCount, 0.0);
  int escapes = 0;
  void Add(int bin, double value) {
    sum[bin % kTregenzaBinCount] += value;
    if (bin >= kTregenzaBinCount) unreflected[bin - kTregenzaBinCount] += value;
    ++escapes;
  }
  void EndPath() {}
};

// A horizontal square of half side `half` at height `z`, two triangles.
void AddSquare(std::vector<Vec3f>& v, float half, float z) {
  const Vec3f a{-half, -half, z}, b{half, -half, z}, c{half, half, z}, d{-half, half, z};
  v.insert(v.end(), {a, b, c, a, c, d});
}

TEST(SamplingTest, BasisIsOrthonormalForAnyNormal) {
  const Vec3f normals[] = {{0, 0, 1},
                           {0, 0, -1},
                           {1, 0, 0},
                           {0, -1, 0},
                           Normalize(Vec3f{1, 2, -3}),
                           Normalize(Vec3f{-1e-7f, 0, -1})};
  for (const Vec3f n : normals) {
    Vec3f t, b;
    OrthonormalBasis(n, &t, &b);
    EXPECT_NEAR(Dot(t, t), 1, 1e-6);
    EXPECT_NEAR(Dot(b, b), 1, 1e-6);
    EXPECT_NEAR(Dot(t, b), 0, 1e-6);
    EXPECT_NEAR(Dot(t, n), 0, 1e-6);
    EXPECT_NEAR(Dot(b, n), 0, 1e-6);
  }
}

TEST(SamplingTest, CosineSamplesHaveMeanCosineTwoThirds) {
  const Vec3f n = Normalize(Vec3f{0.3f, -0.5f, -0.8f});
  const int kSamples = 200000;
  double sum = 0;
  for (int i = 0; i < kSamples; ++i) {
    const Uniform4 u = PathRandom(1, 0, i).Draw(0, 0);
    const Vec3f d = SampleCosineHemisphere(n, u.u[0], u.u[1]);
    ASSERT_NEAR(Dot(d, d), 1, 1e-5);
    ASSERT_GT(Dot(d, n), 0);
    sum += Dot(d, n);
  }
  // E[cos] = 2/3, Var[cos] = 1/2 - 4/9 = 1/18
  EXPECT_NEAR(sum / kSamples, 2.0 / 3.0, 5 * std::sqrt(1.0 / 18 / kSamples));
}

TEST(RayOffsetTest, MovesTheOriginToTheNormalsSide) {
  const float magnitudes[] = {0.0f, 1e-3f, 0.04f, 1.0f, 37.5f, 1e4f, 1e6f};
  for (float m : magnitudes) {
    for (float sign : {1.0f, -1.0f}) {
      const Vec3f p{sign * m, -m, m};
      const Vec3f n = Normalize(Vec3f{1, 2, -2});
      const Vec3f q = OffsetRayOrigin(p, n);
      EXPECT_GT(Dot(q - p, n), 0) << "magnitude " << m;
      // At most a few hundred ulps (or 2^-16 near the origin)
      EXPECT_LT(Length(q - p), std::max(1e-4f, 1e-4f * m)) << "magnitude " << m;
    }
  }
}

TEST(TracePathTest, EmptySceneEscapesAtOnceWithFullWeight) {
  const BruteForceIntersector scene{nullptr, 0};
  const TraceMaterial material{0.5f, -1.0f};
  const uint32_t triangle_material = 0;
  const SurfaceTable surfaces{&material, &triangle_material};
  RecordingSink sink;
  OneStageMode<RecordingSink> mode{{0, 0, 0}, {0, 0, 1}, &sink};
  const PathSettings settings{-1, true, 1.0f, 1000};
  for (int p = 0; p < 1000; ++p) {
    const PathStats stats = TracePath(scene, surfaces, settings, PathRandom(3, 0, p), mode);
    EXPECT_EQ(stats.rays, 1u);
    EXPECT_EQ(stats.end, PathEnd::kEscaped);
    EXPECT_EQ(stats.max_weight, 1.0f);
  }
  double total = 0;
  for (double v : sink.sum) total += v;
  EXPECT_NEAR(total, 1000 * kPi, 1e-9);
  EXPECT_EQ(sink.sum[0], 0.0);
}

TEST(TracePathTest, BounceLimitCountsReflections) {
  // A downward sensor 1 m over a ground square of reflectance 0.5 (no roulette)
  std::vector<Vec3f> vertices;
  AddSquare(vertices, 1e4f, 0.0f);
  const BruteForceIntersector scene{vertices.data(), 2};
  const TraceMaterial material{0.5f, -1.0f};
  const uint32_t triangle_material[] = {0, 0};
  const SurfaceTable surfaces{&material, triangle_material};
  RecordingSink sink;
  OneStageMode<RecordingSink> mode{{0, 0, 1}, {0, 0, -1}, &sink};

  // No reflection allowed: every path ends at the ground
  PathSettings settings{0, false, 1.0f, 1000};
  for (int p = 0; p < 100; ++p) {
    const PathStats stats = TracePath(scene, surfaces, settings, PathRandom(3, 0, p), mode);
    EXPECT_EQ(stats.end, PathEnd::kBounceLimit);
    EXPECT_EQ(stats.rays, 1u);
  }
  EXPECT_EQ(sink.escapes, 0);

  // One reflection: every path escapes to the sky with weight 0.5 after two rays
  settings.max_bounces = 1;
  for (int p = 0; p < 100; ++p) {
    const PathStats stats = TracePath(scene, surfaces, settings, PathRandom(3, 0, p), mode);
    EXPECT_EQ(stats.end, PathEnd::kEscaped);
    EXPECT_EQ(stats.rays, 2u);
  }
  EXPECT_EQ(sink.escapes, 100);
  EXPECT_EQ(sink.sum[0], 0.0);
  double total = 0;
  for (double v : sink.sum) total += v;
  EXPECT_NEAR(total, 100 * 0.5 * kPi, 1e-9);
}

TEST(TracePathTest, RouletteKeepsWeightsAtMostOne) {
  // Sensor between two parallel squares of reflectance 0.99 (almost closed)
  std::vector<Vec3f> vertices;
  AddSquare(vertices, 100.0f, 0.0f);
  AddSquare(vertices, 100.0f, 1.0f);
  const BruteForceIntersector scene{vertices.data(), 4};
  const TraceMaterial material{0.99f, -1.0f};
  const uint32_t triangle_material[] = {0, 0, 0, 0};
  const SurfaceTable surfaces{&material, triangle_material};
  for (float threshold : {1.0f, 0.3f, 1e-3f}) {
    RecordingSink sink;
    OneStageMode<RecordingSink> mode{{0, 0, 0.5f}, {0, 0, 1}, &sink};
    const PathSettings settings{-1, true, threshold, 1u << 20};
    for (int p = 0; p < 2000; ++p) {
      const PathStats stats = TracePath(scene, surfaces, settings, PathRandom(5, 0, p), mode);
      ASSERT_LE(stats.max_weight, 1.0f);
      ASSERT_NE(stats.end, PathEnd::kTruncated);
    }
  }
}

TEST(TracePathTest, GlazingTransmitsStraightAndReflectsDiffusely) {
  // An upward sensor under a wide pane (tau 0.6, rho 0.1): pi tau reaches the sky, bin by
  // bin as without the pane; pi rho goes down and escapes to the ground bin.
  std::vector<Vec3f> vertices;
  AddSquare(vertices, 1e5f, 1.0f);
  const BruteForceIntersector scene{vertices.data(), 2};
  const TraceMaterial material{0.1f, 0.6f};
  const uint32_t triangle_material[] = {0, 0};
  const SurfaceTable surfaces{&material, triangle_material};
  RecordingSink sink;
  OneStageMode<RecordingSink> mode{{0, 0, 0}, {0, 0, 1}, &sink};
  const PathSettings settings{-1, false, 1.0f, 1000};
  PathSettings limited = settings;
  limited.max_bounces = 5;
  const int kPaths = 100000;
  for (int p = 0; p < kPaths; ++p) {
    const PathStats stats = TracePath(scene, surfaces, limited, PathRandom(9, 0, p), mode);
    ASSERT_EQ(stats.end, PathEnd::kEscaped);
    ASSERT_EQ(stats.rays, 2u);
  }
  double total = 0;
  for (double v : sink.sum) total += v;
  EXPECT_NEAR(total / kPaths, 0.7 * kPi, 1e-6);
  double sky = 0;
  for (int b = 1; b < kTregenzaBinCount; ++b) sky += sink.sum[b];
  // Each path carries 0.7 pi; the choice is Bernoulli(6/7)
  const double p_sky = 0.6 / 0.7;
  const double se = 0.7 * kPi * std::sqrt(p_sky * (1 - p_sky) / kPaths);
  EXPECT_NEAR(sky / kPaths, 0.6 * kPi, 4 * se);
  EXPECT_NEAR(sink.sum[0] / kPaths, 0.1 * kPi, 4 * se);
  // Straight through the pane is the direct component; the reflected light is not
  for (int b = 1; b < kTregenzaBinCount; ++b) EXPECT_EQ(sink.unreflected[b], sink.sum[b]);
  EXPECT_EQ(sink.unreflected[0], 0.0);
}

// A plate with two faces of their own, top white (Lambertian 0.8) and bottom a mirror (0.9),
// or the other way round: a sensor under it facing up gets, all through the ground bin, what
// the bottom face sends down; one above it facing down gets, all through the sky, what the
// top sends up. Every path scatters once and escapes, so each sum is exact.
TEST(TracePathTest, TwoFacedPlateSendsEachFacesLight) {
  std::vector<Vec3f> vertices;
  AddSquare(vertices, 1e4f, 1.0f);   // bottom face: triangles 0, 1
  AddSquare(vertices, 1e4f, 1.01f);  // top face: triangles 2, 3
  const BruteForceIntersector scene{vertices.data(), 4};
  TraceMaterial mirror{0.0f, -1.0f};
  mirror.specular = 0.9f;
  const TraceMaterial materials[2] = {{0.8f, -1.0f}, mirror};
  const PathSettings settings{-1, false, 1.0f, 100};
  for (const bool mirror_below : {true, false}) {
    const uint32_t bottom = mirror_below ? 1 : 0, top = mirror_below ? 0 : 1;
    const uint32_t triangle_material[] = {bottom, bottom, top, top};
    const SurfaceTable surfaces{materials, triangle_material};
    const double below = mirror_below ? 0.9 : 0.8, above = mirror_below ? 0.8 : 0.9;
    for (const bool up : {true, false}) {
      RecordingSink sink;
      OneStageMode<RecordingSink> mode{{0, 0, up ? 0.0f : 2.0f}, {0, 0, up ? 1.0f : -1.0f}, &sink};
      const int kPaths = 20000;
      for (int p = 0; p < kPaths; ++p) {
        const PathStats stats = TracePath(scene, surfaces, settings, PathRandom(21, 0, p), mode);
        ASSERT_EQ(stats.end, PathEnd::kEscaped);
        ASSERT_EQ(stats.rays, 2u);
      }
      double sky = 0, unreflected = 0;
      for (int b = 1; b < kTregenzaBinCount; ++b) sky += sink.sum[b];
      for (int b = 0; b < kTregenzaBinCount; ++b) unreflected += sink.unreflected[b];
      EXPECT_NEAR(sink.sum[0] / kPaths, up ? below * kPi : 0.0, 1e-5);
      EXPECT_NEAR(sky / kPaths, up ? 0.0 : above * kPi, 1e-5);
      EXPECT_EQ(unreflected, 0.0);  // a mirror's light is reflected light
    }
  }
}

}  // namespace
}  // namespace fenestra
