#include "core/metrics/occupancy.h"

#include "absl/strings/str_cat.h"

namespace fenestra {

absl::StatusOr<std::vector<bool>> OccupiedSteps(std::span<const double> step_centre_hours,
                                                const OccupancySchedule& schedule) {
  const double start = schedule.start_hour;
  const double end = schedule.end_hour;
  if (!(start >= 0 && start <= 24 && end >= 0 && end <= 24) || start == end) {
    return absl::InvalidArgumentError(absl::StrCat("occupancy from ", start, " h to ", end,
                                                   " h: hours must lie in [0, 24] and differ"));
  }
  std::vector<bool> occupied(step_centre_hours.size());
  for (size_t t = 0; t < step_centre_hours.size(); ++t) {
    const double hour = step_centre_hours[t];
    occupied[t] = start < end ? (hour >= start && hour < end) : (hour >= start || hour < end);
  }
  return occupied;
}

}  // namespace fenestra
