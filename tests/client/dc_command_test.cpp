// fenestra dc, run as a user would.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <tuple>
#include <vector>

#include "core/common/radiance_matrix.h"
#include "tests/client/cli_run.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

using DcCommandTest = CliTest;

const std::string kLightwell = kExamples + "/lightwell/scene.json";

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), {}};
}

Matrix ReadMatrix(const fs::path& path) {
  absl::StatusOr<Matrix> m = ReadRadianceMatrix(path.string());
  EXPECT_TRUE(m.ok()) << m.status();
  return m.ok() ? *m : Matrix();
}

// The relative standard errors [%] of the sensors' sky sums the command printed.
std::vector<double> PrintedRelativeErrors(const std::string& output) {
  static const std::regex line(R"(sky sum \S+ sr \+- \S+ \(([0-9.]+)%\))");
  std::vector<double> errors;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line);
       it != std::sregex_iterator(); ++it) {
    errors.push_back(std::stod((*it)[1]));
  }
  return errors;
}

TEST_F(DcCommandTest, TwoStageWritesDAndBothStages) {
  const std::string d = (dir_ / "D.mtx").string(), o = (dir_ / "O.mtx").string(),
                    i = (dir_ / "I.mtx").string();
  const CliRun run = Fenestra("dc " + kExamples +
                              "/city_office/scene.json --method two-stage --outdoor-paths 110592 "
                              "--indoor-paths 2000 --outdoor-bounces 3 --indoor-bounces 2 "
                              "--set alpha=1 -o " +
                              d + " --outdoor-matrix " + o + " --indoor-matrix " + i);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // The 2 m x 1.5 m window in 4 x 3 parts of 0.5 m, 288 direction cells each, one outdoor path
  // per window cell and batch; O and I also have the 2 x 146 direct rows and columns (sky bins
  // seen straight through the window: after a reflection in the room, then from the sensor)
  EXPECT_NE(run.output.find("4x3 window parts x 288 direction cells"), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("outdoor stage: 110592 paths, at most 3 reflections"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("2000 paths in 32 batches, at most 2 reflections"), std::string::npos)
      << run.output;
  for (const auto& [path, rows, cols] :
       {std::tuple{d, 9, 146}, std::tuple{o, 3456 + 292, 146}, std::tuple{i, 9, 3456 + 292}}) {
    EXPECT_NE(
        ReadText(path).find("NROWS=" + std::to_string(rows) + "\nNCOLS=" + std::to_string(cols)),
        std::string::npos)
        << path;
  }
  // Every sensor's sky sum with its correlated standard error and relative error
  EXPECT_EQ(PrintedRelativeErrors(run.output).size(), 9u) << run.output;
}

TEST_F(DcCommandTest, TwoStageDefaultsAreTheJobs) {
  const CliRun run = Fenestra("dc --help");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // job.proto: outdoor 2e7 paths, indoor 2e5 paths, reflections unlimited in both stages
  for (const char* flag : {"--outdoor-paths INT=20000000", "--indoor-paths INT=200000",
                           "--outdoor-bounces INT=-1", "--indoor-bounces INT=-1"}) {
    EXPECT_NE(run.output.find(flag), std::string::npos) << flag << "\n" << run.output;
  }
}

TEST_F(DcCommandTest, BouncesIsRefusedForTwoStage) {
  const CliRun run = Fenestra("dc " + kLightwell + " --method two-stage --bounces 5 -o " +
                              (dir_ / "D.mtx").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("error: --bounces is the one-stage limit; the two-stage method takes "
                            "--outdoor-bounces (default -1) and --indoor-bounces (default -1)"),
            std::string::npos)
      << run.output;
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(DcCommandTest, FlagsOfTheOtherMethodAreRefused) {
  for (const auto& [flags, message] :
       {std::pair{"--indoor-bounces 3", "--indoor-bounces applies to --method two-stage only"},
        std::pair{"--outdoor-paths 100000", "--outdoor-paths applies to --method two-stage only"},
        std::pair{"--method two-stage --paths 1000", "--paths applies to --method one-stage only"},
        std::pair{"--method two-stage --indoor-bounces -2",
                  "--indoor-bounces must be >= 0, or -1 for unlimited, got -2"},
        std::pair{"--max-seconds 10", "--max-seconds needs --target-error"},
        std::pair{"--target-error 1.5", "--target-error must be in (0, 1)"}}) {
    const CliRun run =
        Fenestra("dc " + kLightwell + " " + flags + " -o " + (dir_ / "D.mtx").string());
    EXPECT_EQ(run.exit_code, 1) << flags;
    EXPECT_NE(run.output.find(message), std::string::npos) << run.output;
    EXPECT_TRUE(fs::is_empty(dir_)) << flags;
  }
}

// Each bounce flag reaches its own stage, and the light follows: with no indoor reflections a
// sensor sees only the window, and interreflection adds the most, relatively, at the back of
// the room; with no outdoor reflections the window cells (views that meet the light well's
// walls) carry no light, only the sky seen straight through the window does (I's direct
// columns). The other stage's matrix stays the same to the bit (same seed).
TEST_F(DcCommandTest, BounceFlagsReachTheirStages) {
  const auto trace = [&](const std::string& name, int outdoor_bounces, int indoor_bounces) {
    const fs::path o = dir_ / (name + "_O.mtx"), i = dir_ / (name + "_I.mtx");
    const CliRun run = Fenestra(
        "dc " + kLightwell + " --method two-stage --outdoor-paths 110592 --indoor-paths 20000 " +
        "--outdoor-bounces " + std::to_string(outdoor_bounces) + " --indoor-bounces " +
        std::to_string(indoor_bounces) + " -o " + (dir_ / (name + "_D.mtx")).string() +
        " --outdoor-matrix " + o.string() + " --indoor-matrix " + i.string());
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return std::pair{o, i};
  };
  const auto [o_direct_sky, i_default] = trace("a", 0, 5);
  const auto [o_default, i_direct_window] = trace("b", 30, 0);
  const auto [o_default_again, i_default_again] = trace("c", 30, 5);
  EXPECT_EQ(ReadText(o_default), ReadText(o_default_again));
  EXPECT_EQ(ReadText(i_default), ReadText(i_default_again));

  // Indoor: S1 near the window, S3 at the back
  const Eigen::VectorXd direct = ReadMatrix(i_direct_window).rowwise().sum();
  const Eigen::VectorXd reflected = ReadMatrix(i_default).rowwise().sum();
  ASSERT_EQ(direct.size(), 3);
  const Eigen::VectorXd gain = reflected.cwiseQuotient(direct);
  EXPECT_GT(gain(0), 1.2) << gain.transpose();
  EXPECT_GT(gain(1), 1.5 * gain(0)) << gain.transpose();
  EXPECT_GT(gain(2), 1.5 * gain(1)) << gain.transpose();

  // Outdoor: the walls of the light well reflect the sky into the window cells; the identity
  // rows for the direct columns stay
  constexpr int kWindowCells = 3456;
  const Matrix o_direct = ReadMatrix(o_direct_sky), o_reflected = ReadMatrix(o_default);
  ASSERT_EQ(o_direct.rows(), kWindowCells + 292);
  EXPECT_EQ(o_direct.topRows(kWindowCells).cwiseAbs().sum(), 0);
  for (const Matrix* o : {&o_direct, &o_reflected}) {
    EXPECT_TRUE(o->middleRows(kWindowCells, 146).isIdentity());
    EXPECT_TRUE(o->bottomRows(146).isIdentity());
  }
  // The sensors see little sky straight through the light well: the walls bring most light
  // (about 40 times as much, measured)
  const Eigen::VectorXd d_direct = ReadMatrix(dir_ / "a_D.mtx").rightCols(145).rowwise().sum();
  const Eigen::VectorXd d_reflected = ReadMatrix(dir_ / "c_D.mtx").rightCols(145).rowwise().sum();
  for (int s = 0; s < 3; ++s) EXPECT_GT(d_reflected(s), 10 * d_direct(s)) << "sensor " << s;
}

// The sensors' sky sums [sr] and their standard errors [sr] the command printed.
std::vector<std::pair<double, double>> PrintedSkySums(const std::string& output) {
  static const std::regex line(R"(sky sum (\S+) sr \+- (\S+) \()");
  std::vector<std::pair<double, double>> sums;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line);
       it != std::sregex_iterator(); ++it) {
    sums.emplace_back(std::stod((*it)[1]), std::stod((*it)[2]));
  }
  return sums;
}

// --bounces 0 is the direct component: the sky seen straight through the window and between
// the open slats of the city office, the same light as the two-stage method with no
// reflection in either stage (within 4 combined standard errors, fixed seeds), and far less
// than with reflections; -1 is unlimited.
TEST_F(DcCommandTest, ZeroBouncesGiveTheDirectComponent) {
  const auto run = [&](const std::string& flags) {
    const CliRun r = Fenestra("dc " + kExamples + "/city_office/scene.json --set alpha=1.5 " +
                              flags + " -o " + (dir_ / "D.mtx").string());
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return r.output;
  };
  const std::string one_direct = run("--paths 100000 --bounces 0 --seed 3");
  EXPECT_NE(one_direct.find("at most 0 reflections"), std::string::npos) << one_direct;
  const std::string one_all = run("--paths 4000 --bounces -1 --seed 3");
  EXPECT_NE(one_all.find("unlimited reflections"), std::string::npos) << one_all;
  const std::string two_direct =
      run("--method two-stage --outdoor-paths 110592 --indoor-paths 20000 --outdoor-bounces 0 "
          "--indoor-bounces 0 --seed 4");
  const auto direct = PrintedSkySums(one_direct), all = PrintedSkySums(one_all),
             two = PrintedSkySums(two_direct);
  ASSERT_EQ(direct.size(), 9u) << one_direct;
  ASSERT_EQ(all.size(), 9u) << one_all;
  ASSERT_EQ(two.size(), 9u) << two_direct;
  for (int s = 0; s < 9; ++s) {
    SCOPED_TRACE(testing::Message() << "sensor " << s);
    EXPECT_GT(direct[s].first, 5 * direct[s].second);
    EXPECT_NEAR(direct[s].first, two[s].first, 4 * std::hypot(direct[s].second, two[s].second));
    EXPECT_GT(all[s].first, 2 * direct[s].first);
  }
}

TEST_F(DcCommandTest, OneStageTargetErrorLandsJustBelowIt) {
  const fs::path d = dir_ / "D.mtx";
  const CliRun run = Fenestra("dc " + kLightwell + " --target-error 0.02 -o " + d.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("target 2.00% reached in"), std::string::npos) << run.output;
  const std::vector<double> errors = PrintedRelativeErrors(run.output);
  ASSERT_EQ(errors.size(), 3u) << run.output;
  const double largest = *std::max_element(errors.begin(), errors.end());
  EXPECT_LE(largest, 2.0) << run.output;
  EXPECT_GE(largest, 1.4) << run.output;
  EXPECT_TRUE(fs::exists(d));
}

// 3% rather than 2%: the outdoor paths of the light well (up to 30 reflections between its walls)
// would take most of the test's time
TEST_F(DcCommandTest, TwoStageTargetErrorLandsJustBelowIt) {
  const CliRun run = Fenestra("dc " + kLightwell +
                              " --method two-stage --outdoor-paths 1000000 --indoor-paths 10000 "
                              "--target-error 0.03 -o " +
                              (dir_ / "D.mtx").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("target 3.00% reached in"), std::string::npos) << run.output;
  const std::vector<double> errors = PrintedRelativeErrors(run.output);
  ASSERT_EQ(errors.size(), 3u) << run.output;
  const double largest = *std::max_element(errors.begin(), errors.end());
  EXPECT_LE(largest, 3.0) << run.output;
  EXPECT_GE(largest, 2.1) << run.output;
}

TEST_F(DcCommandTest, TargetOutOfReachStopsAtTheLimitWithExitCode2) {
  const fs::path d = dir_ / "D.mtx";
  const CliRun run =
      Fenestra("dc " + kLightwell + " --paths 20000 --target-error 0.001 --max-paths 30000 -o " +
               d.string());
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("target 0.10% not reached"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("stopped by the maximum path count"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("3 sensors x 30000 paths"), std::string::npos) << run.output;
  EXPECT_TRUE(fs::exists(d));  // what was traced is kept
}

TEST_F(DcCommandTest, RejectsBadWindowParts) {
  for (const std::string parts : {"0x2", "4", "4x3x1", "axb", "17x1"}) {
    const CliRun run = Fenestra("dc " + kExamples + "/city_office/scene.json --method two-stage " +
                                "--window-parts " + parts + " -o " + (dir_ / "D.mtx").string());
    EXPECT_EQ(run.exit_code, 1) << parts;
    EXPECT_NE(run.output.find("window parts"), std::string::npos) << run.output;
    EXPECT_TRUE(fs::is_empty(dir_)) << parts;
  }
}

TEST_F(DcCommandTest, StageMatricesNeedTheTwoStageMethod) {
  const CliRun run = Fenestra("dc " + kLightwell + " -o " + (dir_ / "D.mtx").string() +
                              " --outdoor-matrix " + (dir_ / "O.mtx").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("--outdoor-matrix needs --method two-stage"), std::string::npos)
      << run.output;
  EXPECT_TRUE(fs::is_empty(dir_));
}

}  // namespace
}  // namespace fenestra

namespace fenestra {
namespace {

using GlareCommandTest = CliTest;

const std::string kSunnyOffice = kExamples + "/sunny_office/scene.json";

TEST_F(GlareCommandTest, PrintsEachViewsYearAndWritesItsHours) {
  const std::string hourly = (dir_ / "hours.csv").string();
  const CliRun run =
      Fenestra("glare " + kSunnyOffice + " --set alpha=1.2 --paths 4000 --hourly " + hourly);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const char* text :
       {"view desk facing the window at (0.00, 2.00, 4.20)", "view desk facing the side wall",
        "glare autonomy", "of 3650 occupied hours (DGP < 0.40; target 95%: not met)",
        "EN 17037 glare protection", "hours imperceptible"}) {
    EXPECT_NE(run.output.find(text), std::string::npos) << text << "\n" << run.output;
  }
  const std::string csv = ReadText(hourly);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 8761);
  EXPECT_EQ(csv.substr(0, csv.find(",desk facing the side wall")),
            "month,day,hour,desk facing the window Ev [lx],desk facing the window Ev SE "
            "[lx],desk facing the window DGPs,desk facing the window DGP");
}

TEST_F(GlareCommandTest, ASceneWithoutViewsOrATwoStageRunIsRefused) {
  CliRun run = Fenestra("glare " + kExamples + "/city_office/scene.json --paths 100");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("the scene has no view points"), std::string::npos) << run.output;
  run = Fenestra("glare " + kSunnyOffice + " --method two-stage");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.output.find("one-stage"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace fenestra
