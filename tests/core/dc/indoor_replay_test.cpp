#include "core/dc/indoor_replay.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "tests/core/dc/replay_checks.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// Replayed paths are the traced paths: for designs across the ranges, I equals the indoor
// stage's with the same seed, up to the order of the sums (and the rare path whose float
// rounding differs between the two acceleration structures).
TEST(IndoorReplayTest, EqualsTheIndoorStage) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions options;
  options.paths_per_sensor = 20'000;
  options.parts = {2, 2};
  absl::StatusOr<std::unique_ptr<IndoorReplay>> replay = IndoorReplay::Record(scene, options);
  ASSERT_TRUE(replay.ok()) << replay.status();
  std::printf("paths resumed per design: %.1f%%\n", 100 * (*replay)->ResumedFraction());
  EXPECT_GT((*replay)->ResumedFraction(), 0.0);
  EXPECT_LT((*replay)->ResumedFraction(), 0.5);
  // A path whose ray the slats leave clear goes on as recorded: a design traces on fewer paths
  // than reached the envelope (at closed slats about three quarters of them)
  ExpectReplayIsTheTrace(scene, options, **replay, nullptr, [&](const BlindDesign& design) {
    absl::StatusOr<IndoorTally> tally = (*replay)->TraceParts(design, 0, kDesignParts);
    ASSERT_TRUE(tally.ok()) << tally.status();
    uint64_t traced_on = 0;
    for (uint64_t paths : tally->counters.ends) traced_on += paths;
    const double reached = (*replay)->ResumedFraction() *
                           static_cast<double>(options.paths_per_sensor * scene.sensors.size());
    EXPECT_GT(traced_on, 0u);
    EXPECT_LT(static_cast<double>(traced_on), 0.95 * reached);
  });
}

// With the Sobol draws too: a resumed path draws what its full trace draws (its batch's
// point and scramble).
TEST(IndoorReplayTest, EqualsTheIndoorStageWithSobolDraws) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions options;
  options.paths_per_sensor = 20'000;
  options.parts = {2, 2};
  options.sequence = Sequence::kSobol;
  absl::StatusOr<std::unique_ptr<IndoorReplay>> replay = IndoorReplay::Record(scene, options);
  ASSERT_TRUE(replay.ok()) << replay.status();
  ExpectReplayIsTheTrace(scene, options, **replay);
}

// The records serve every finish: a design's finish replays as the scene whose blind is of its
// materials (bit for bit), and as the design's full trace; dark slats get less light into the
// room than the scene's light ones. A finish of materials the scene lacks is refused.
TEST(IndoorReplayTest, DesignFinishReplaysAsSlatsOfItsMaterials) {
  Scene scene = LoadExample("city_office");
  scene.materials.push_back({"dark", 0.05, -1});
  const uint32_t dark = static_cast<uint32_t>(scene.materials.size() - 1);
  Scene dark_scene = scene;
  dark_scene.blind()->material = dark;
  IndoorOptions options;
  options.paths_per_sensor = 10'000;
  options.parts = {2, 2};
  absl::StatusOr<std::unique_ptr<IndoorReplay>> replay = IndoorReplay::Record(scene, options);
  absl::StatusOr<std::unique_ptr<IndoorReplay>> dark_replay =
      IndoorReplay::Record(dark_scene, options);
  ASSERT_TRUE(replay.ok() && dark_replay.ok()) << replay.status() << dark_replay.status();
  for (const double alpha : {0.3, 0.8}) {
    SCOPED_TRACE(alpha);
    absl::StatusOr<BlindDesign> plain =
        DesignWithOverrides(scene, {{"alpha", alpha}, {"spacing", 0.02}});
    ASSERT_TRUE(plain.ok()) << plain.status();
    BlindDesign finished = *plain;
    finished.finish = SlatFinish{dark, dark};
    absl::StatusOr<IndoorResult> replayed = (*replay)->Compute(finished);
    absl::StatusOr<IndoorResult> of_scene = (*dark_replay)->Compute(*plain);
    absl::StatusOr<IndoorResult> traced = ComputeIndoorStage(scene, finished, options);
    absl::StatusOr<IndoorResult> light = (*replay)->Compute(*plain);
    ASSERT_TRUE(replayed.ok() && of_scene.ok() && traced.ok() && light.ok());
    EXPECT_TRUE(replayed->coefficients == of_scene->coefficients);
    ExpectReplayEqualsTrace(*traced, *replayed);
    EXPECT_LT(replayed->coefficients.sum(), 0.98 * light->coefficients.sum());
  }
  BlindDesign unknown = DefaultDesign(scene);
  unknown.finish = SlatFinish{99, 99};
  EXPECT_EQ((*replay)->Compute(unknown).status().code(), absl::StatusCode::kInvalidArgument);
}

// A search's designs in rounds on the CPU (racing): each round traces only the parts it
// adds, and the last ends where one full trace does; designs asked together are traced as
// alone; a design's I from the tallies is its full trace's.
TEST(IndoorReplayTest, RoundsEndAsOneTrace) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions options;
  options.paths_per_sensor = 16'000;
  options.parts = {2, 2};
  options.batches = 4;
  const int columns = 4 * 288 + kIndoorDirectColumns;
  std::vector<Matrix> outdoor;
  for (int b = 0; b < options.batches; ++b) {
    outdoor.push_back(Matrix::Random(columns, kDaylightBins).cwiseAbs());
  }
  const Matrix sky = 100 * Matrix::Random(kDaylightBins, 300).cwiseAbs();
  std::unique_ptr<DcBackend> cpu = MakeEmbreeBackend();
  // The records come first; the tallies wait for an annual product that fits them
  absl::StatusOr<std::unique_ptr<DesignTallies>> tallies = cpu->StartDesignTallies(scene, options);
  ASSERT_TRUE(tallies.ok()) << tallies.status();
  const BlindDesign a = *DesignWithOverrides(scene, {{"alpha", 0.2}});
  EXPECT_EQ((*tallies)->Tally(a, MetricOptions{}).status().code(),
            absl::StatusCode::kFailedPrecondition);
  const std::vector<Matrix> too_few(outdoor.begin(), outdoor.end() - 1);
  EXPECT_EQ((*tallies)->SetProduct(too_few, sky).code(), absl::StatusCode::kInvalidArgument);
  const std::vector<Matrix> other_rows(outdoor.size(), Matrix::Ones(columns - 1, kDaylightBins));
  EXPECT_EQ((*tallies)->SetProduct(other_rows, sky).code(), absl::StatusCode::kInvalidArgument);
  ASSERT_TRUE((*tallies)->SetProduct(outdoor, sky).ok());
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, a, options);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> product = cpu->MakeAnnualProduct(outdoor, sky);
  ASSERT_TRUE(i.ok() && product.ok());
  absl::StatusOr<std::vector<Matrix>> e = (*product)->Apply(i->batches);
  ASSERT_TRUE(e.ok()) << e.status();
  const MetricOptions limits = QuartileLimits((*e)[0]);
  ExpectIndoorBatchesAreTheTrace(**tallies, a, *i);
  ExpectRoundsEndAsOneCall(**tallies, a,
                           *DesignWithOverrides(scene, {{"alpha", 1.0}, {"width", 0.05}}), limits);
  BlindDesign wide = DefaultDesign(scene);
  wide.slat_width_m = 0.3;
  ExpectTogetherAsAlone(**tallies, {a, *DesignWithOverrides(scene, {{"alpha", 0.5}})}, wide,
                        limits);
}

}  // namespace
}  // namespace fenestra
