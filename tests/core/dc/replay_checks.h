#pragma once

// What the indoor replay tests (CPU and GPU) share: designs across the city office's blind
// ranges, and the check that a replay's I is the full trace's.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "core/dc/indoor_replay.h"
#include "core/dc/two_stage.h"

namespace fenestra {

// Designs at the ends and inside the ranges (overrides of the scene's default design).
inline std::vector<std::map<std::string, double>> ReplayCheckDesigns() {
  return {{{"alpha", 0.0}, {"spacing", 0.0}},
          {{"alpha", 0.8}, {"width", 0.05}},
          {{"alpha", 1.5707963}, {"spacing", 0.1}},
          {{"alpha", 0.3}, {"thickness", 0.02}}};
}

// Expects `replayed` to equal `traced` up to the order of the sums (and the rare path whose
// float rounding differs between the two acceleration structures), with light in both kinds
// of column: the direct ones (the view reaches the sky) and the window cells (it meets the
// street's buildings). Returns the relative L1 difference.
inline double ExpectReplayEqualsTrace(const IndoorResult& traced, const IndoorResult& replayed) {
  EXPECT_EQ(traced.coefficients.cols(), replayed.coefficients.cols());
  if (traced.coefficients.cols() != replayed.coefficients.cols()) return 1.0;
  for (Eigen::Index s = 0; s < traced.coefficients.rows(); ++s) {
    const double a = traced.coefficients.row(s).sum(), b = replayed.coefficients.row(s).sum();
    EXPECT_NEAR(b, a, 1e-6 * a) << "sensor " << s + 1;
  }
  const double difference = (traced.coefficients - replayed.coefficients).cwiseAbs().sum();
  EXPECT_LT(difference, 1e-6 * traced.coefficients.sum());
  EXPECT_GT(replayed.coefficients.rightCols(kDaylightBins).sum(), 0);
  EXPECT_GT(replayed.coefficients.leftCols(replayed.coefficients.cols() - kDaylightBins).sum(), 0);
  return difference / traced.coefficients.sum();
}

}  // namespace fenestra
