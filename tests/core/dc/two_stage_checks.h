#pragma once

// What the tests of several windows share between the backends: the two-stage method against
// the one-stage method over a grid of designs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"

namespace fenestra {

// Over a grid of designs (alpha x spacing), the two-stage sky sums of `scene` lie within 3
// combined SE + 1% of the one-stage ones at every one of its `sensors` sensors, both methods
// traced by `backend` (the CPU's where null). Seeds are fixed.
inline void ExpectTwoStageMatchesOneStage(const Scene& scene, int sensors,
                                          DcBackend* backend = nullptr) {
  OutdoorOptions outdoor;
  outdoor.paths = 4'000'000;
  outdoor.parts = WindowParts{0, 0};  // each window's automatic split
  outdoor.seed = 7;
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor, backend);
  ASSERT_TRUE(o.ok()) << o.status();
  int compared = 0;
  double largest = 0;  // in combined SE
  for (const double alpha : {0.0, 0.8, 1.5}) {
    for (const double spacing : {0.0, 0.1}) {
      absl::StatusOr<BlindDesign> design =
          DesignWithOverrides(scene, {{"alpha", alpha}, {"spacing", spacing}});
      ASSERT_TRUE(design.ok()) << design.status();
      OneStageOptions one_stage;
      one_stage.paths_per_sensor = 20000;
      one_stage.seed = 5;
      absl::StatusOr<OneStageResult> one = ComputeOneStage(scene, *design, one_stage, backend);
      ASSERT_TRUE(one.ok()) << one.status();
      IndoorOptions indoor;
      indoor.paths_per_sensor = 20000;
      indoor.parts = outdoor.parts;
      indoor.seed = 11;
      absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, *design, indoor, backend);
      ASSERT_TRUE(i.ok()) << i.status();
      absl::StatusOr<TwoStageResult> two = CombineStages(*i, *o);
      ASSERT_TRUE(two.ok()) << two.status();
      for (Eigen::Index s = 0; s < one->sky_sum.size(); ++s, ++compared) {
        const double se =
            std::hypot(one->sky_sum_standard_error(s), two->sky_sum_standard_error(s));
        largest = std::max(largest, std::abs(two->sky_sum(s) - one->sky_sum(s)) / se);
        EXPECT_NEAR(two->sky_sum(s), one->sky_sum(s), 3 * se + 0.01 * one->sky_sum(s))
            << "alpha " << alpha << ", spacing " << spacing << ", sensor " << s;
      }
    }
  }
  EXPECT_EQ(compared, 6 * sensors);
  std::printf("two-stage against one-stage: %d sky sums, largest difference %.2f combined SE\n",
              compared, largest);
}

}  // namespace fenestra
