#include "client/report/annual_outputs.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "core/common/radiance_matrix.h"
#include "core/geometry/blind.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/scene.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class AnnualOutputsTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fenestra_annual_outputs_" +
            std::string(testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(AnnualOutputsTest, CsvAndMatrixHoldTheResultsValues) {
  const v1::JobResult& result = QuickJobResult();
  const v1::HourlyIlluminance& h = result.best_hourly();
  const int steps = h.month_size();
  ASSERT_TRUE(WriteAnnualOutputs(result, {Path("h.csv"), Path("h.mtx"), ""}).ok());

  // CSV: a header naming the sensors, then month, day, hour and one value per sensor
  std::ifstream csv(Path("h.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "month,day,hour,S1,S2,S3,S4,S5,S6,S7,S8,S9");
  int row = 0;
  for (; std::getline(csv, line); ++row) {
    ASSERT_LT(row, steps);
    const std::vector<std::string> fields = absl::StrSplit(line, ',');
    ASSERT_EQ(fields.size(), 12u) << line;
    EXPECT_EQ(fields[0], std::to_string(h.month(row)));
    EXPECT_EQ(fields[1], std::to_string(h.day(row)));
    double hour;
    ASSERT_TRUE(absl::SimpleAtod(fields[2], &hour));
    EXPECT_EQ(hour, h.hour(row));
    for (int i = 0; i < 9; ++i) {
      float lux;
      ASSERT_TRUE(absl::SimpleAtof(fields[3 + i], &lux)) << fields[3 + i];
      ASSERT_EQ(lux, h.illuminance_lux(i * steps + row)) << "row " << row << " sensor " << i;
    }
  }
  EXPECT_EQ(row, 8760);

  // Matrix: sensors x steps, three equal channels of illuminance / 179
  absl::StatusOr<std::vector<Matrix>> matrix = ReadRadianceMatrixComponents(Path("h.mtx"));
  ASSERT_TRUE(matrix.ok()) << matrix.status();
  ASSERT_EQ(matrix->size(), 3u);
  for (const Matrix& channel : *matrix) {
    ASSERT_EQ(channel.rows(), 9);
    ASSERT_EQ(channel.cols(), 8760);
    for (int i = 0; i < 9; ++i) {
      for (int j = 0; j < steps; ++j) {
        const double lux = h.illuminance_lux(i * steps + j);
        ASSERT_NEAR(179 * channel(i, j), lux, 1e-7 * lux) << i << ", " << j;
      }
    }
  }
  std::ifstream header(Path("h.mtx"));
  std::string text((std::istreambuf_iterator<char>(header)), {});
  EXPECT_THAT(text.substr(0, 60), HasSubstr("NROWS=9\nNCOLS=8760\nNCOMP=3\nFORMAT=ascii\n"));
}

TEST_F(AnnualOutputsTest, ObjHoldsTheSceneWithTheBestBlind) {
  const v1::JobResult& result = QuickJobResult();
  ASSERT_TRUE(WriteAnnualOutputs(result, {"", "", Path("best.obj")}).ok());
  absl::StatusOr<ObjTriangles> obj = ReadObj(Path("best.obj"));
  ASSERT_TRUE(obj.ok()) << obj.status();
  absl::StatusOr<Scene> scene = BuildScene(result.job().scene(), "result");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const std::map<std::string, double> best(result.best_design().begin(),
                                           result.best_design().end());
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(*scene, best);
  ASSERT_TRUE(design.ok()) << design.status();
  const int slats = LayoutBlind(scene->window(), *scene->blind(), *design).slat_count;
  EXPECT_EQ(std::count(obj->group.begin(), obj->group.end(), "blind"), 12 * slats);
  EXPECT_EQ(obj->group.size(), scene->fixed.TriangleCount() + 12 * slats);
  // The slats are where the generator puts them at the best design (OBJ holds floats)
  TriangleMesh blind;
  GenerateBlind(scene->window(), *scene->blind(), *design, 0, blind);
  size_t k = 0;
  for (size_t t = 0; t < obj->group.size(); ++t) {
    if (obj->group[t] != "blind") continue;
    for (int v = 0; v < 3; ++v) {
      const Vec3d a = obj->vertices[3 * t + v], b = blind.vertices[3 * k + v];
      ASSERT_LT(Length(a - b), 1e-5) << "blind triangle " << k;
    }
    ++k;
  }
}

// The best design of a search over the finish: its slats in the OBJ are of its finish's
// material (white), none of the scene's own (black).
TEST_F(AnnualOutputsTest, ObjHoldsTheBestFinish) {
  const v1::JobResult& result = QuickFinishJobResult();
  ASSERT_EQ(result.best_design().at("finish"), 1);
  ASSERT_TRUE(WriteAnnualOutputs(result, {"", "", Path("best.obj")}).ok());
  absl::StatusOr<ObjTriangles> obj = ReadObj(Path("best.obj"));
  ASSERT_TRUE(obj.ok()) << obj.status();
  absl::StatusOr<Scene> scene = BuildScene(result.job().scene(), "result");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const int slats = LayoutBlind(scene->window(), *scene->blind(), DefaultDesign(*scene)).slat_count;
  EXPECT_EQ(std::count(obj->group.begin(), obj->group.end(), "white"), 12 * slats);
  EXPECT_EQ(std::count(obj->group.begin(), obj->group.end(), "black"), 0);
}

TEST_F(AnnualOutputsTest, WhatTheResultLacksIsAnErrorNamingTheFlag) {
  v1::JobResult result = QuickJobResult();
  result.clear_best_hourly();
  absl::Status status = WriteAnnualOutputs(result, {Path("h.csv"), "", ""});
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(status.message(), HasSubstr("--hourly-csv: the result holds no hourly illuminance"));
  status = WriteAnnualOutputs(result, {"", Path("h.mtx"), ""});
  EXPECT_THAT(status.message(), HasSubstr("--hourly-matrix: the result holds no hourly"));
  result.clear_job();
  status = WriteAnnualOutputs(result, {"", "", Path("b.obj")});
  EXPECT_THAT(status.message(), HasSubstr("--best-obj: the result holds no scene"));
  EXPECT_TRUE(fs::is_empty(dir_));
  // Sizes that do not agree are refused too
  result = QuickJobResult();
  result.mutable_best_hourly()->mutable_illuminance_lux()->RemoveLast();
  EXPECT_THAT(WriteHourlyCsv(result, Path("h.csv")).message(), HasSubstr("do not fill 9 sensors"));
}

TEST_F(AnnualOutputsTest, SensorNamesAreQuotedInCsv) {
  v1::JobResult result = QuickJobResult();
  result.mutable_best_hourly()->set_sensors(0, "desk, \"north\"");
  ASSERT_TRUE(WriteHourlyCsv(result, Path("h.csv")).ok());
  std::ifstream csv(Path("h.csv"));
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "month,day,hour,\"desk, \"\"north\"\"\",S2,S3,S4,S5,S6,S7,S8,S9");
}

}  // namespace
}  // namespace fenestra
