// Runs the fenestra executable as a user would.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <tuple>

#include "core/geometry/obj_io.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int exit_code;
  std::string output;  // stdout and stderr together
};

CliRun Fenestra(const std::string& args) {
  const std::string command = std::string(FENESTRA_CLI) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

const std::string kExamples = FENESTRA_SOURCE_DIR "/examples";

class SceneCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           (std::string("fenestra_cli_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SceneCliTest, ExportLightwellGives42Triangles) {
  const std::string obj = (dir_ / "x.obj").string();
  const CliRun run = Fenestra("scene export " + kExamples + "/lightwell/scene.json --obj " + obj);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  absl::StatusOr<ObjTriangles> read = ReadObj(obj);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->group.size(), 42u);
}

TEST_F(SceneCliTest, ExportWithDesignValues) {
  const std::string obj = (dir_ / "office.obj").string();
  const CliRun run = Fenestra("scene export " + kExamples + "/city_office/scene.json --obj " + obj +
                              " --set alpha=0.5,width=0.1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  absl::StatusOr<ObjTriangles> read = ReadObj(obj);
  ASSERT_TRUE(read.ok()) << read.status();
  // 126 fixed triangles + 15 slats (1 + ceil((1.5 - 0.1) / 0.1)) of 12
  EXPECT_EQ(read->group.size(), 126u + 15u * 12u);
}

TEST_F(SceneCliTest, CheckPrintsASummary) {
  const CliRun run = Fenestra("scene check " + kExamples + "/city_office/scene.json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("246 triangles"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("sensors: 9"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("10 slats"), std::string::npos) << run.output;
}

TEST_F(SceneCliTest, BadDesignValueFailsAndWritesNothing) {
  const std::string obj = (dir_ / "bad.obj").string();
  const CliRun run = Fenestra("scene export " + kExamples + "/city_office/scene.json --obj " + obj +
                              " --set width=0.3");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("error: design variable width = 0.3 is outside its range"),
            std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(obj));
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(SceneCliTest, BadSceneFailsAndWritesNothing) {
  const std::string scene = (dir_ / "scene.json").string();
  std::ofstream(scene) << R"({"name": "x", "materials": [{"name": "m", "reflectance": 1.5}]})";
  const std::string obj = (dir_ / "out.obj").string();
  const CliRun run = Fenestra("scene export " + scene + " --obj " + obj);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find(scene + ": materials[0].reflectance: must be in [0, 1)"),
            std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(obj));
}

TEST_F(SceneCliTest, UnwritableOutputFailsCleanly) {
  const CliRun run = Fenestra("scene export " + kExamples + "/lightwell/scene.json --obj " +
                              (dir_ / "no/such/dir/x.obj").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("cannot open for writing"), std::string::npos) << run.output;
}

TEST_F(SceneCliTest, DcTwoStageWritesDAndBothStages) {
  const std::string d = (dir_ / "D.mtx").string(), o = (dir_ / "O.mtx").string(),
                    i = (dir_ / "I.mtx").string();
  const CliRun run = Fenestra("dc " + kExamples +
                              "/city_office/scene.json --method two-stage --outdoor-paths 69120 "
                              "--indoor-paths 2000 --bounces 3 --set alpha=1 -o " +
                              d + " --outdoor-matrix " + o + " --indoor-matrix " + i);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // The 2 m x 1.5 m window in 4 x 3 parts of 0.5 m, 288 direction cells each; O and I also
  // have the 146 direct rows and columns (sky bins seen straight through the window)
  EXPECT_NE(run.output.find("4x3 window parts x 288 direction cells"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("outdoor stage: 69120 paths"), std::string::npos) << run.output;
  for (const auto& [path, rows, cols] :
       {std::tuple{d, 9, 146}, std::tuple{o, 3456 + 146, 146}, std::tuple{i, 9, 3456 + 146}}) {
    std::ifstream in(path);
    std::string header((std::istreambuf_iterator<char>(in)), {});
    EXPECT_NE(header.find("NROWS=" + std::to_string(rows) + "\nNCOLS=" + std::to_string(cols)),
              std::string::npos)
        << path;
  }
}

TEST_F(SceneCliTest, DcRejectsBadWindowParts) {
  for (const std::string parts : {"0x2", "4", "4x3x1", "axb", "17x1"}) {
    const CliRun run = Fenestra("dc " + kExamples + "/city_office/scene.json --method two-stage " +
                                "--window-parts " + parts + " -o " + (dir_ / "D.mtx").string());
    EXPECT_EQ(run.exit_code, 1) << parts;
    EXPECT_NE(run.output.find("window parts"), std::string::npos) << run.output;
    EXPECT_TRUE(fs::is_empty(dir_)) << parts;
  }
}

TEST_F(SceneCliTest, DcStageMatricesNeedTheTwoStageMethod) {
  const CliRun run =
      Fenestra("dc " + kExamples + "/lightwell/scene.json -o " + (dir_ / "D.mtx").string() +
               " --outdoor-matrix " + (dir_ / "O.mtx").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("--outdoor-matrix needs --method two-stage"), std::string::npos)
      << run.output;
  EXPECT_TRUE(fs::is_empty(dir_));
}

}  // namespace
}  // namespace fenestra
