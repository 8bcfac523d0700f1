#include "core/optimize/job.h"

#include <gtest/gtest.h>

#include "tests/example_scene.h"

namespace fenestra {
namespace {

TEST(JobTest, WindowPartsAreResolvedAndChecked) {
  absl::StatusOr<v1::Sampling> automatic = ResolveSampling(v1::Sampling());
  ASSERT_TRUE(automatic.ok()) << automatic.status();
  const Scene scene = LoadExample("city_office");
  EXPECT_EQ(SamplingWindowParts(*automatic, scene.window), (WindowParts{4, 3}));
  v1::Sampling columns_only = *automatic;
  columns_only.set_window_columns(2);
  EXPECT_EQ(SamplingWindowParts(columns_only, scene.window), (WindowParts{2, 3}));
  for (const int bad : {-1, 17}) {
    v1::Sampling s;
    s.set_window_rows(bad);
    absl::StatusOr<v1::Sampling> resolved = ResolveSampling(s);
    ASSERT_FALSE(resolved.ok());
    EXPECT_NE(resolved.status().message().find("sampling.window_columns/window_rows"),
              std::string::npos)
        << resolved.status();
  }
  // Enough outdoor paths for every window cell
  v1::Sampling few;
  few.set_outdoor_paths(1000);
  few.set_window_columns(2);
  EXPECT_FALSE(ResolveSampling(few).ok());
}

// A job needs two outdoor paths per window cell of its resolved parts
TEST(JobTest, PrepareChecksOutdoorPathsAgainstTheWindowCells) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  ASSERT_TRUE(job.ok()) << job.status();
  job->mutable_sampling()->set_outdoor_paths(5000);  // 4 x 3 x 288 cells need 6912
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_FALSE(prepared.ok());
  EXPECT_NE(prepared.status().message().find("4x3 window parts"), std::string::npos)
      << prepared.status();
  job->mutable_sampling()->set_window_columns(1);
  job->mutable_sampling()->set_window_rows(1);
  prepared = PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  EXPECT_TRUE(prepared.ok()) << prepared.status();
}

// A width range whose narrowest slats would need more than kMaxBlindSlats is refused before
// any blind is generated.
TEST(JobTest, PrepareRefusesWidthsNeedingTooManySlats) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_width_target.json");
  ASSERT_TRUE(job.ok()) << job.status();
  for (v1::DesignVariable& v : *job->mutable_variables()) {
    if (v.name() == "width") v.set_lower(1e-6);  // 1.5 m window: 1.5 million slats
  }
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_FALSE(prepared.ok());
  EXPECT_NE(prepared.status().message().find(".lower: at width 1e-06 m the blind would need up to"),
            std::string::npos)
      << prepared.status();
}

// The outdoor matrix's key follows the window parts it was traced with, not how they
// were asked for.
TEST(JobTest, OutdoorKeyFollowsTheWindowParts) {
  const Scene scene = LoadExample("city_office");
  v1::Sampling automatic = *ResolveSampling(v1::Sampling());
  v1::Sampling explicit_parts = automatic;
  explicit_parts.set_window_columns(4);
  explicit_parts.set_window_rows(3);
  v1::Sampling whole = automatic;
  whole.set_window_columns(1);
  whole.set_window_rows(1);
  EXPECT_EQ(OutdoorMatrixKey(scene, automatic), OutdoorMatrixKey(scene, explicit_parts));
  EXPECT_NE(OutdoorMatrixKey(scene, automatic), OutdoorMatrixKey(scene, whole));
}

}  // namespace
}  // namespace fenestra
