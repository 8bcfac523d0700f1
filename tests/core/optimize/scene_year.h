// A scene's year as the glare tests take it: the sky matrix of its weather file (with the
// scene's ground reflectance) and the occupied steps of the default occupancy.
#pragma once

#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "core/geometry/scene.h"
#include "core/metrics/occupancy.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {

struct SceneYear {
  SkyMatrix sky;
  std::vector<bool> occupied;
  std::vector<double> hours;  // each step's centre, local standard time [h]
};

inline SceneYear YearOf(const Scene& scene) {
  absl::StatusOr<EpwData> epw = ReadEpw(scene.site.weather_file);
  EXPECT_TRUE(epw.ok()) << epw.status();
  SkyMatrixOptions options;
  options.ground_reflectance = scene.site.ground_reflectance;
  absl::StatusOr<SkyMatrix> sky = BuildSkyMatrix(*epw, options);
  EXPECT_TRUE(sky.ok()) << sky.status();
  std::vector<double> hours;
  for (const EpwRecord& r : epw->records)
    hours.push_back(StepCentreHours(r, epw->records_per_hour));
  absl::StatusOr<std::vector<bool>> occupied = OccupiedSteps(hours);
  EXPECT_TRUE(occupied.ok());
  return {*std::move(sky), *std::move(occupied), std::move(hours)};
}

}  // namespace fenestra
