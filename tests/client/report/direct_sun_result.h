#pragma once

// A job result with the direct-sun fields set by hand, for tests of the report: ASE, the
// sensors' sunlit hours, LEED points, the blind operated (AUTOMATED_SUN) and in place in some
// hours, the hourly direct sun and an ASE constraint. The quick job's result (9 sensors, 8760
// hourly steps) with these numbers:
//   - sensors 0 and 1 get 1500 lx of direct sun, sensor 2 800 lx, from 10 to 14 h every day of
//     January, February and December (360 steps, all occupied), no other sun;
//   - the blind is in place exactly in those steps;
//   - sunlit hours 400, 260, 249, 0, 0, 0, 10, 0, 0: 2 sensors at 250 h or more, ASE 22.22 %;
//   - blind in place 9.86 %, LEED 1 point, the objective constrained to ASE at most 10 %.
#include "fenestra/v1/job.pb.h"

namespace fenestra {

inline constexpr double kDirectSunAse = 200.0 / 9;

inline v1::JobResult WithDirectSun(v1::JobResult r) {
  v1::Job& job = *r.mutable_job();
  job.mutable_scene()->mutable_blind()->set_operation(v1::VenetianBlind::AUTOMATED_SUN);
  job.mutable_metrics()->set_ase_threshold_lux(1000);
  job.mutable_metrics()->set_ase_min_hours(250);
  job.mutable_metrics()->set_operation_sensor_percent(2);
  job.mutable_metrics()->set_operation_threshold_lux(1000);
  job.mutable_objective()->clear_constraints();
  v1::Constraint& ase = *job.mutable_objective()->add_constraints();
  ase.set_metric(v1::METRIC_ASE);
  ase.set_bound(v1::Constraint::AT_MOST);
  ase.set_value(10);
  r.clear_best_constraints();

  v1::Metrics& m = *r.mutable_best_metrics();
  m.mutable_ase()->set_value(kDirectSunAse);
  m.mutable_ase()->set_standard_error(0);
  m.mutable_blind_in_place()->set_value(9.86);
  m.mutable_blind_in_place()->set_standard_error(0);
  m.clear_sensor_sunlit_hours();
  for (const int hours : {400, 260, 249, 0, 0, 0, 10, 0, 0}) m.add_sensor_sunlit_hours(hours);
  m.set_leed_points(1);

  v1::HourlyIlluminance& h = *r.mutable_best_hourly();
  const int steps = h.month_size(), sensors = h.sensors_size();
  h.clear_direct_sun_lux();
  h.clear_blind_in_place();
  for (int i = 0; i < sensors; ++i) {
    for (int j = 0; j < steps; ++j) {
      const bool sun = (h.month(j) <= 2 || h.month(j) == 12) && h.hour(j) > 10 && h.hour(j) < 14;
      h.add_direct_sun_lux(!sun ? 0.0f : i < 2 ? 1500.0f : i == 2 ? 800.0f : 0.0f);
      if (i == 0) h.add_blind_in_place(sun);
    }
  }
  return r;
}

// `r` without any of the direct-sun fields: what a result from before them holds.
inline v1::JobResult WithoutDirectSun(v1::JobResult r) {
  v1::Metrics& m = *r.mutable_best_metrics();
  m.clear_ase();
  m.clear_blind_in_place();
  m.clear_sensor_sunlit_hours();
  m.clear_leed_points();
  r.mutable_best_hourly()->clear_direct_sun_lux();
  r.mutable_best_hourly()->clear_blind_in_place();
  r.mutable_job()->mutable_objective()->clear_constraints();
  r.mutable_job()->mutable_scene()->mutable_blind()->clear_operation();
  r.clear_best_constraints();
  return r;
}

}  // namespace fenestra
