// Feeds every seed of tests/fuzz/corpus and every input that once crashed a parser
// (tests/fuzz/regressions) to the fuzz targets' entry functions, in every build.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/match.h"
#include "tests/fuzz/fuzz_targets.h"

namespace fenestra::fuzz {

// Test names and failures show the target's name.
void PrintTo(const Target& target, std::ostream* out) { *out << target.name; }

namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

class FuzzRegressionTest : public testing::TestWithParam<Target> {
 protected:
  static void SetUpTestSuite() { QuietLibraries(); }
};

// The seeds are real files: each parses, except those named bad_*.
TEST_P(FuzzRegressionTest, SeedsParseUnlessNamedBad) {
  const fs::path dir = fs::path(FENESTRA_SOURCE_DIR) / "tests/fuzz/corpus" / GetParam().name;
  int seeds = 0;
  for (const auto& file : fs::directory_iterator(dir)) {
    const std::string name = file.path().filename().string();
    const absl::Status status = GetParam().run(ReadBytes(file.path()));
    EXPECT_EQ(status.ok(), !absl::StartsWith(name, "bad_")) << name << ": " << status;
    ++seeds;
  }
  EXPECT_GT(seeds, 0) << dir;
}

// Inputs that once crashed, hung or broke an invariant now end with a status.
TEST_P(FuzzRegressionTest, RegressionsEndWithAStatus) {
  const fs::path dir = fs::path(FENESTRA_SOURCE_DIR) / "tests/fuzz/regressions" / GetParam().name;
  if (!fs::exists(dir)) return;
  for (const auto& file : fs::directory_iterator(dir)) {
    const absl::Status status = GetParam().run(ReadBytes(file.path()));
    SCOPED_TRACE(file.path().filename().string());
    EXPECT_FALSE(status.message().empty() && !status.ok());
  }
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegressionTest, testing::ValuesIn(Targets()),
                         [](const testing::TestParamInfo<Target>& info) {
                           return std::string(info.param.name);
                         });

}  // namespace
}  // namespace fenestra::fuzz
