#include "core/geometry/hemisphere_basis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace fenestra {
namespace {

TEST(HemisphereBasisTest, Beckers288RingsAndLimits) {
  const HemisphereBasis b = Beckers288();
  ASSERT_EQ(b.ring_count, 11);
  EXPECT_EQ(b.cell_count, 288);
  const int expected[] = {1, 9, 22, 41, 65, 94, 128, 165, 205, 246, 288};
  for (int i = 0; i < 11; ++i) EXPECT_EQ(b.cumulative[i], expected[i]);
  // Outer limit of the cap: arccos(1 - 1/288) = 4.776 degrees
  EXPECT_NEAR(std::acos(1 - 1.0 / 288) * 180 / std::numbers::pi, 4.776, 1e-3);
}

// Solid angles sum to 2π, and a uniform sample of the hemisphere fills every cell equally.
void CheckEqualArea(const HemisphereBasis& b) {
  ASSERT_GT(b.cell_count, 0);
  EXPECT_NEAR(BasisCellSolidAngle(b) * b.cell_count, 2 * std::numbers::pi, 1e-12);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  const int per_cell = 400;
  std::vector<int> hits(b.cell_count, 0);
  for (int i = 0; i < per_cell * b.cell_count; ++i) {
    const double z = u(rng), phi = 2 * std::numbers::pi * u(rng), s = std::sqrt(1 - z * z);
    const int cell = BasisCell(b, Vec3d{s * std::cos(phi), s * std::sin(phi), z});
    ASSERT_GE(cell, 0);
    ASSERT_LT(cell, b.cell_count);
    ++hits[cell];
  }
  // Binomial counts: mean per_cell, sd ~ sqrt(per_cell) = 20; allow 5 sd
  for (int c = 0; c < b.cell_count; ++c)
    EXPECT_NEAR(hits[c], per_cell, 5 * std::sqrt(per_cell)) << c;
}

TEST(HemisphereBasisTest, Basis288IsEqualArea) { CheckEqualArea(Beckers288()); }

TEST(HemisphereBasisTest, Basis1152IsEqualArea) {
  const HemisphereBasis b = BeckersBasis(1152);
  EXPECT_EQ(b.cell_count, 1152);
  EXPECT_EQ(b.cumulative[b.ring_count - 1], 1152);
  EXPECT_GT(b.ring_count, 15);
  CheckEqualArea(b);
}

TEST(HemisphereBasisTest, SamplesStayInTheirCell) {
  for (const HemisphereBasis& b : {Beckers288(), BeckersBasis(1152)}) {
    std::mt19937_64 rng(2);
    std::uniform_real_distribution<double> u(0, 1);
    for (int cell = 0; cell < b.cell_count; ++cell) {
      for (int k = 0; k < 20; ++k) {
        for (const bool projected : {false, true}) {
          const Vec3d d = SampleBasisCell(b, cell, u(rng), u(rng), projected);
          EXPECT_NEAR(Length(d), 1, 1e-12);
          EXPECT_EQ(BasisCell(b, d), cell);
        }
      }
      EXPECT_EQ(BasisCell(b, BasisCellCenter(b, cell)), cell);
    }
  }
}

// In projected solid angle the density within a ring is proportional to cos θ: the mean
// cos θ of the samples is 2/3 (c1³ - c0³) / (c1² - c0²) for ring limits c0 < c1, against
// (c0 + c1) / 2 uniformly in solid angle. The outermost ring (cos θ from 0 to 0.146)
// differs most: 0.097 against 0.073. 20000 samples give the mean to about 0.0003.
TEST(HemisphereBasisTest, ProjectedSamplesFollowTheCosine) {
  const HemisphereBasis b = Beckers288();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  const int cell = 287;  // in the outermost ring
  const double c0 = 0, c1 = 42.0 / 288;
  for (const bool projected : {false, true}) {
    double mean = 0;
    const int n = 20000;
    for (int k = 0; k < n; ++k) mean += SampleBasisCell(b, cell, u(rng), u(rng), projected).z / n;
    const double expected =
        projected ? 2.0 / 3 * (c1 * c1 * c1 - c0 * c0 * c0) / (c1 * c1 - c0 * c0) : (c0 + c1) / 2;
    EXPECT_NEAR(mean, expected, 0.001) << (projected ? "projected" : "solid angle");
  }
}

TEST(HemisphereBasisTest, BelowTheHorizonHasNoCell) {
  const HemisphereBasis b = Beckers288();
  EXPECT_EQ(BasisCell(b, Vec3d{1, 0, 0}), -1);
  EXPECT_EQ(BasisCell(b, Vec3d{0, 0, -1}), -1);
  EXPECT_EQ(BasisCell(b, Vec3d{0, 0, 0}), -1);
  EXPECT_EQ(BasisCell(b, Vec3d{0, 0, 1}), 0);
  EXPECT_EQ(BasisCell(b, Vec3f{0.f, 0.f, 1.f}), 0);
}

}  // namespace
}  // namespace fenestra
