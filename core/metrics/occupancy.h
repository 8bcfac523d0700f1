// Occupied hours for the annual metrics.
//
// A time step is occupied when the local standard time of its centre lies in
// [start_hour, end_hour). The default 8:00-18:00 every day is the LEED / IES LM-83 schedule
// as Honeybee applies it (occupancy_schedule_8_to_6): the hourly EPW record for hour h covers
// h-1 .. h and is centred at h - 0.5 (gendaymtx, epw2wea, Ladybug), so records 9..18 of each
// day are occupied, 10 per day, 3650 h in a 365-day year. Daylight saving time is not
// applied. Occupied steps with the sun down stay in the denominator of every metric.
#pragma once

#include <span>
#include <vector>

#include "absl/status/statusor.h"

namespace fenestra {

struct OccupancySchedule {
  double start_hour = 8.0;  // local standard time [h], inclusive
  double end_hour = 18.0;   // local standard time [h], exclusive; start > end wraps midnight
};

// One flag per time step from the decimal local standard time [h, 0..24) of each step's
// centre. InvalidArgument when a schedule hour lies outside [0, 24] or equals the other.
absl::StatusOr<std::vector<bool>> OccupiedSteps(std::span<const double> step_centre_hours,
                                                const OccupancySchedule& schedule = {});

}  // namespace fenestra
