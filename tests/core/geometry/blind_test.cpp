#include "core/geometry/blind.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "core/geometry/scene.h"

namespace fenestra {
namespace {

// The city office window: 2 x 1.5 m, outer face at y = 0.25, wall 0.25 m thick.
Window OfficeWindow() {
  Window w;
  w.center = {0, 0.25, 7.65};
  w.normal = {0, 1, 0};
  w.up = {0, 0, 1};
  w.across = Normalize(Cross(w.up, w.normal));
  w.width_m = 2;
  w.height_m = 1.5;
  w.depth_m = 0.25;
  return w;
}

BlindDesign Design(double tilt, double w, double s, double t) { return {true, tilt, w, s, t, {}}; }

TriangleMesh Slats(const BlindDesign& design, BlindLayout* layout = nullptr, BlindSpec spec = {}) {
  TriangleMesh mesh;
  const BlindLayout l = GenerateBlind(OfficeWindow(), spec, design, 0, mesh);
  if (layout) *layout = l;
  return mesh;
}

// Möller–Trumbore; true if the segment p + t d, t in (0, 1), crosses triangle i.
bool Crosses(const TriangleMesh& mesh, size_t i, Vec3d p, Vec3d d) {
  const Vec3d a = mesh.vertices[3 * i], e1 = mesh.vertices[3 * i + 1] - a,
              e2 = mesh.vertices[3 * i + 2] - a;
  const Vec3d q = Cross(d, e2);
  const double det = Dot(e1, q);
  if (std::abs(det) < 1e-15) return false;
  const Vec3d r = p - a;
  const double u = Dot(r, q) / det;
  const Vec3d k = Cross(r, e1);
  const double v = Dot(d, k) / det;
  const double t = Dot(e2, k) / det;
  return u >= 0 && v >= 0 && u + v <= 1 && t > 0 && t < 1;
}

TEST(BlindTest, SlatCountCoversTheWindowHeight) {
  struct Case {
    double w, s;
    int count;
  };
  for (const Case& c : {Case{0.15, 0, 10}, Case{0.10, 0.05, 11}, Case{0.05, 0.10, 11},
                        Case{0.13, 0.07, 8}, Case{0.05, 0, 30}, Case{2.0, 0, 1}}) {
    BlindLayout layout;
    const TriangleMesh mesh = Slats(Design(0, c.w, c.s, 0.01), &layout);
    EXPECT_EQ(layout.slat_count, c.count) << "w " << c.w << " s " << c.s;
    EXPECT_DOUBLE_EQ(layout.pitch_m, c.w + c.s);
    EXPECT_EQ(mesh.TriangleCount(), 12u * c.count);
    EXPECT_GE((layout.slat_count - 1) * layout.pitch_m + c.w, 1.5 - 1e-12);
  }
}

TEST(BlindTest, ClosedAtZeroTiltAndZeroSpacing) {
  const BlindDesign design = Design(0, 0.13, 0, 0.01);
  BlindLayout layout;
  const TriangleMesh mesh = Slats(design, &layout);
  // Straight lines through the opening (a point on its outer face, one on its inner face)
  // that cross the slat plane within the opening's extent must all hit a slat.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(-1, 1), uz(6.9, 8.4);
  int tested = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3d outer{ux(rng), 0.25, uz(rng)};
    const Vec3d inner{ux(rng), 0.0, uz(rng)};
    const Vec3d d = inner - outer;
    const double to_plane = (0.25 + layout.axis_depth_m) / 0.25;  // y = -axis_depth
    const Vec3d at_plane = outer + to_plane * d;
    if (std::abs(at_plane.x) > 1 || std::abs(at_plane.z - 7.65) > 0.75) continue;
    ++tested;
    const Vec3d end = outer + 4.0 * d;  // well inside the room
    bool hit = false;
    for (size_t t = 0; t < mesh.TriangleCount() && !hit; ++t)
      hit = Crosses(mesh, t, outer, end - outer);
    ASSERT_TRUE(hit) << "line through (" << outer.x << ", " << outer.z << ") and (" << inner.x
                     << ", " << inner.z << ") passes the closed blind";
  }
  EXPECT_GT(tested, 5000);
}

// Depth of a point behind the wall's inner face (y = 0), into the room.
double Depth(Vec3d v) { return -v.y; }

TEST(BlindTest, NoSlatReachesTheWallOrRevealsAtAnyTilt) {
  for (double w : {0.05, 0.15}) {
    for (double t : {0.01, 0.02}) {
      for (int i = 0; i <= 90; ++i) {
        const double tilt = i * std::numbers::pi / 180;
        const TriangleMesh mesh = Slats(Design(tilt, w, 0, t));
        for (const Vec3d& v : mesh.vertices) ASSERT_GE(Depth(v), 0.01 - 1e-12) << tilt;
      }
    }
  }
}

// Corners of slat k projected onto the cross-section plane (stack axis z, depth).
std::vector<std::pair<double, double>> Section(const TriangleMesh& mesh, int k) {
  std::vector<std::pair<double, double>> points;
  for (int i = 36 * k; i < 36 * (k + 1); ++i) {
    points.push_back({mesh.vertices[i].z, Depth(mesh.vertices[i])});
  }
  return points;
}

// Separating-axis test for two convex point sets; touching counts as separated.
bool Separated(const std::vector<std::pair<double, double>>& a,
               const std::vector<std::pair<double, double>>& b) {
  for (const auto* set : {&a, &b}) {
    for (size_t i = 0; i < set->size(); ++i) {
      for (size_t j = i + 1; j < set->size(); ++j) {
        const double ax = -((*set)[j].second - (*set)[i].second);
        const double ay = (*set)[j].first - (*set)[i].first;
        if (std::hypot(ax, ay) < 1e-9) continue;
        double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
        for (auto [x, y] : a)
          amin = std::min(amin, ax * x + ay * y), amax = std::max(amax, ax * x + ay * y);
        for (auto [x, y] : b)
          bmin = std::min(bmin, ax * x + ay * y), bmax = std::max(bmax, ax * x + ay * y);
        const double eps = 1e-12 * std::hypot(ax, ay);
        if (amax <= bmin + eps || bmax <= amin + eps) return true;
      }
    }
  }
  return false;
}

TEST(BlindTest, SlatsNeverOverlap) {
  for (double w : {0.05, 0.13, 0.15}) {
    for (double t : {0.01, 0.02}) {
      for (double s : {0.0, 0.03}) {
        for (int i = 0; i <= 180; ++i) {
          const double tilt = i * std::numbers::pi / 360;
          BlindLayout layout;
          const TriangleMesh mesh = Slats(Design(tilt, w, s, t), &layout);
          for (int k = 0; k + 1 < layout.slat_count; ++k) {
            ASSERT_TRUE(Separated(Section(mesh, k), Section(mesh, k + 1)))
                << "w " << w << " t " << t << " s " << s << " tilt " << tilt << " slat " << k;
          }
        }
      }
    }
  }
}

TEST(BlindTest, PerpendicularSlatsLeaveTheFullPitchOpen) {
  BlindLayout layout;
  const TriangleMesh mesh = Slats(Design(std::numbers::pi / 2, 0.15, 0, 0.01), &layout);
  EXPECT_DOUBLE_EQ(layout.pitch_m, 0.15);
  // Each slat is a horizontal plate t thick: its vertical extent is t
  for (int k = 0; k < layout.slat_count; ++k) {
    double lo = 1e300, hi = -1e300;
    for (auto [z, depth] : Section(mesh, k)) lo = std::min(lo, z), hi = std::max(hi, z);
    EXPECT_NEAR(hi - lo, 0.01, 1e-12);
  }
}

TEST(BlindTest, VerticalSlatsStackAcrossTheWindow) {
  BlindSpec spec;
  spec.vertical = true;
  BlindLayout layout;
  const TriangleMesh mesh = Slats(Design(0, 0.1, 0, 0.01), &layout, spec);
  EXPECT_EQ(layout.slat_count, 20);  // 2 m wide / 0.1 m
  for (const Vec3d& v : mesh.vertices) {
    EXPECT_GE(v.z, 6.9 - 1e-12);
    EXPECT_LE(v.z, 8.4 + 1e-12);
  }
}

// The outer material's faces (face 4, two triangles of every slat's twelve) face the window at
// tilt 0 and turn up as horizontal slats tilt towards π/2; the other broad face (5) the other
// way.
TEST(BlindTest, OuterMaterialFacesTheWindowThenTurnsUp) {
  BlindSpec spec;
  spec.material = 3;
  spec.outer_material = 7;
  for (const double tilt : {0.0, 0.5, std::numbers::pi / 2}) {
    BlindLayout layout;
    const TriangleMesh mesh = Slats(Design(tilt, 0.15, 0, 0.01), &layout, spec);
    ASSERT_EQ(mesh.TriangleCount(), 12u * layout.slat_count);
    for (int k = 0; k < layout.slat_count; ++k) {
      // Each face's centre, from the mean of its two triangles' vertices
      Vec3d centre[6] = {};
      for (int t = 0; t < kTrianglesPerSlat; ++t) {
        const size_t triangle = static_cast<size_t>(kTrianglesPerSlat * k + t);
        EXPECT_EQ(mesh.material[triangle], t / 2 == kSlatOuterFace ? 7u : 3u);
        for (int v = 0; v < 3; ++v) centre[t / 2] += mesh.vertices[3 * triangle + v] * (1.0 / 6);
      }
      // The outer face lies towards the window (+y) and up (+z) by the slat's thickness
      const Vec3d across = centre[kSlatOuterFace] - centre[5];
      EXPECT_NEAR(across.y, 0.01 * std::cos(tilt), 1e-12) << "tilt " << tilt << " slat " << k;
      EXPECT_NEAR(across.z, 0.01 * std::sin(tilt), 1e-12) << "tilt " << tilt << " slat " << k;
    }
  }
}

// A design's finish overrides the spec's materials on every slat, the outer broad faces taking
// its outer material and every other face its material; without one the spec's hold.
TEST(BlindTest, DesignFinishGivesTheSlatsItsMaterials) {
  BlindSpec spec;
  spec.material = 3;
  spec.outer_material = 7;
  EXPECT_EQ(FinishOf(spec, Design(0.5, 0.15, 0, 0.01)), (SlatFinish{3, 7}));
  for (const SlatFinish finish : {SlatFinish{1, 1}, SlatFinish{2, 5}, SlatFinish{5, 2}}) {
    BlindDesign design = Design(0.5, 0.15, 0.02, 0.01);
    design.finish = finish;
    EXPECT_EQ(FinishOf(spec, design), finish);
    BlindLayout layout;
    const TriangleMesh mesh = Slats(design, &layout, spec);
    ASSERT_EQ(mesh.TriangleCount(), 12u * layout.slat_count);
    std::map<uint32_t, size_t> per_material;
    for (size_t triangle = 0; triangle < mesh.TriangleCount(); ++triangle) {
      const int t = static_cast<int>(triangle % kTrianglesPerSlat);
      EXPECT_EQ(mesh.material[triangle],
                t / 2 == kSlatOuterFace ? finish.outer_material : finish.material);
      ++per_material[mesh.material[triangle]];
    }
    EXPECT_EQ(per_material.count(3) + per_material.count(7), 0u);
    // The same geometry as the spec's finish: only the materials differ
    const TriangleMesh plain = Slats(Design(0.5, 0.15, 0.02, 0.01), nullptr, spec);
    ASSERT_EQ(mesh.vertices.size(), plain.vertices.size());
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      EXPECT_EQ(Length(mesh.vertices[v] - plain.vertices[v]), 0.0);
    }
  }
  // Designs that differ only by their finish are different designs
  BlindDesign white = Design(0.5, 0.15, 0, 0.01), black = white;
  white.finish = SlatFinish{1, 1};
  black.finish = SlatFinish{0, 0};
  EXPECT_NE(white, black);
  EXPECT_NE(white, Design(0.5, 0.15, 0, 0.01));
}

// The envelope holds every slat of every design within the ranges, horizontal or vertical,
// tilted either way, and no more than it must along the depth.
TEST(BlindTest, EnvelopeHoldsTheBlindOfEveryDesignInRange) {
  std::mt19937 rng(3);
  for (const bool vertical : {false, true}) {
    BlindSpec spec;
    spec.vertical = vertical;
    spec.side_margin_m = 0.02;
    spec.tilt_rad = {0, -std::numbers::pi / 2, std::numbers::pi / 2};
    spec.slat_width_m = {0.15, 0.05, 0.15};
    spec.slat_spacing_m = {0, 0, 0.1};
    spec.slat_thickness_m = {0.01, 0.01, 0.02};
    const BlindEnvelope envelope = EnvelopeOfBlind(OfficeWindow(), spec, 0);
    double deepest = 0;
    for (int i = 0; i < 2000; ++i) {
      auto pick = [&](const ParameterRange& r) {
        return std::uniform_real_distribution<double>(r.min, r.max)(rng);
      };
      const BlindDesign design = Design(pick(spec.tilt_rad), pick(spec.slat_width_m),
                                        pick(spec.slat_spacing_m), pick(spec.slat_thickness_m));
      const TriangleMesh mesh = Slats(design, nullptr, spec);
      for (const Vec3d& v : mesh.vertices) {
        for (int k = 0; k < 3; ++k) {
          const double offset = Dot(v - envelope.center, envelope.axis[k]);
          ASSERT_LE(std::abs(offset), envelope.half_extent[k] + 1e-12)
              << "axis " << k << " vertical " << vertical << " tilt " << design.tilt_rad;
          if (k == 2) deepest = std::max(deepest, offset);
        }
      }
    }
    // The widest slats, tilted perpendicular to the wall, reach the back of the envelope
    EXPECT_GT(deepest, envelope.half_extent[2] - 0.01);
  }
}

}  // namespace
}  // namespace fenestra
