// Solar position as gendaymtx computes it (Radiance sun.c), from the IES Lighting Handbook
// (1981) formulas:
//   declination  d = 0.4093 sin(2 pi (J - 81) / 365)
//   solar time   t = t_std + 0.170 sin(4 pi (J - 80) / 373) - 0.129 sin(2 pi (J - 8) / 355)
//                    + 12 (L_meridian - L) / pi          (longitudes in radians, west positive)
//   altitude     sin a = sin(lat) sin d - cos(lat) cos d cos(pi t / 12)
//   azimuth      A_south = -atan2(cos d sin(pi t / 12),
//                                 -cos(lat) sin d - sin(lat) cos d cos(pi t / 12))
// with J the day of year without leap days (Feb 29 counts as day 60, later dates one more),
// and the azimuth reported from north towards east (A_south + pi).
#pragma once

namespace fenestra {

// Where the sun is computed for.
struct SolarSite {
  double latitude_deg = 0;     // north positive
  double longitude_deg = 0;    // east positive
  double time_zone_hours = 0;  // standard time offset from GMT, east positive
};

// Sun direction at one instant.
struct SolarPosition {
  double altitude_rad = 0;  // above the horizon; negative at night
  double azimuth_rad = 0;   // from north towards east, in [0, 2 pi)
};

// Half the angular diameter of the sun (0.533 / 2 degrees), in radians.
inline constexpr double kSunHalfAngleRad = 0.2665 * 3.14159265358979323846 / 180;

// Day of year 1..365 in gendaymtx's numbering, which has no leap years: Feb 29 is day 60
// and sets *after_leap_day, which adds one to every later date. `month` is 1..12.
int DayOfYear(int month, int day, bool* after_leap_day);

// Solar declination in radians on day `day_of_year`.
double SolarDeclinationRad(int day_of_year);

// Apparent solar time in hours at local standard time `standard_time_hours`.
double SolarTimeHours(const SolarSite& site, int day_of_year, double standard_time_hours);

// Sun position at local standard time `standard_time_hours` (decimal hours, 0..24).
SolarPosition ComputeSolarPosition(const SolarSite& site, int day_of_year,
                                   double standard_time_hours);

// Whether any part of the solar disc is above the horizon.
inline bool SunInSky(double altitude_rad) { return altitude_rad > -kSunHalfAngleRad; }

}  // namespace fenestra
