// Builds small EPW texts for the sky tests.
#pragma once

#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace fenestra::testing {

// The 8 header lines of an EPW file for a site.
inline std::string EpwHeader(double latitude_deg, double longitude_deg, double time_zone_hours,
                             int records_per_hour = 1, const std::string& elevation = "10") {
  return absl::StrCat("LOCATION,Test Site,-,TST,Fixture,000000,", latitude_deg, ",", longitude_deg,
                      ",", time_zone_hours, ",", elevation,
                      "\nDESIGN CONDITIONS,0\nTYPICAL/EXTREME PERIODS,0\nGROUND TEMPERATURES,0\n"
                      "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0\nCOMMENTS 1,fixture\nCOMMENTS 2,fixture\n"
                      "DATA PERIODS,1,",
                      records_per_hour, ",Data,Sunday, 1/ 1,12/31\n");
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

}  // namespace fenestra::testing
