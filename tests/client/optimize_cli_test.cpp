// Runs `fenestra optimize --local` as a user would: the final check in the output, the result
// file and the history CSV with the best value against time.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "client/cli_util.h"
#include "core/common/json_proto.h"
#include "fenestra/v1/job.pb.h"
#include "tests/client/cli_run.h"

namespace fenestra {
namespace {

using OptimizeCliTest = CliTest;

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  for (std::string field; std::getline(s, field, ',');) fields.push_back(field);
  return fields;
}

// The quick tilt job with 6 evaluations and the source publication's reflection limits (30
// outdoor, 5 indoor), which the check (without a limit) finds at this seed.
TEST_F(OptimizeCliTest, PrintsTheFinalCheckAndWritesTheBestValueAgainstTime) {
  v1::Job job;
  ASSERT_TRUE(ReadJsonProtoFile(kExamples + "/city_office/alpha_max_quick.json", "job", &job).ok());
  job.set_scene_file(kExamples + "/city_office/scene.json");
  job.mutable_budget()->set_max_evaluations(6);
  job.mutable_sampling()->set_backend("cpu");
  job.mutable_sampling()->set_outdoor_bounces(30);
  job.mutable_sampling()->set_indoor_bounces(5);
  ASSERT_TRUE(WriteJsonFile((dir_ / "job.json").string(), job).ok());

  const CliRun run = Fenestra("optimize --local " + (dir_ / "job.json").string() + " -o " +
                              (dir_ / "result.json").string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string& output = run.output;
  EXPECT_NE(output.find("checking the best design by the one-stage method...\n"), std::string::npos)
      << output;
  EXPECT_NE(output.find("[6/6] check of the best design ("), std::string::npos) << output;
  EXPECT_NE(output.find("final check (one-stage, "), std::string::npos) << output;

  // The result file: the check, and the same flag in the output
  v1::JobResult result;
  ASSERT_TRUE(ReadJsonProtoFile((dir_ / "result.json").string(), "result", &result).ok());
  ASSERT_TRUE(result.has_final_check());
  EXPECT_TRUE(result.final_check().disagrees()) << result.final_check().DebugString();
  EXPECT_NE(output.find(": DISAGREES"), std::string::npos) << output;
  EXPECT_NE(output.find("warning: the two-stage value and the one-stage check differ by more "
                        "than 3 standard errors"),
            std::string::npos)
      << output;

  // The CSV: each step's time and the best value so far, as the result's best_over_time
  std::ifstream csv(dir_ / "result.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  const std::vector<std::string> header = Split(line);
  ASSERT_GE(header.size(), 3u);
  EXPECT_EQ(header[header.size() - 3], "elapsed_seconds");
  EXPECT_EQ(header[header.size() - 2], "best_value");
  EXPECT_EQ(header[header.size() - 1], "best_standard_error");
  size_t improved_column = 0;
  while (header[improved_column] != "improved") ++improved_column;
  int rows = 0, moves = 0;
  double previous_elapsed = 0;
  for (; std::getline(csv, line); ++rows) {
    const std::vector<std::string> f = Split(line);
    ASSERT_EQ(f.size(), header.size()) << line;
    const double elapsed = std::stod(f[f.size() - 3]);
    EXPECT_GE(elapsed, previous_elapsed);
    previous_elapsed = elapsed;
    if (f[improved_column] == "1") {
      ASSERT_LT(moves, result.best_over_time_size());
      const v1::BestSoFar& best = result.best_over_time(moves++);
      EXPECT_EQ(best.evaluation(), rows);
      EXPECT_NEAR(std::stod(f[f.size() - 2]), best.value().value(), 1e-6);
      EXPECT_NEAR(std::stod(f[f.size() - 1]), best.value().standard_error(), 1e-6);
      EXPECT_NEAR(elapsed, best.elapsed_seconds(), 1e-5);
    }
  }
  EXPECT_EQ(rows, result.history_size());
  EXPECT_EQ(moves, result.best_over_time_size());
  EXPECT_GE(moves, 1);
}

}  // namespace
}  // namespace fenestra
