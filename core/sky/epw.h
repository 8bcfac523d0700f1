// EnergyPlus weather (EPW) reader: the LOCATION and DATA PERIODS header lines and the
// hourly or sub-hourly data rows, as described in the EnergyPlus "Auxiliary Programs"
// weather-data dictionary (35 comma-separated fields per row).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace fenestra {

// The LOCATION header line.
struct EpwLocation {
  std::string city;
  std::string region;
  std::string country;
  double latitude_deg = 0;     // north positive, [-90, 90]
  double longitude_deg = 0;    // east positive, [-180, 180]
  double time_zone_hours = 0;  // offset of local standard time from GMT, [-12, 14]
  double elevation_m = 0;
};

// One data row. Radiation is the mean over the interval that ends at (hour, minute).
struct EpwRecord {
  int line = 0;  // 1-based line number in the file
  int year = 0;
  int month = 1;   // 1..12
  int day = 1;     // 1..31
  int hour = 1;    // 1..24; hour 1 covers 00:00-01:00 local standard time
  int minute = 0;  // 0..60
  std::optional<double> dry_bulb_c;
  std::optional<double> dew_point_c;
  std::optional<double> global_horizontal_wm2;
  double direct_normal_wm2 = 0;
  double diffuse_horizontal_wm2 = 0;
  std::optional<double> global_horizontal_lux;
  std::optional<double> direct_normal_lux;
  std::optional<double> diffuse_horizontal_lux;
};

// A whole weather file.
struct EpwData {
  std::string source;  // file name used in messages
  EpwLocation location;
  int records_per_hour = 1;
  std::vector<EpwRecord> records;
  // Direct normal or diffuse horizontal values that were missing (>= 9999) or negative
  // and were replaced by 0 (only with EpwReadOptions::treat_missing_as_zero).
  int replaced_radiation_values = 0;
};

struct EpwReadOptions {
  // Replace missing or negative direct normal / diffuse horizontal radiation by 0 and
  // count them, instead of failing.
  bool treat_missing_as_zero = false;
};

// Reads an EPW file. Errors (InvalidArgument, NotFound) name the file and the line.
absl::StatusOr<EpwData> ReadEpw(const std::string& path, const EpwReadOptions& options = {});

// Parses EPW text; `source` names it in error messages.
absl::StatusOr<EpwData> ParseEpw(absl::string_view text, absl::string_view source,
                                 const EpwReadOptions& options = {});

}  // namespace fenestra
