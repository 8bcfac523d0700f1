// Builds small EPW texts for the sky tests.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/sky/epw.h"

namespace fenestra::testing {

// The 8 header lines of an EPW file for a site whose one data period runs from `first_day`
// to `last_day` (month/day).
inline std::string EpwHeader(double latitude_deg, double longitude_deg, double time_zone_hours,
                             int records_per_hour = 1, const std::string& elevation = "10",
                             const std::string& first_day = " 1/ 1",
                             const std::string& last_day = "12/31") {
  return absl::StrCat("LOCATION,Test Site,-,TST,Fixture,000000,", latitude_deg, ",", longitude_deg,
                      ",", time_zone_hours, ",", elevation,
                      "\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\n"
                      "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,fixture\nCOMMENTS 2,fixture\n"
                      "DATA PERIODS,1,",
                      records_per_hour, ",Data,Sunday,", first_day, ",", last_day, "\n");
}

// One data row (35 fields) with the given direct normal and diffuse horizontal radiation;
// global horizontal radiation and the illuminances are marked missing.
inline std::string EpwRow(int month, int day, int hour, double direct_normal,
                          double diffuse_horizontal, int minute = 60, double dew_point = 10) {
  return absl::StrFormat(
      "2001,%d,%d,%d,%d,?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9,20.0,%g,70,101300,"
      "0,1415,350,9999,%g,%g,999999,999999,999999,9999,180,2.0,5,5,20.0,77777,9,999999999,0,"
      "0.1000,0,88,0.200,0.0,0.0\n",
      month, day, hour, minute, dew_point, direct_normal, diffuse_horizontal);
}

// A whole day of hourly rows without radiation; `rows` replaces some of them (hour -> row).
inline std::string EpwDay(int month, int day, const std::map<int, std::string>& rows = {}) {
  std::string text;
  for (int hour = 1; hour <= 24; ++hour) {
    auto it = rows.find(hour);
    text += it != rows.end() ? it->second : EpwRow(month, day, hour, 0, 0);
  }
  return text;
}

// Days in each month of a year without Feb 29.
inline constexpr int kFixtureDaysInMonth[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};

// A whole hourly year in which every hour has the same radiation.
inline std::string ConstantYearEpw(double latitude_deg, double longitude_deg,
                                   double time_zone_hours, double direct_normal,
                                   double diffuse_horizontal) {
  std::string text = EpwHeader(latitude_deg, longitude_deg, time_zone_hours);
  for (int month = 1; month <= 12; ++month) {
    for (int day = 1; day <= kFixtureDaysInMonth[month - 1]; ++day) {
      for (int hour = 1; hour <= 24; ++hour) {
        text += EpwRow(month, day, hour, direct_normal, diffuse_horizontal);
      }
    }
  }
  return text;
}

// One weather step as the sky matrix reads it (what EpwRow writes), built without the parser.
inline EpwRecord Step(int month, int day, int hour, double direct_normal, double diffuse_horizontal,
                      int minute = 60, double dew_point = 10) {
  EpwRecord r;
  r.year = 2001, r.month = month, r.day = day, r.hour = hour, r.minute = minute;
  r.dry_bulb_c = 20;
  if (dew_point < 99.9) r.dew_point_c = dew_point;
  r.direct_normal_wm2 = direct_normal;
  r.diffuse_horizontal_wm2 = diffuse_horizontal;
  return r;
}

// Weather of hand-picked steps (any hours, in any order) for a site: what a sky test needs,
// where the parser would ask for whole data periods.
inline EpwData Weather(double latitude_deg, double longitude_deg, double time_zone_hours,
                       std::vector<EpwRecord> steps, int records_per_hour = 1) {
  EpwData data;
  data.source = "fixture";
  data.location.latitude_deg = latitude_deg;
  data.location.longitude_deg = longitude_deg;
  data.location.time_zone_hours = time_zone_hours;
  data.records_per_hour = records_per_hour;
  data.records = std::move(steps);
  return data;
}

}  // namespace fenestra::testing
