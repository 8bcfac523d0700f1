#include "core/sky/solar_position.h"

#include <cmath>
#include <numbers>

namespace fenestra {
namespace {

constexpr int kDaysBeforeMonth[12] = {0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334};

double Radians(double degrees) { return degrees * (std::numbers::pi / 180); }

}  // namespace

int DayOfYear(int month, int day, bool* after_leap_day) {
  if (month == 2 && day == 29) {
    *after_leap_day = true;
    return 60;
  }
  const int m = month < 1 ? 1 : (month > 12 ? 12 : month);
  return kDaysBeforeMonth[m - 1] + day + (*after_leap_day ? 1 : 0);
}

double SolarDeclinationRad(int day_of_year) {
  return 0.4093 * std::sin(2 * std::numbers::pi * (day_of_year - 81) / 365);
}

double SolarTimeHours(const SolarSite& site, int day_of_year, double standard_time_hours) {
  // Longitudes west positive, as in the handbook formula.
  const double longitude_west = Radians(-site.longitude_deg);
  const double meridian_west = Radians(-15 * site.time_zone_hours);
  return standard_time_hours + 0.170 * std::sin(4 * std::numbers::pi * (day_of_year - 80) / 373) -
         0.129 * std::sin(2 * std::numbers::pi * (day_of_year - 8) / 355) +
         12 * (meridian_west - longitude_west) / std::numbers::pi;
}

SolarPosition ComputeSolarPosition(const SolarSite& site, int day_of_year,
                                   double standard_time_hours) {
  const double latitude = Radians(site.latitude_deg);
  const double declination = SolarDeclinationRad(day_of_year);
  const double hour_angle =
      SolarTimeHours(site, day_of_year, standard_time_hours) * (std::numbers::pi / 12);
  const double sin_altitude = std::sin(latitude) * std::sin(declination) -
                              std::cos(latitude) * std::cos(declination) * std::cos(hour_angle);
  SolarPosition position;
  position.altitude_rad = std::asin(std::fmax(-1.0, std::fmin(1.0, sin_altitude)));
  const double azimuth_south =
      -std::atan2(std::cos(declination) * std::sin(hour_angle),
                  -std::cos(latitude) * std::sin(declination) -
                      std::sin(latitude) * std::cos(declination) * std::cos(hour_angle));
  double azimuth = azimuth_south + std::numbers::pi;
  if (azimuth >= 2 * std::numbers::pi) azimuth -= 2 * std::numbers::pi;
  if (azimuth < 0) azimuth += 2 * std::numbers::pi;
  position.azimuth_rad = azimuth;
  return position;
}

}  // namespace fenestra
