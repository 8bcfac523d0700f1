#include "core/sky/epw.h"

#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/common/text.h"

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
      return error(1, "LOCATION ", numbers[i].name, " is not a number: ", QuoteText(text));
    }
    if (*numbers[i].value < numbers[i].lo || *numbers[i].value > numbers[i].hi) {
      return error(1, "LOCATION ", numbers[i].name, " ", *numbers[i].value, " is outside [",
                   numbers[i].lo, ", ", numbers[i].hi, "]");
    }
  }
  return absl::OkStatus();
}

// A day of the year, as EPW dates write it.
struct MonthDay {
  int month = 1;
  int day = 1;
  bool operator==(const MonthDay&) const = default;
};

// One DATA PERIODS entry: the rows cover whole days from `start` to `end`.
struct DataPeriod {
  MonthDay start, end;
};

// "m/d" or "m/d/yyyy" (the year is not used).
bool ParseMonthDay(absl::string_view text, MonthDay* date) {
  const std::vector<absl::string_view> parts = absl::StrSplit(Trim(text), '/');
  if (parts.size() != 2 && parts.size() != 3) return false;
  int year = 0;
  if (!ParseInt(parts[0], &date->month) || !ParseInt(parts[1], &date->day)) return false;
  if (parts.size() == 3 && !ParseInt(parts[2], &year)) return false;
  return date->month >= 1 && date->month <= 12 && date->day >= 1 &&
         date->day <= kDaysInMonth[date->month - 1];
}

// DATA PERIODS,<count>,<records per hour>, then per period: name, start weekday, start
// date, end date.
absl::Status ParseDataPeriods(absl::string_view line, int line_number, const LineErrors& error,
                              int* records_per_hour, std::vector<DataPeriod>* periods) {
  const std::vector<absl::string_view> fields = absl::StrSplit(line, ',');
  int count = 0;
  if (fields.size() < 3 || !ParseInt(fields[1], &count) || count < 1) {
    return error(line_number, "DATA PERIODS needs a number of periods >= 1");
  }
  if (!ParseInt(fields[2], records_per_hour) || *records_per_hour < 1 || *records_per_hour > 60 ||
      60 % *records_per_hour != 0) {
    return error(line_number, "DATA PERIODS records per hour must divide 60, got ",
                 QuoteText(Trim(fields[2])));
  }
  if (fields.size() < 3 + 4 * static_cast<size_t>(count)) {
    return error(line_number, "DATA PERIODS declares ", count, " periods but has ", fields.size(),
                 " fields; each period needs 4 (name, start weekday, start date, end date)");
  }
  for (int k = 0; k < count; ++k) {
    DataPeriod period;
    const size_t start = 5 + 4 * static_cast<size_t>(k), end = start + 1;
    if (!ParseMonthDay(fields[start], &period.start) || !ParseMonthDay(fields[end], &period.end)) {
      return error(line_number, "DATA PERIODS fields ", start + 1, " and ", end + 1,
                   " (start and end date of period ", k + 1, ") must be month/day dates, got ",
                   QuoteText(Trim(fields[start])), " and ", QuoteText(Trim(fields[end])));
    }
    periods->push_back(period);
  }
  return absl::OkStatus();
}

// One time step: a day, an hour (1..24) and the interval within the hour (1..records per
// hour).
struct Step {
  MonthDay date;
  int hour = 1;
  int interval = 1;
  bool operator==(const Step&) const = default;
};

std::string DescribeStep(const Step& s, int records_per_hour) {
  return absl::StrCat(
      s.date.month, "/", s.date.day, " hour ", s.hour,
      records_per_hour > 1 ? absl::StrCat(" minute ", s.interval * 60 / records_per_hour) : "");
}

MonthDay NextDay(MonthDay d) {
  if (d.day < kDaysInMonth[d.month - 1]) return {d.month, d.day + 1};
  return {d.month % 12 + 1, 1};
}

// Checks that the data rows are consecutive time steps covering the DATA PERIODS exactly:
// each period from hour 1 of its start date to hour 24 of its end date. February 29 may be
// present or left out.
class StepSequence {
 public:
  StepSequence(std::vector<DataPeriod> periods, int records_per_hour)
      : periods_(std::move(periods)), records_per_hour_(records_per_hour) {}

  absl::Status Next(const EpwRecord& record, const LineErrors& error) {
    if (period_ >= periods_.size()) {
      return error(record.line, "a row after the end of the last data period (",
                   DescribeEnd(periods_.back()), "); the DATA PERIODS line must cover every row");
    }
    const Step step{{record.month, record.day}, record.hour, IntervalOf(record)};
    if (step.interval < 1) {
      return error(record.line, DescribeColumn(kMinute), " ", record.minute,
                   " is not the end of a ", 60 / records_per_hour_, "-minute interval");
    }
    if (!Expected(step)) {
      return error(record.line, "columns 2-5 (month, day, hour, minute) give ",
                   DescribeStep(step, records_per_hour_), ", expected ", DescribeExpected(),
                   ": rows must be consecutive time steps of the DATA PERIODS");
    }
    previous_ = step;
    last_line_ = record.line;
    const DataPeriod& period = periods_[period_];
    if (step.date == period.end && step.hour == 24 && step.interval == records_per_hour_) {
      ++period_;
      previous_.reset();
    }
    return absl::OkStatus();
  }

  // After the last row: every period must be complete.
  absl::Status Finish(const LineErrors& error) const {
    if (period_ >= periods_.size()) return absl::OkStatus();
    if (!previous_) {
      return error(last_line_, "the rows end before data period ", period_ + 1, " (",
                   DescribeEnd(periods_[period_]), ") begins: the file is truncated");
    }
    return error(last_line_, "the rows end at ", DescribeStep(*previous_, records_per_hour_),
                 ", before the end of data period ", period_ + 1, " (",
                 DescribeEnd(periods_[period_]), "): the file is truncated");
  }

 private:
  int IntervalOf(const EpwRecord& r) const {
    if (records_per_hour_ == 1) return 1;
    const int minutes = 60 / records_per_hour_;
    return r.minute % minutes == 0 ? r.minute / minutes : 0;
  }

  bool Expected(const Step& step) const {
    if (!previous_) return step == Step{periods_[period_].start, 1, 1};
    Step next = *previous_;
    if (next.interval < records_per_hour_)
      return step == Step{next.date, next.hour, next.interval + 1};
    if (next.hour < 24) return step == Step{next.date, next.hour + 1, 1};
    const MonthDay day = NextDay(next.date);
    if (step == Step{day, 1, 1}) return true;
    // February 29 may be left out
    return day == MonthDay{2, 29} && step == Step{MonthDay{3, 1}, 1, 1};
  }

  std::string DescribeExpected() const {
    if (!previous_) {
      return absl::StrCat(DescribeStep({periods_[period_].start, 1, 1}, records_per_hour_),
                          " (the start of data period ", period_ + 1, ")");
    }
    return absl::StrCat("the step after ", DescribeStep(*previous_, records_per_hour_));
  }

  std::string DescribeEnd(const DataPeriod& p) const {
    return absl::StrCat(p.start.month, "/", p.start.day, " to ", p.end.month, "/", p.end.day);
  }

  std::vector<DataPeriod> periods_;
  int records_per_hour_;
  size_t period_ = 0;
  std::optional<Step> previous_;
  int last_line_ = 0;
};

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
      return error(line_number, DescribeColumn(column),
                   " is not an integer: ", QuoteText(Trim(fields[column])));
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
      return error(line_number, DescribeColumn(column), " is not a number: ", QuoteText(text));
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
      return error(line_number, DescribeColumn(column), " is not a number: ", QuoteText(text));
    }
    const bool missing = empty || *value >= kMissingRadiation;
    if (!missing && *value >= 0) continue;
    if (!options.treat_missing_as_zero) {
      return error(line_number, DescribeColumn(column), " is ", missing ? "missing" : "negative",
                   " (", QuoteText(text),
                   "); the treat-missing-as-zero option reads such values as 0");
    }
    *value = 0;
    ++*replaced;
  }
  return absl::OkStatus();
}

// Reads the header lines into `data` and `periods`; returns the index of the first line
// after them.
absl::StatusOr<size_t> ParseHeader(const std::vector<absl::string_view>& lines,
                                   const LineErrors& error, EpwData* data,
                                   std::vector<DataPeriod>* periods) {
  if (lines.empty() || !absl::StartsWithIgnoreCase(lines[0], "LOCATION,")) {
    return error(1, "an EPW file starts with a LOCATION line");
  }
  if (absl::Status s = ParseLocation(lines[0], error, &data->location); !s.ok()) return s;
  for (size_t index = 1;; ++index) {
    const int line_number = static_cast<int>(index) + 1;
    if (index >= lines.size() || index >= kMaxHeaderLines) {
      return error(line_number, "no DATA PERIODS line in the first ", kMaxHeaderLines,
                   " lines of the header");
    }
    const absl::string_view line = Trim(lines[index]);
    if (absl::StartsWithIgnoreCase(line, "DATA PERIODS,")) {
      absl::Status s = ParseDataPeriods(line, line_number, error, &data->records_per_hour, periods);
      if (!s.ok()) return s;
      return index + 1;
    }
    if (!line.empty() && absl::ascii_isdigit(static_cast<unsigned char>(line[0]))) {
      return error(line_number, "data row before the DATA PERIODS header line");
    }
  }
}

}  // namespace

absl::StatusOr<EpwData> ParseEpw(absl::string_view text, absl::string_view source,
                                 const EpwReadOptions& options) {
  EpwData data;
  data.source = std::string(source);
  const LineErrors error(data.source);
  std::vector<absl::string_view> lines = absl::StrSplit(text, '\n');
  for (absl::string_view& line : lines) absl::ConsumeSuffix(&line, "\r");
  std::vector<DataPeriod> periods;
  absl::StatusOr<size_t> first_row = ParseHeader(lines, error, &data, &periods);
  if (!first_row.ok()) return first_row.status();

  // Data rows, consecutive steps of the data periods
  StepSequence sequence(std::move(periods), data.records_per_hour);
  data.records.reserve(lines.size() - *first_row);
  for (size_t index = *first_row; index < lines.size(); ++index) {
    if (Trim(lines[index]).empty()) continue;
    EpwRecord record;
    if (absl::Status s =
            ParseRecord(lines[index], static_cast<int>(index) + 1, data.records_per_hour, options,
                        error, &record, &data.replaced_radiation_values);
        !s.ok()) {
      return s;
    }
    if (absl::Status s = sequence.Next(record, error); !s.ok()) return s;
    data.records.push_back(std::move(record));
  }
  if (data.records.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(data.source, ": no data rows"));
  }
  if (absl::Status s = sequence.Finish(error); !s.ok()) return s;
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
