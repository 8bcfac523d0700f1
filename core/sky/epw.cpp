#include "core/sky/epw.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace fenestra {
namespace {

constexpr int kFieldCount = 35;
constexpr int kMaxHeaderLines = 8;
constexpr int kDaysInMonth[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};

// Data-row columns (0-based) and the values from which a field counts as missing.
enum Column {
  kYear = 0,
  kMonth = 1,
  kDay = 2,
  kHour = 3,
  kMinute = 4,
  kDryBulb = 6,
  kDewPoint = 7,
  kGlobalHorizontal = 13,
  kDirectNormal = 14,
  kDiffuseHorizontal = 15,
  kGlobalHorizontalLux = 16,
  kDirectNormalLux = 17,
  kDiffuseHorizontalLux = 18,
};
constexpr double kMissingTemperature = 99.9;
constexpr double kMissingRadiation = 9999;
constexpr double kMissingIlluminance = 999900;

// Builds error messages that name the source and the line.
class LineErrors {
 public:
  explicit LineErrors(absl::string_view source) : source_(source) {}
  template <typename... Args>
  absl::Status operator()(int line, const Args&... args) const {
    return absl::InvalidArgumentError(absl::StrCat(source_, ", line ", line, ": ", args...));
  }

 private:
  absl::string_view source_;
};

absl::string_view Trim(absl::string_view s) { return absl::StripAsciiWhitespace(s); }

bool ParseDouble(absl::string_view field, double* value) {
  return absl::SimpleAtod(Trim(field), value) && std::isfinite(*value);
}

bool ParseInt(absl::string_view field, int* value) { return absl::SimpleAtoi(Trim(field), value); }

std::string ColumnName(int column) {
  switch (column) {
    case kYear:
      return "year";
    case kMonth:
      return "month";
    case kDay:
      return "day";
    case kHour:
      return "hour";
    case kMinute:
      return "minute";
    case kDryBulb:
      return "dry bulb temperature";
    case kDewPoint:
      return "dew point temperature";
    case kGlobalHorizontal:
      return "global horizontal radiation";
    case kDirectNormal:
      return "direct normal radiation";
    case kDiffuseHorizontal:
      return "diffuse horizontal radiation";
    case kGlobalHorizontalLux:
      return "global horizontal illuminance";
    case kDirectNormalLux:
      return "direct normal illuminance";
    case kDiffuseHorizontalLux:
      return "diffuse horizontal illuminance";
    default:
      return "field";
  }
}

// "column 15 (direct normal radiation)"; columns are numbered from 1 for people.
std::string DescribeColumn(int column) {
  return absl::StrCat("column ", column + 1, " (", ColumnName(column), ")");
}

absl::Status ParseLocation(absl::string_view line, const LineErrors& error, EpwLocation* loc) {
  std::vector<absl::string_view> fields = absl::StrSplit(line, ',');
  while (fields.size() > 10 && Trim(fields.back()).empty()) fields.pop_back();
  if (fields.size() < 10) {
    return error(1, "LOCATION needs 10 comma-separated fields, found ", fields.size());
  }
  loc->city = std::string(Trim(fields[1]));
  loc->region = std::string(Trim(fields[2]));
  loc->country = std::string(Trim(fields[3]));
  // The numbers are the last four fields (a city name may hold a comma).
  const size_t first = fields.size() - 4;
  struct NumberField {
    const char* name;
    double* value;
    double lo, hi;
  };
  const NumberField numbers[4] = {
      {"latitude", &loc->latitude_deg, -90, 90},
      {"longitude", &loc->longitude_deg, -180, 180},
      {"time zone", &loc->time_zone_hours, -12, 14},
      {"elevation", &loc->elevation_m, -1000, 9999.9},
  };
  for (int i = 0; i < 4; ++i) {
    const absl::string_view text = Trim(fields[first + i]);
    if (!ParseDouble(text, numbers[i].value)) {
      return error(1, "LOCATION ", numbers[i].name, " is not a number: '", text, "'");
    }
    if (*numbers[i].value < numbers[i].lo || *numbers[i].value > numbers[i].hi) {
      return error(1, "LOCATION ", numbers[i].name, " ", text, " is outside [", numbers[i].lo, ", ",
                   numbers[i].hi, "]");
    }
  }
  return absl::OkStatus();
}

absl::Status ParseDataPeriods(absl::string_view line, int line_number, const LineErrors& error,
                              int* records_per_hour) {
  const std::vector<absl::string_view> fields = absl::StrSplit(line, ',');
  int periods = 0;
  if (fields.size() < 3 || !ParseInt(fields[1], &periods) || periods < 1) {
    return error(line_number, "DATA PERIODS needs a number of periods >= 1");
  }
  if (!ParseInt(fields[2], records_per_hour) || *records_per_hour < 1 || *records_per_hour > 60 ||
      60 % *records_per_hour != 0) {
    return error(line_number, "DATA PERIODS records per hour must divide 60, got '",
                 Trim(fields[2]), "'");
  }
  return absl::OkStatus();
}

// Parses one data row into `record`; counts replaced radiation values in `replaced`.
absl::Status ParseRecord(absl::string_view line, int line_number, int records_per_hour,
                         const EpwReadOptions& options, const LineErrors& error, EpwRecord* record,
                         int* replaced) {
  const std::vector<absl::string_view> fields = absl::StrSplit(line, ',');
  if (fields.size() != kFieldCount) {
    return error(line_number, "expected ", kFieldCount, " comma-separated fields, found ",
                 fields.size(), fields.size() < kFieldCount ? " (truncated row)" : "");
  }
  record->line = line_number;

  // Date and time
  int* date_fields[5] = {&record->year, &record->month, &record->day, &record->hour,
                         &record->minute};
  for (int column = kYear; column <= kMinute; ++column) {
    if (!ParseInt(fields[column], date_fields[column])) {
      return error(line_number, DescribeColumn(column), " is not an integer: '",
                   Trim(fields[column]), "'");
    }
  }
  if (record->month < 1 || record->month > 12) {
    return error(line_number, "month ", record->month, " is outside [1, 12]");
  }
  if (record->day < 1 || record->day > kDaysInMonth[record->month - 1]) {
    return error(line_number, "day ", record->day, " does not exist in month ", record->month);
  }
  if (record->hour < 1 || record->hour > 24) {
    return error(line_number, "hour ", record->hour, " is outside [1, 24]");
  }
  const int min_minute = records_per_hour > 1 ? 1 : 0;
  if (record->minute < min_minute || record->minute > 60) {
    return error(line_number, "minute ", record->minute, " is outside [", min_minute,
                 ", 60] (the minute marks the end of the interval)");
  }

  // Optional quantities: empty or at the missing value -> absent
  auto optional_field = [&](int column, double missing,
                            std::optional<double>* value) -> absl::Status {
    const absl::string_view text = Trim(fields[column]);
    if (text.empty()) return absl::OkStatus();
    double v;
    if (!ParseDouble(text, &v)) {
      return error(line_number, DescribeColumn(column), " is not a number: '", text, "'");
    }
    if (v < missing) *value = v;
    return absl::OkStatus();
  };
  struct Optional {
    int column;
    double missing;
    std::optional<double>* value;
  };
  const Optional optionals[] = {
      {kDryBulb, kMissingTemperature, &record->dry_bulb_c},
      {kDewPoint, kMissingTemperature, &record->dew_point_c},
      {kGlobalHorizontal, kMissingRadiation, &record->global_horizontal_wm2},
      {kGlobalHorizontalLux, kMissingIlluminance, &record->global_horizontal_lux},
      {kDirectNormalLux, kMissingIlluminance, &record->direct_normal_lux},
      {kDiffuseHorizontalLux, kMissingIlluminance, &record->diffuse_horizontal_lux},
  };
  for (const Optional& o : optionals) {
    if (absl::Status s = optional_field(o.column, o.missing, o.value); !s.ok()) return s;
  }

  // Required radiation: missing or negative fails, or becomes 0 when asked
  const std::pair<int, double*> required[] = {
      {kDirectNormal, &record->direct_normal_wm2},
      {kDiffuseHorizontal, &record->diffuse_horizontal_wm2},
  };
  for (const auto& [column, value] : required) {
    const absl::string_view text = Trim(fields[column]);
    const bool empty = text.empty();
    if (!empty && !ParseDouble(text, value)) {
      return error(line_number, DescribeColumn(column), " is not a number: '", text, "'");
    }
    const bool missing = empty || *value >= kMissingRadiation;
    if (!missing && *value >= 0) continue;
    if (!options.treat_missing_as_zero) {
      return error(line_number, DescribeColumn(column), " is ", missing ? "missing" : "negative",
                   " ('", text, "'); the treat-missing-as-zero option reads such values as 0");
    }
    *value = 0;
    ++*replaced;
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<EpwData> ParseEpw(absl::string_view text, absl::string_view source,
                                 const EpwReadOptions& options) {
  EpwData data;
  data.source = std::string(source);
  const LineErrors error(data.source);
  std::vector<absl::string_view> lines = absl::StrSplit(text, '\n');
  for (absl::string_view& line : lines) absl::ConsumeSuffix(&line, "\r");

  // Header: LOCATION first, DATA PERIODS last
  if (lines.empty() || !absl::StartsWithIgnoreCase(lines[0], "LOCATION,")) {
    return error(1, "an EPW file starts with a LOCATION line");
  }
  if (absl::Status s = ParseLocation(lines[0], error, &data.location); !s.ok()) return s;
  size_t index = 1;
  for (;; ++index) {
    const int line_number = static_cast<int>(index) + 1;
    if (index >= lines.size() || index >= kMaxHeaderLines) {
      return error(line_number, "no DATA PERIODS line in the first ", kMaxHeaderLines,
                   " lines of the header");
    }
    const absl::string_view line = Trim(lines[index]);
    if (absl::StartsWithIgnoreCase(line, "DATA PERIODS,")) {
      if (absl::Status s = ParseDataPeriods(line, line_number, error, &data.records_per_hour);
          !s.ok()) {
        return s;
      }
      ++index;
      break;
    }
    if (!line.empty() && absl::ascii_isdigit(static_cast<unsigned char>(line[0]))) {
      return error(line_number, "data row before the DATA PERIODS header line");
    }
  }

  // Data rows
  data.records.reserve(lines.size() - index);
  for (; index < lines.size(); ++index) {
    if (Trim(lines[index]).empty()) continue;
    EpwRecord record;
    if (absl::Status s =
            ParseRecord(lines[index], static_cast<int>(index) + 1, data.records_per_hour, options,
                        error, &record, &data.replaced_radiation_values);
        !s.ok()) {
      return s;
    }
    data.records.push_back(std::move(record));
  }
  if (data.records.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(data.source, ": no data rows"));
  }
  return data;
}

absl::StatusOr<EpwData> ReadEpw(const std::string& path, const EpwReadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open weather file"));
  std::ostringstream contents;
  contents << in.rdbuf();
  if (in.bad()) return absl::DataLossError(absl::StrCat(path, ": read error"));
  return ParseEpw(contents.str(), path, options);
}

}  // namespace fenestra
