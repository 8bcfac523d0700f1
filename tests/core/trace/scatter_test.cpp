#include "core/trace/scatter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/trace/brute_force_intersector.h"
#include "core/trace/path.h"

namespace fenestra {
namespace {

const Vec3f kUp{0, 0, 1};

Vec3f Direction(double theta, double phi) {
  return Vec3f{static_cast<float>(std::sin(theta) * std::cos(phi)),
               static_cast<float>(std::sin(theta) * std::sin(phi)),
               static_cast<float>(std::cos(theta))};
}

TraceMaterial Glossy(float diffuse, float specular, float roughness) {
  TraceMaterial m{diffuse, -1.0f};
  m.specular = specular;
  m.roughness = roughness;
  if (roughness > kMirrorRoughness) m.energy = LobeEnergyOf(roughness);
  return m;
}

// The integral over the sphere of Value (/ pi) and of its density, by the midpoint rule on
// a grid fine enough for a lobe of roughness `alpha`. In polar angle: equal steps up to
// kSteepAngle from the pole, then equal steps in t = sqrt|cos theta| to the horizon, where
// Ward's lobe (1 / sqrt(cos_i cos_o)) makes Value grow as sqrt|cos theta|. In azimuth: equal
// steps in s with phi = phi_mirror + pi s^3 (s in [-1, 1]), close together around the mirror
// direction's azimuth, where a grazing lobe is a few milliradians wide.
struct Integrals {
  double albedo = 0, density = 0;
};
constexpr double kSteepAngle = 1.2;
Integrals Integrate(const SurfaceScatter& s, float alpha) {
  const int rings = s.lobe > 0.0f ? std::max(300, static_cast<int>(40 / alpha)) : 200;
  const int sectors = 2 * rings;
  Integrals out;
  const double mirror = std::atan2(s.view.y, s.view.x) + kPi;
  // One ring between |cos theta| = c0 > c1, sampled at |cos theta| = mid, on both hemispheres
  const auto ring = [&](double c0, double c1, double mid) {
    for (const double theta : {std::acos(mid), kPi - std::acos(mid)}) {
      for (int j = 0; j < sectors; ++j) {
        const double t = -1.0 + 2.0 * (j + 0.5) / sectors;
        const double cell = (c0 - c1) * 3 * kPi * t * t * 2.0 / sectors;
        float pdf;
        const double value = s.Value(Direction(theta, mirror + kPi * t * t * t), &pdf);
        out.albedo += value / kPi * cell;
        out.density += pdf * cell;
      }
    }
  };
  const int steep = static_cast<int>(rings * kSteepAngle / (kPi / 2));
  for (int i = 0; i < steep; ++i) {
    const double t0 = kSteepAngle * i / steep, t1 = kSteepAngle * (i + 1) / steep;
    ring(std::cos(t0), std::cos(t1), std::cos(0.5 * (t0 + t1)));
  }
  const double edge = std::sqrt(std::cos(kSteepAngle));
  for (int i = 0; i < rings; ++i) {
    const double t0 = edge * (rings - i) / rings, t1 = edge * (rings - i - 1) / rings;
    ring(t0 * t0, t1 * t1, 0.25 * (t0 + t1) * (t0 + t1));
  }
  return out;
}

struct Mean {
  double mean = 0, standard_error = 0, largest = 0;
};

// The mean of Sample's factor over `count` draws (fixed seed), the directional albedo.
Mean SampledAlbedo(const SurfaceScatter& s, int count, uint64_t seed) {
  const PathRandom random(seed, 0, 0);
  double sum = 0, squares = 0, largest = 0;
  for (int k = 0; k < count; ++k) {
    const ScatterSample sample = Sample(s, random.Draw(k, 0));
    sum += sample.factor, squares += double{sample.factor} * sample.factor;
    largest = std::max<double>(largest, sample.factor);
  }
  const double mean = sum / count;
  return {mean, std::sqrt((squares / count - mean * mean) / (count - 1)), largest};
}

// A Lambertian surface is what it was: every draw weighs its reflectance, with the cosine
// density, and connects with rho cos.
TEST(ScatterTest, LambertianAsBefore) {
  const TraceMaterial m{0.6f, -1.0f};
  const SurfaceScatter s = ScatterAt(m, kUp, Direction(0.4, 1.0));
  const PathRandom random(1, 0, 0);
  for (int k = 0; k < 1000; ++k) {
    const ScatterSample sample = Sample(s, random.Draw(k, 0));
    ASSERT_FLOAT_EQ(sample.factor, 0.6f);
    ASSERT_NEAR(sample.pdf, sample.direction.z / kPi, 1e-6);
    ASSERT_TRUE(sample.scatters);
    ASSERT_FALSE(sample.through);
  }
  float pdf;
  EXPECT_FLOAT_EQ(s.Value(Direction(0.3, 2.0), &pdf), 0.6f * std::cos(0.3f));
  EXPECT_FLOAT_EQ(pdf, std::cos(0.3f) / kPiF);
  EXPECT_EQ(s.Value(Direction(2.0, 2.0), &pdf), 0.0f);
}

// Each draw's density is the one Value gives for its direction, and Value's density
// integrates to the smooth parts' share of the draws (the lobe's below-surface part aside).
TEST(ScatterTest, SampleDensityIsValuesDensity) {
  TraceMaterial m = Glossy(0.2f, 0.5f, 0.1f);
  m.through = 0.15f;
  m.transmittance = 0.1f;
  m.straight_scatters = true;
  const SurfaceScatter s = ScatterAt(m, kUp, Direction(0.5, 0.3));
  const PathRandom random(2, 0, 0);
  int smooth = 0;
  for (int k = 0; k < 20000; ++k) {
    const ScatterSample sample = Sample(s, random.Draw(k, 0));
    if (sample.straight) {
      ASSERT_EQ(sample.pdf, 0.0f);
      ASSERT_TRUE(sample.scatters);  // trans's straight pass is a scattering event
      continue;
    }
    if (!(sample.factor > 0.0f)) continue;
    float pdf;
    s.Value(sample.direction, &pdf);
    ASSERT_NEAR(sample.pdf, pdf, 1e-5 * pdf);
    ++smooth;
  }
  EXPECT_GT(smooth, 15000);
  const Integrals integrals = Integrate(s, 0.1f);
  // Diffuse parts integrate exactly; the lobe loses what its half vectors reflect below
  const double diffuse_share = (0.2 + 0.15) / 0.95, lobe_share = 0.5 / 0.95;
  EXPECT_GT(integrals.density, diffuse_share + 0.9 * lobe_share);
  EXPECT_LT(integrals.density, diffuse_share + lobe_share + 1e-3);
}

// The factor's mean is the surface's directional albedo, the integral of Value: mixture
// estimator and evaluation agree at any roughness and angle (within 4 standard errors).
TEST(ScatterTest, SampledAlbedoIsValuesIntegral) {
  for (float roughness : {0.05f, 0.2f, 0.5f}) {
    for (double theta : {0.0, 0.7, 1.3, 1.55}) {
      TraceMaterial m = Glossy(0.3f, 0.6f, roughness);
      m.through = 0.05f;
      const SurfaceScatter s = ScatterAt(m, kUp, Direction(theta, 0.0));
      const Integrals integrals = Integrate(s, roughness);
      const Mean sampled = SampledAlbedo(s, 200000, 7);
      EXPECT_NEAR(sampled.mean, integrals.albedo, 4 * sampled.standard_error + 2e-4)
          << "roughness " << roughness << " theta " << theta;
      // No draw weighs much more than the albedo, at grazing incidence too: the lost light is
      // drawn as it is spread
      EXPECT_LT(sampled.largest, 2.5) << "roughness " << roughness << " theta " << theta;
      // The lobe and what it loses reflect the specular part exactly
      EXPECT_NEAR(integrals.albedo, 0.95, 2e-3) << "roughness " << roughness << " theta " << theta;
    }
  }
}

// Reciprocity: pi f(v, l) = pi f(l, v), Value divided by the cosine of its argument.
TEST(ScatterTest, ValueIsReciprocal) {
  const PathRandom random(3, 0, 0);
  int compared = 0;
  for (int k = 0; k < 5000; ++k) {
    const Uniform4 u = random.Draw(k, 0);
    const Vec3f v = Direction(std::acos(u.u[0]), 2 * kPi * u.u[1]);
    const Vec3f l = Direction(std::acos(u.u[2]), 2 * kPi * u.u[3]);
    const TraceMaterial m = Glossy(0.1f, 0.8f, 0.3f);
    float pdf;
    const double a = ScatterAt(m, kUp, v).Value(l, &pdf) / l.z;
    const double b = ScatterAt(m, kUp, l).Value(v, &pdf) / v.z;
    ASSERT_NEAR(a, b, 1e-5 * std::max(a, 1.0));
    compared += a > 0.2;  // more than the diffuse part
  }
  EXPECT_GT(compared, 500);
}

// Roughness at or below kMirrorRoughness (0 and 1e-4) is a mirror: the reflected direction,
// the full specular weight, no density (no connection reaches it), finite.
TEST(ScatterTest, SmoothLobesAreMirrors) {
  for (float roughness : {0.0f, 1e-4f, kMirrorRoughness}) {
    const Vec3f v = Direction(1.2, 0.5);
    const TraceMaterial m = Glossy(0.0f, 0.9f, roughness);
    const SurfaceScatter s = ScatterAt(m, kUp, v);
    EXPECT_EQ(s.lobe, 0.0f);
    EXPECT_FLOAT_EQ(s.mirror, 0.9f);
    EXPECT_FALSE(s.Smooth());
    const ScatterSample sample = Sample(s, Uniform4{{0.3f, 0.6f, 0.5f, 0.5f}});
    EXPECT_FLOAT_EQ(sample.factor, 0.9f);
    EXPECT_EQ(sample.pdf, 0.0f);
    EXPECT_NEAR(sample.direction.x, -v.x, 1e-6);
    EXPECT_NEAR(sample.direction.y, -v.y, 1e-6);
    EXPECT_NEAR(sample.direction.z, v.z, 1e-6);
  }
  // Just above: a lobe, still finite, its draws near the mirror direction
  const Vec3f v = Direction(0.6, 0.0);
  const TraceMaterial m = Glossy(0.0f, 0.9f, 2e-3f);
  const SurfaceScatter s = ScatterAt(m, kUp, v);
  const Mean sampled = SampledAlbedo(s, 20000, 11);
  EXPECT_TRUE(std::isfinite(sampled.mean));
  EXPECT_NEAR(sampled.mean, 0.9, 0.01);
  EXPECT_LT(sampled.standard_error, 1e-3);  // the factor varies by under 1%
}

// Glass: Fresnel reflection as a mirror and straight transmission, by the angle.
TEST(ScatterTest, GlassByTheAngle) {
  TraceMaterial m{0.0f, 0.88f};
  m.glass = GlassPane::TransmissivityFor(0.88f);
  for (double theta : {0.0, 0.8, 1.4}) {
    const SurfaceScatter s = ScatterAt(m, kUp, Direction(theta, 0.0));
    const GlassPane pane{m.glass};
    const float c = static_cast<float>(std::cos(theta));
    EXPECT_FLOAT_EQ(s.straight, pane.Transmittance(c));
    EXPECT_FLOAT_EQ(s.mirror, pane.Reflectance(c));
    EXPECT_FLOAT_EQ(StraightTransmittance(m, c), pane.Transmittance(c));
    EXPECT_FALSE(s.Smooth());
  }
  EXPECT_NEAR(StraightTransmittance(m, 1.0f), 0.88f, 1e-4);
}

// Counts what a closed box's paths carry into each vertex: with roulette the mean is the sum
// over k of the albedo to the k-th power, 1 / (1 - albedo), whatever the geometry, when the
// albedo is the same at every angle: Lambertian and mirror parts, and a Ward lobe with the
// light it loses given back (lobe_energy.h), any mix.
struct FurnaceMode {
  double carried = 0;
  template <class Intersector>
  PathState Start(const Intersector&, const PathRandom& random) const {
    const Uniform4 u = random.Draw(0, 0);
    return PathState{{0.1f, 0.2f, 0.3f}, SampleCosineHemisphere(kUp, u.u[0], u.u[1]), 1.0f, 0, 0};
  }
  template <class Intersector>
  void AtReflection(const Intersector&, const PathState& path, const ReflectionVertex&,
                    const PathRandom&) {
    carried += path.weight;
  }
  void Escape(const PathState&) { ADD_FAILURE() << "a ray left the closed box"; }
  void Finish(const PathStats&) {}
};

std::vector<Vec3f> BoxTriangles() {
  const Vec3f p[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                      {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
  const int quads[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 2, 6, 5}};
  std::vector<Vec3f> v;
  for (const auto& q : quads)
    v.insert(v.end(), {p[q[0]], p[q[1]], p[q[2]], p[q[0]], p[q[2]], p[q[3]]});
  return v;
}

TEST(ScatterTest, WhiteFurnaceAtAnySpecularityAndRoughness) {
  const std::vector<Vec3f> vertices = BoxTriangles();
  const BruteForceIntersector scene{vertices.data(), 12};
  const uint32_t triangle_material[12] = {};
  constexpr float kEpsilon = 0.05f;
  for (float specular : {0.0f, 0.3f, 0.9f, 0.94f}) {
    for (float roughness : {0.0f, 1e-4f, 0.05f, 0.2f, 0.5f}) {
      const TraceMaterial m = Glossy(1.0f - kEpsilon - specular, specular, roughness);
      const SurfaceTable surfaces{&m, triangle_material};
      const PathSettings settings{kUnlimitedBounces, true, 1.0f, 1u << 16};
      const int kPaths = 40000;
      double sum = 0, squares = 0;
      for (int p = 0; p < kPaths; ++p) {
        FurnaceMode mode;
        const PathStats stats = TracePath(scene, surfaces, settings, PathRandom(13, 0, p), mode);
        ASSERT_NE(stats.end, PathEnd::kTruncated);
        sum += mode.carried, squares += mode.carried * mode.carried;
      }
      const double mean = sum / kPaths;
      const double se = std::sqrt((squares / kPaths - mean * mean) / (kPaths - 1));
      EXPECT_NEAR(mean, 1.0 / kEpsilon, 4 * se) << specular << " " << roughness;
    }
  }
}

// Sums what each path scores, and the squares of those sums.
struct CeilingSink {
  double path = 0, sum = 0, squares = 0;
  void Add(int, double value) { path += value; }
  void EndPath() {
    sum += path, squares += path * path;
    path = 0;
  }
};

// The lobe's energy along whole paths: an upward sensor under an endless ceiling of material
// m sees, after one scattering, what the ceiling sends back down (to the ground bin) and on
// up (the sky): pi times the ceiling's albedo averaged over the sensor's cosine-weighted
// view, here by quadrature of Value, at several roughnesses (within 4 standard errors).
TEST(ScatterTest, CeilingReturnsItsAlbedoAtAnyRoughness) {
  std::vector<Vec3f> vertices;
  const float half = 1e5f;
  vertices.insert(vertices.end(), {{-half, -half, 1},
                                   {half, -half, 1},
                                   {half, half, 1},
                                   {-half, -half, 1},
                                   {half, half, 1},
                                   {-half, half, 1}});
  const BruteForceIntersector scene{vertices.data(), 2};
  const uint32_t triangle_material[2] = {};
  for (float roughness : {0.0f, 0.05f, 0.2f, 0.5f}) {
    TraceMaterial m = Glossy(0.1f, 0.8f, roughness);
    m.through = 0.05f;
    const SurfaceTable surfaces{&m, triangle_material};
    // The expected value: the cosine-weighted mean over incidence of the directional albedo
    const Vec3f down{0, 0, -1};
    double expected = 0, weight = 0;
    const int angles = 24;
    for (int i = 0; i < angles; ++i) {
      const double theta = 0.5 * kPi * (i + 0.5) / angles;
      const double w = std::cos(theta) * std::sin(theta);
      // The ray arrives going up at angle theta: the ceiling's normal faces down
      const SurfaceScatter s = ScatterAt(m, down, Direction(theta, 0.0) * -1.0f);
      expected += w * (Integrate(s, roughness).albedo + s.mirror + s.straight);
      weight += w;
    }
    expected /= weight;
    CeilingSink sink;
    OneStageMode<CeilingSink> mode{{0, 0, 0}, kUp, &sink};
    const PathSettings settings{1, false, 1.0f, 16};
    const int kPaths = 200000;
    for (int p = 0; p < kPaths; ++p) {
      TracePath(scene, surfaces, settings, PathRandom(17, 0, p), mode);
    }
    const double mean = sink.sum / kPaths / kPi;
    const double se =
        std::sqrt(std::max(0.0, sink.squares / kPaths / (kPi * kPi) - mean * mean) / kPaths);
    EXPECT_NEAR(mean, expected, 4 * se + 1e-3) << "roughness " << roughness;
  }
}

}  // namespace
}  // namespace fenestra
