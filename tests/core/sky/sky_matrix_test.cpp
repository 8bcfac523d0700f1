#include "core/sky/sky_matrix.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>

#include "tests/core/sky/epw_fixture.h"

namespace fenestra {
namespace {

using ::fenestra::testing::ConstantYearEpw;
using ::fenestra::testing::Step;
using ::fenestra::testing::Weather;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

const std::string kMontevideo =
    FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw";
const std::string kReference = FENESTRA_SOURCE_DIR "/tests/data/reference/";

// Reads a gzipped one-component ASCII Radiance matrix.
absl::StatusOr<Matrix> ReadGzippedMatrix(const std::string& path) {
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) return absl::NotFoundError(path);
  std::string text;
  char buffer[1 << 16];
  int n;
  while ((n = gzread(file, buffer, sizeof buffer)) > 0) text.append(buffer, n);
  gzclose(file);
  long rows = 0, cols = 0;
  size_t pos = 0;
  for (;;) {
    const size_t end = text.find('\n', pos);
    if (end == std::string::npos) return absl::DataLossError(path + ": no header end");
    const std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    if (line.empty()) break;
    std::sscanf(line.c_str(), "NROWS=%ld", &rows);
    std::sscanf(line.c_str(), "NCOLS=%ld", &cols);
  }
  Matrix m(rows, cols);
  const char* cursor = text.c_str() + pos;
  for (long i = 0; i < rows * cols; ++i) {
    char* next;
    m.data()[i] = std::strtod(cursor, &next);
    if (next == cursor) return absl::DataLossError(path + ": short data");
    cursor = next;
  }
  return m;
}

// Sky radiance integrated over the sky patches, sum of L_i Omega_i [W/m2 of the quantity].
double SkyFlux(const SkyPatches& patches, const Matrix& m, int column) {
  double sum = 0;
  for (int bin = 1; bin < patches.size(); ++bin) {
    sum += m(bin, column) * patches[bin].solid_angle_sr;
  }
  return sum;
}

void ExpectFiniteAndNonNegative(const SkyMatrix& sky) {
  for (Eigen::Index c = 0; c < sky.radiance.cols(); ++c) {
    for (Eigen::Index r = 0; r < sky.radiance.rows(); ++r) {
      ASSERT_TRUE(std::isfinite(sky.radiance(r, c))) << "row " << r << " column " << c;
      ASSERT_GE(sky.radiance(r, c), 0) << "row " << r << " column " << c;
    }
  }
}

absl::StatusOr<SkyMatrix> SkyOf(const std::string& epw_text, const SkyMatrixOptions& options = {}) {
  absl::StatusOr<EpwData> epw = ParseEpw(epw_text, "fixture.epw");
  if (!epw.ok()) return epw.status();
  return BuildSkyMatrix(*epw, options);
}

absl::StatusOr<SkyMatrix> SkyOf(const EpwData& weather, const SkyMatrixOptions& options = {}) {
  return BuildSkyMatrix(weather, options);
}

class GendaymtxReferenceTest : public ::testing::TestWithParam<SkyQuantity> {};

// Compares with gendaymtx -m 1 -c 1 1 1 -g 0.2 0.2 0.2 -r 0 -O0 (visible) / -O1 (solar).
TEST_P(GendaymtxReferenceTest, MatchesMontevideo) {
  const bool solar = GetParam() == SkyQuantity::kSolar;
  absl::StatusOr<EpwData> epw = ReadEpw(kMontevideo);
  ASSERT_TRUE(epw.ok()) << epw.status();
  absl::StatusOr<SkyMatrix> sky = BuildSkyMatrix(*epw, {.quantity = GetParam()});
  ASSERT_TRUE(sky.ok()) << sky.status();
  absl::StatusOr<Matrix> reference = ReadGzippedMatrix(
      kReference + (solar ? "montevideo_sky_mf1_sol.mtx.gz" : "montevideo_sky_mf1_vis.mtx.gz"));
  ASSERT_TRUE(reference.ok()) << reference.status();
  const Matrix& ours = sky->radiance;
  ASSERT_EQ(ours.rows(), 146);
  ASSERT_EQ(ours.cols(), 8760);
  ASSERT_EQ(reference->rows(), 146);
  ASSERT_EQ(reference->cols(), 8760);

  // Per patch-hour, where the value is above 1% of its column's maximum
  double worst = 0;
  int worst_row = -1, worst_col = -1;
  int reference_daytime = 0;
  for (int c = 0; c < 8760; ++c) {
    const double column_max = reference->col(c).maxCoeff();
    if (column_max <= 0) {
      EXPECT_FALSE(sky->steps[c].daytime) << "column " << c;
      EXPECT_EQ(ours.col(c).maxCoeff(), 0) << "column " << c;
      continue;
    }
    ++reference_daytime;
    EXPECT_TRUE(sky->steps[c].daytime) << "column " << c;
    for (int r = 0; r < 146; ++r) {
      const double ref = (*reference)(r, c);
      if (ref <= 0.01 * column_max) continue;
      const double difference = std::fabs(ours(r, c) - ref) / ref;
      if (difference > worst) {
        worst = difference;
        worst_row = r;
        worst_col = c;
      }
    }
  }
  EXPECT_EQ(sky->daytime_steps, reference_daytime);
  ASSERT_GE(worst_col, 0);
  std::printf(
      "%s: worst patch-hour difference %.4f%%: value %.6g, reference %.6g, "
      "column %d (%d/%d %.1f h), row %d\n",
      solar ? "solar" : "visible", 100 * worst, ours(worst_row, worst_col),
      (*reference)(worst_row, worst_col), worst_col, sky->steps[worst_col].month,
      sky->steps[worst_col].day, sky->steps[worst_col].hour, worst_row);
  EXPECT_LE(worst, 0.01);

  // Annual sum of every row
  double worst_sum = 0;
  int worst_sum_row = -1;
  for (int r = 0; r < 146; ++r) {
    const double ref = reference->row(r).sum();
    const double difference = std::fabs(ours.row(r).sum() - ref) / ref;
    if (difference > worst_sum) {
      worst_sum = difference;
      worst_sum_row = r;
    }
  }
  std::printf("%s: worst annual row-sum difference %.4f%% (row %d)\n", solar ? "solar" : "visible",
              100 * worst_sum, worst_sum_row);
  EXPECT_LE(worst_sum, 0.005);
}

INSTANTIATE_TEST_SUITE_P(Quantities, GendaymtxReferenceTest,
                         ::testing::Values(SkyQuantity::kVisible, SkyQuantity::kSolar),
                         [](const auto& param_info) {
                           return param_info.param == SkyQuantity::kSolar ? "Solar" : "Visible";
                         });

TEST(SkyMatrixTest, StepCentres) {
  EpwRecord r;
  r.hour = 13;
  r.minute = 60;
  EXPECT_DOUBLE_EQ(StepCentreHours(r, 1), 12.5);
  r.minute = 0;  // hourly files are centred whatever the minute field says
  EXPECT_DOUBLE_EQ(StepCentreHours(r, 1), 12.5);
  r.minute = 15;
  EXPECT_DOUBLE_EQ(StepCentreHours(r, 4), 12.125);
  r.minute = 60;
  EXPECT_DOUBLE_EQ(StepCentreHours(r, 4), 12.875);
  r.minute = 30;
  EXPECT_DOUBLE_EQ(StepCentreHours(r, 2), 12.25);
}

TEST(SkyMatrixTest, SubHourlyFile) {
  std::vector<EpwRecord> steps;
  for (int hour = 12; hour <= 13; ++hour) {
    for (int minute : {15, 30, 45, 60}) steps.push_back(Step(6, 21, hour, 400, 100, minute));
  }
  const EpwData weather = Weather(-34.83, -56.0, -3, steps, 4);
  absl::StatusOr<SkyMatrix> sky = SkyOf(weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  ASSERT_EQ(sky->steps.size(), 8u);
  EXPECT_DOUBLE_EQ(sky->steps[0].hour, 11.125);
  EXPECT_DOUBLE_EQ(sky->steps[7].hour, 12.875);
  EXPECT_EQ(sky->daytime_steps, 8);
  // The sun climbs towards its noon (about 12:45 standard time)
  EXPECT_LT(sky->steps[0].solar_altitude_rad, sky->steps[6].solar_altitude_rad);
  ExpectFiniteAndNonNegative(*sky);
}

TEST(SkyMatrixTest, LeapDayShiftsLaterDays) {
  absl::StatusOr<EpwData> epw = ReadEpw(FENESTRA_SOURCE_DIR "/tests/data/sky/leap_day.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  absl::StatusOr<SkyMatrix> sky = BuildSkyMatrix(*epw);
  ASSERT_TRUE(sky.ok()) << sky.status();
  EXPECT_EQ(sky->steps[0].day_of_year, 59);   // Feb 28
  EXPECT_EQ(sky->steps[24].day_of_year, 60);  // Feb 29
  EXPECT_EQ(sky->steps[48].day_of_year, 61);  // Mar 1, one later than in a common year
  ExpectFiniteAndNonNegative(*sky);
}

TEST(SkyMatrixTest, NightColumnsAreZeroAndFlagged) {
  const EpwData weather =
      Weather(45, 7, 1, {Step(6, 21, 1, 0, 0), Step(6, 21, 13, 700, 120), Step(6, 21, 23, 0, 0)});
  absl::StatusOr<SkyMatrix> sky = SkyOf(weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  EXPECT_EQ(sky->daytime_steps, 1);
  EXPECT_FALSE(sky->steps[0].daytime);
  EXPECT_TRUE(sky->steps[1].daytime);
  EXPECT_FALSE(sky->steps[2].daytime);
  EXPECT_EQ(sky->radiance.col(0).cwiseAbs().maxCoeff(), 0);
  EXPECT_EQ(sky->radiance.col(2).cwiseAbs().maxCoeff(), 0);
  EXPECT_GT(sky->radiance.col(1).minCoeff(), 0);
  EXPECT_FALSE(sky->steps[0].sun_in_sky);
  EXPECT_TRUE(sky->steps[1].sun_in_sky);
}

TEST(SkyMatrixTest, AllZeroRadiation) {
  absl::StatusOr<SkyMatrix> sky = SkyOf(ConstantYearEpw(45, 7, 1, 0, 0));
  ASSERT_TRUE(sky.ok()) << sky.status();
  EXPECT_EQ(sky->radiance.cols(), 8760);
  EXPECT_EQ(sky->daytime_steps, 0);
  EXPECT_EQ(sky->radiance.cwiseAbs().maxCoeff(), 0);
  for (const SkyStep& step : sky->steps) EXPECT_FALSE(step.daytime);
}

// Energy bookkeeping of one column: the sky patches carry the diffuse illuminance, the sun
// patches carry the direct normal flux, the ground reflects both.
TEST(SkyMatrixTest, ColumnConservesTheInput) {
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  const EpwData weather = Weather(45, 7, 1, {Step(6, 21, 13, 700, 120)});
  for (SkyQuantity quantity : {SkyQuantity::kSolar, SkyQuantity::kVisible}) {
    absl::StatusOr<SkyMatrix> all = SkyOf(weather, {.quantity = quantity});
    absl::StatusOr<SkyMatrix> sky_only =
        SkyOf(weather, {.quantity = quantity, .include_sun = false});
    absl::StatusOr<SkyMatrix> sun_only =
        SkyOf(weather, {.quantity = quantity, .include_sky = false});
    ASSERT_TRUE(all.ok() && sky_only.ok() && sun_only.ok());
    const double alt = all->steps[0].solar_altitude_rad;
    const PerezSkyCondition c =
        ComputePerezSkyCondition(700, 120, alt, all->steps[0].day_of_year, 10, quantity);

    EXPECT_NEAR(SkyFlux(*patches, sun_only->radiance, 0) * kWhiteEfficacyLmPerW,
                c.direct_illuminance, 1e-9 * c.direct_illuminance);
    EXPECT_EQ(sun_only->radiance(0, 0), 0);
    double horizontal = 0;
    for (int bin = 1; bin < 146; ++bin) {
      horizontal += sky_only->radiance(bin, 0) * std::sin((*patches)[bin].altitude_rad) *
                    (*patches)[bin].solid_angle_sr;
    }
    EXPECT_NEAR(horizontal * kWhiteEfficacyLmPerW, c.diffuse_illuminance,
                1e-9 * c.diffuse_illuminance);
    const double ground = 0.2 * (c.diffuse_illuminance + c.direct_illuminance * std::sin(alt)) /
                          (kPi * kWhiteEfficacyLmPerW);
    EXPECT_NEAR(all->radiance(0, 0), ground, 1e-12 * ground);
    EXPECT_NEAR(sky_only->radiance(0, 0), ground, 1e-12 * ground);
    for (int bin = 0; bin < 146; ++bin) {
      EXPECT_NEAR(all->radiance(bin, 0), sky_only->radiance(bin, 0) + sun_only->radiance(bin, 0),
                  1e-12 * all->radiance(bin, 0));
    }
  }
  // Solar output: the sky patches give back the measured diffuse irradiance.
  absl::StatusOr<SkyMatrix> solar = SkyOf(weather, {.quantity = SkyQuantity::kSolar});
  ASSERT_TRUE(solar.ok());
  double horizontal = 0;
  for (int bin = 1; bin < 146; ++bin) {
    horizontal += solar->radiance(bin, 0) * std::sin((*patches)[bin].altitude_rad) *
                  (*patches)[bin].solid_angle_sr;
  }
  // Sky plus sun patches, horizontal: about diffuse + direct sin(alt).
  const double alt = solar->steps[0].solar_altitude_rad;
  EXPECT_NEAR(horizontal, 120 + 700 * std::sin(alt), 0.03 * (120 + 700 * std::sin(alt)));
}

TEST(SkyMatrixTest, GroundReflectance) {
  const EpwData weather = Weather(45, 7, 1, {Step(6, 21, 13, 700, 120)});
  absl::StatusOr<SkyMatrix> a = SkyOf(weather, {.ground_reflectance = 0.2});
  absl::StatusOr<SkyMatrix> b = SkyOf(weather, {.ground_reflectance = 0.5});
  absl::StatusOr<SkyMatrix> black = SkyOf(weather, {.ground_reflectance = 0});
  ASSERT_TRUE(a.ok() && b.ok() && black.ok());
  EXPECT_NEAR(b->radiance(0, 0), 2.5 * a->radiance(0, 0), 1e-12);
  EXPECT_EQ(black->radiance(0, 0), 0);
  EXPECT_EQ(a->radiance(77, 0), b->radiance(77, 0));
  EXPECT_FALSE(SkyOf(weather, {.ground_reflectance = 1.5}).ok());
  EXPECT_FALSE(SkyOf(weather, {.ground_reflectance = -0.1}).ok());
  EXPECT_FALSE(SkyOf(weather, {.mf = 0}).ok());
}

TEST(SkyMatrixTest, DiffuseZeroDirectPositive) {
  const EpwData weather = Weather(45, 7, 1, {Step(6, 21, 13, 800, 0)});
  absl::StatusOr<SkyMatrix> sky = SkyOf(weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  ExpectFiniteAndNonNegative(*sky);
  EXPECT_EQ(sky->daytime_steps, 1);
  // Only the 4 sun patches and the ground are lit
  int lit = 0;
  for (int bin = 1; bin < 146; ++bin) lit += sky->radiance(bin, 0) > 0;
  EXPECT_EQ(lit, 4);
  EXPECT_GT(sky->radiance(0, 0), 0);
  const int sun_bin = TregenzaBin(
      DirectionFromAltAz(sky->steps[0].solar_altitude_rad, sky->steps[0].solar_azimuth_rad));
  EXPECT_GT(sky->radiance(sun_bin, 0), 0);
}

TEST(SkyMatrixTest, DirectWithSunBelowHorizon) {
  // 23:00-24:00 in June at 45 N: the sun is well below the horizon.
  const EpwData weather =
      Weather(45, 7, 1, {Step(6, 21, 24, 300, 0), Step(6, 21, 23, 300, 40), Step(6, 21, 22, 0, 5)});
  absl::StatusOr<SkyMatrix> sky = SkyOf(weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  ExpectFiniteAndNonNegative(*sky);
  EXPECT_EQ(sky->direct_with_sun_down_steps, 2);
  for (int c = 0; c < 3; ++c) {
    EXPECT_LT(sky->steps[c].solar_altitude_rad, -5 * kDeg);
    EXPECT_TRUE(sky->steps[c].daytime);
  }
  // Like gendaymtx, the sun goes to the patches nearest its direction: the horizon row.
  for (int bin = 31; bin < 146; ++bin) EXPECT_EQ(sky->radiance(bin, 0), 0) << bin;
  double horizon = 0;
  for (int bin = 1; bin <= 30; ++bin) horizon += sky->radiance(bin, 0);
  EXPECT_GT(horizon, 0);
  // The ground sees no direct sun from below the horizon: diffuse only.
  EXPECT_EQ(sky->radiance(0, 0), 0);
  EXPECT_GT(sky->radiance(0, 1), 0);
  // Twilight diffuse: a uniform-ish positive sky.
  EXPECT_GT(sky->radiance.col(2).minCoeff(), 0);
}

TEST(SkyMatrixTest, ClearnessAndBrightnessExtremes) {
  // Very clear (epsilon clamped at 11.9), very dark (delta clamped at 0.01), very bright
  // low sun (delta clamped at 0.6) and an overcast sky.
  const EpwData weather =
      Weather(45, 7, 1,
              {Step(6, 21, 13, 1100, 0.5), Step(6, 21, 12, 0, 0.01), Step(6, 21, 6, 0, 600),
               Step(6, 21, 11, 0, 400), Step(6, 21, 10, 1e-5, 1e-5)});
  absl::StatusOr<SkyMatrix> sky = SkyOf(weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  ExpectFiniteAndNonNegative(*sky);
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  for (int c = 0; c < 4; ++c) EXPECT_GT(SkyFlux(*patches, sky->radiance, c), 0) << c;
  // Below the 1e-4 W/m2 threshold: night
  EXPECT_FALSE(sky->steps[4].daytime);
}

// Sites at +-89.9 degrees: the sun grazes the horizon or stays down for months. Constant
// radiation in every hour also feeds direct light when the sun is down.
TEST(SkyMatrixTest, PolarSites) {
  for (double latitude : {89.9, -89.9}) {
    absl::StatusOr<SkyMatrix> sky = SkyOf(ConstantYearEpw(latitude, 0, 0, 400, 150));
    ASSERT_TRUE(sky.ok()) << sky.status();
    ExpectFiniteAndNonNegative(*sky);
    EXPECT_EQ(sky->daytime_steps, 8760);
    int sun_down = 0;
    for (const SkyStep& step : sky->steps) sun_down += !step.sun_in_sky;
    EXPECT_GT(sun_down, 3500) << latitude;
    EXPECT_LT(sun_down, 5000) << latitude;
    EXPECT_EQ(sky->direct_with_sun_down_steps, sun_down);
    for (Eigen::Index c = 0; c < sky->radiance.cols(); ++c) {
      ASSERT_GT(sky->radiance.col(c).sum(), 0) << c;
    }
  }
}

TEST(SkyMatrixTest, ReinhartMf2) {
  const EpwData weather =
      Weather(-34.83, -56, -3, {Step(1, 15, 14, 650, 110), Step(1, 15, 3, 0, 0)});
  absl::StatusOr<SkyMatrix> sky = SkyOf(weather, {.mf = 2});
  ASSERT_TRUE(sky.ok()) << sky.status();
  EXPECT_EQ(sky->radiance.rows(), 578);
  ExpectFiniteAndNonNegative(*sky);
  absl::StatusOr<SkyMatrix> mf1 = SkyOf(weather);
  ASSERT_TRUE(mf1.ok());
  absl::StatusOr<SkyPatches> p1 = SkyPatches::Reinhart(1);
  absl::StatusOr<SkyPatches> p2 = SkyPatches::Reinhart(2);
  ASSERT_TRUE(p1.ok() && p2.ok());
  // Same sun flux and same ground in both bases
  absl::StatusOr<SkyMatrix> sun1 = SkyOf(weather, {.include_sky = false});
  absl::StatusOr<SkyMatrix> sun2 = SkyOf(weather, {.mf = 2, .include_sky = false});
  ASSERT_TRUE(sun1.ok() && sun2.ok());
  EXPECT_NEAR(SkyFlux(*p1, sun1->radiance, 0), SkyFlux(*p2, sun2->radiance, 0), 1e-9);
  EXPECT_DOUBLE_EQ(sky->radiance(0, 0), mf1->radiance(0, 0));
}

}  // namespace
}  // namespace fenestra
