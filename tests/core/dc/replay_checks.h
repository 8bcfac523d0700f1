#pragma once

// What the indoor replay tests (CPU and GPU) share: designs across the city office's blind
// ranges, and the check that a replay's I is the full trace's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/dc/dc_backend.h"
#include "core/dc/indoor_replay.h"
#include "core/dc/two_stage.h"
#include "core/metrics/annual_metrics.h"

namespace fenestra {

// Designs at the ends and inside the ranges (overrides of the scene's default design).
inline std::vector<std::map<std::string, double>> ReplayCheckDesigns() {
  return {{{"alpha", 0.0}, {"spacing", 0.0}},
          {{"alpha", 0.8}, {"width", 0.05}},
          {{"alpha", 1.5707963}, {"spacing", 0.1}},
          {{"alpha", 0.3}, {"thickness", 0.02}}};
}

// Expects `replayed` to equal `traced` up to the order of the sums and, on the GPU, the rare
// shadow ray that grazes a slat's edge, which the slats' layout (LocalSlats) and their
// triangles may answer differently within float rounding (about one in a million: a few
// connections, each up to 1e-4 of a sensor's light), with light in both kinds of column: the direct
// ones (the view reaches the sky) and the window cells (it meets the street's buildings). Returns
// the relative L1 difference.
inline double ExpectReplayEqualsTrace(const IndoorResult& traced, const IndoorResult& replayed) {
  EXPECT_EQ(traced.coefficients.cols(), replayed.coefficients.cols());
  if (traced.coefficients.cols() != replayed.coefficients.cols()) return 1.0;
  for (Eigen::Index s = 0; s < traced.coefficients.rows(); ++s) {
    const double a = traced.coefficients.row(s).sum(), b = replayed.coefficients.row(s).sum();
    EXPECT_NEAR(b, a, 5e-4 * a) << "sensor " << s + 1;
  }
  const double difference = (traced.coefficients - replayed.coefficients).cwiseAbs().sum();
  EXPECT_LT(difference, 3e-5 * traced.coefficients.sum());
  EXPECT_GT(replayed.coefficients.rightCols(kDaylightBins).sum(), 0);
  EXPECT_GT(replayed.coefficients.leftCols(replayed.coefficients.cols() - kDaylightBins).sum(), 0);
  return difference / traced.coefficients.sum();
}

// For each design of ReplayCheckDesigns, `replay`'s I equals the indoor stage of `scene` traced
// in full by `backend` (the CPU's where null) with `options`, as ExpectReplayEqualsTrace has
// it; `also`, where given, then checks more at the design. Outside the recorded ranges the
// replay refuses, as it would be wrong there.
inline void ExpectReplayIsTheTrace(const Scene& scene, const IndoorOptions& options,
                                   const IndoorStages& replay, DcBackend* backend = nullptr,
                                   const std::function<void(const BlindDesign&)>& also = nullptr) {
  for (const auto& values : ReplayCheckDesigns()) {
    absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, values);
    ASSERT_TRUE(design.ok()) << design.status();
    absl::StatusOr<IndoorResult> traced = ComputeIndoorStage(scene, *design, options, backend);
    absl::StatusOr<IndoorResult> replayed = replay.Compute(*design);
    ASSERT_TRUE(traced.ok() && replayed.ok()) << traced.status() << replayed.status();
    EXPECT_NE(replayed->backend.find("replay"), std::string::npos) << replayed->backend;
    ASSERT_EQ(traced->coefficients.cols(), replayed->coefficients.cols());
    std::printf(
        "replay against full trace: %.3g relative L1 difference; replay %.2f ms, full %.2f ms\n",
        ExpectReplayEqualsTrace(*traced, *replayed), 1e3 * replayed->wall_seconds,
        1e3 * traced->wall_seconds);
    if (also) also(*design);
  }
  BlindDesign wide = DefaultDesign(scene);
  wide.slat_width_m = 0.3;
  EXPECT_EQ(replay.Compute(wide).status().code(), absl::StatusCode::kInvalidArgument);
}

// The tallies' I of `design` (DesignTallies::IndoorBatches, which gives the best design's
// hourly illuminance) is `traced`'s, the design's indoor stage traced in full: the same
// batches, and their mean equal as ExpectReplayEqualsTrace has it.
inline void ExpectIndoorBatchesAreTheTrace(DesignTallies& tallies, const BlindDesign& design,
                                           const IndoorResult& traced) {
  absl::StatusOr<std::vector<Matrix>> batches = tallies.IndoorBatches(design);
  ASSERT_TRUE(batches.ok()) << batches.status();
  ASSERT_EQ(batches->size(), traced.batches.size());
  IndoorResult replayed;
  replayed.coefficients = Matrix::Zero(traced.coefficients.rows(), traced.coefficients.cols());
  for (const Matrix& b : *batches) {
    ASSERT_EQ(b.rows(), replayed.coefficients.rows());
    ASSERT_EQ(b.cols(), replayed.coefficients.cols());
    replayed.coefficients += b / static_cast<double>(batches->size());
  }
  ExpectReplayEqualsTrace(traced, replayed);
}

// Metric limits at the quartiles of `illuminance`, so that sensors fall on either side.
inline MetricOptions QuartileLimits(const Matrix& illuminance) {
  std::vector<double> values(illuminance.data(), illuminance.data() + illuminance.size());
  std::sort(values.begin(), values.end());
  MetricOptions options;
  options.udi_lower_lux = values[values.size() / 4];
  options.da_threshold_lux = values[values.size() / 2];
  options.udi_upper_lux = values[3 * values.size() / 4];
  return options;
}

// Expects the tallies `a` and `b` equal but for the order of their sums: a few hours may
// change side of a limit in the last bit. Returns the relative difference of sensor 0's
// illuminance sums in version 0.
inline double ExpectTalliesEqual(const std::vector<HourTally>& a, const std::vector<HourTally>& b) {
  EXPECT_EQ(a.size(), b.size());
  if (a.size() != b.size()) return 1.0;
  for (size_t v = 0; v < a.size(); ++v) {
    EXPECT_EQ(a[v].hours, b[v].hours);
    EXPECT_NEAR(a[v].all_in, b[v].all_in, 1) << "version " << v;
    EXPECT_NEAR(a[v].any_below, b[v].any_below, 1) << "version " << v;
    EXPECT_NEAR(a[v].any_above, b[v].any_above, 1) << "version " << v;
    EXPECT_EQ(a[v].sensors.size(), b[v].sensors.size());
    for (size_t i = 0; i < a[v].sensors.size() && i < b[v].sensors.size(); ++i) {
      const SensorHourTally &x = a[v].sensors[i], &y = b[v].sensors[i];
      EXPECT_NEAR(x.below, y.below, 1) << "version " << v << " sensor " << i;
      EXPECT_NEAR(x.above, y.above, 1) << "version " << v << " sensor " << i;
      EXPECT_NEAR(x.da, y.da, 1) << "version " << v << " sensor " << i;
      EXPECT_NEAR(x.sum, y.sum, 1e-9 * y.sum) << "version " << v << " sensor " << i;
      EXPECT_NEAR(x.credit, y.credit, 1e-9 * y.credit) << "version " << v << " sensor " << i;
    }
  }
  return std::abs(a[0].sensors[0].sum - b[0].sensors[0].sum) / b[0].sensors[0].sum;
}

// A design traced in rounds (1 part, 3, then all) ends where one call for all parts does,
// also when another design's round came between (its parts are traced anew); a round's
// tallies are those of fewer paths, not the full ones.
inline void ExpectRoundsEndAsOneCall(DesignTallies& tallies, const BlindDesign& a,
                                     const BlindDesign& b, const MetricOptions& options) {
  ASSERT_TRUE(tallies.TracesInParts());
  absl::StatusOr<std::vector<HourTally>> full_a = tallies.Tally(a, options);
  absl::StatusOr<std::vector<HourTally>> full_b = tallies.Tally(b, options);
  ASSERT_TRUE(full_a.ok() && full_b.ok()) << full_a.status() << full_b.status();

  const uint64_t rays = tallies.RaysTraced();
  absl::StatusOr<std::vector<HourTally>> first = tallies.Tally(a, options, 1);
  const uint64_t first_rays = tallies.RaysTraced() - rays;
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE(tallies.Tally(a, options, 3).ok());
  absl::StatusOr<std::vector<HourTally>> rounds_a = tallies.Tally(a, options, kDesignParts);
  ASSERT_TRUE(rounds_a.ok()) << rounds_a.status();
  const uint64_t all_rays = tallies.RaysTraced() - rays;
  ExpectTalliesEqual(*rounds_a, *full_a);
  // One part of eight traced an eighth of the rays, and its tallies are another estimate
  EXPECT_NEAR(static_cast<double>(first_rays) / static_cast<double>(all_rays), 1.0 / kDesignParts,
              0.02);
  EXPECT_GT(std::abs((*first)[0].sensors[0].sum / (*full_a)[0].sensors[0].sum - 1), 1e-6);

  ASSERT_TRUE(tallies.Tally(a, options, 2).ok());
  ASSERT_TRUE(tallies.Tally(b, options, 2).ok());
  absl::StatusOr<std::vector<HourTally>> rounds_b = tallies.Tally(b, options, kDesignParts);
  ASSERT_TRUE(rounds_b.ok()) << rounds_b.status();
  ExpectTalliesEqual(*rounds_b, *full_b);
  EXPECT_EQ(tallies.Tally(b, options, 0).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(tallies.Tally(b, options, kDesignParts + 1).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// Designs tallied together (DesignTallies::TallyDesigns) give what each gives alone; a
// design the tallies refuse gets its error without taking the others' results; rounds of a
// design after them still end as one call does.
inline void ExpectTogetherAsAlone(DesignTallies& tallies, const std::vector<BlindDesign>& designs,
                                  const BlindDesign& refused, const MetricOptions& options) {
  std::vector<std::vector<HourTally>> alone;
  for (const BlindDesign& design : designs) {
    absl::StatusOr<std::vector<HourTally>> tally = tallies.Tally(design, options);
    ASSERT_TRUE(tally.ok()) << tally.status();
    alone.push_back(*std::move(tally));
  }
  std::vector<BlindDesign> asked = designs;
  asked.insert(asked.begin() + 1, refused);
  const std::vector<absl::StatusOr<std::vector<HourTally>>> together =
      tallies.TallyDesigns(asked, options);
  ASSERT_EQ(together.size(), asked.size());
  EXPECT_EQ(together[1].status().code(), absl::StatusCode::kInvalidArgument);
  for (size_t i = 0; i < designs.size(); ++i) {
    const absl::StatusOr<std::vector<HourTally>>& tally = together[i < 1 ? i : i + 1];
    ASSERT_TRUE(tally.ok()) << tally.status();
    ExpectTalliesEqual(*tally, alone[i]);
  }
  // Designs that differ give different tallies (the comparison is not of one design)
  EXPECT_NE((*together[0])[0].sensors[0].sum, (*together[2])[0].sensors[0].sum);
  if (tallies.TracesInParts()) {
    ASSERT_TRUE(tallies.Tally(designs.back(), options, 2).ok());
    absl::StatusOr<std::vector<HourTally>> rounds = tallies.Tally(designs.back(), options);
    ASSERT_TRUE(rounds.ok()) << rounds.status();
    ExpectTalliesEqual(*rounds, alone.back());
  }
}

}  // namespace fenestra
