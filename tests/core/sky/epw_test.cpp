#include "core/sky/epw.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "tests/core/sky/epw_fixture.h"

namespace fenestra {
namespace {

using ::fenestra::testing::EpwDay;
using ::fenestra::testing::EpwHeader;
using ::fenestra::testing::EpwRow;
using ::testing::AllOf;
using ::testing::HasSubstr;

const std::string kMontevideo =
    FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw";
const std::string kSkyData = FENESTRA_SOURCE_DIR "/tests/data/sky/";

// The header of a file holding the one day 1/1 (hour h is on line 8 + h).
std::string OneDayHeader(double latitude_deg = 45, double longitude_deg = 7,
                         double time_zone_hours = 1, int records_per_hour = 1) {
  return EpwHeader(latitude_deg, longitude_deg, time_zone_hours, records_per_hour, "10", " 1/ 1",
                   " 1/ 1");
}

std::string ErrorOf(const std::string& text, const EpwReadOptions& options = {}) {
  absl::StatusOr<EpwData> epw = ParseEpw(text, "fixture.epw", options);
  EXPECT_FALSE(epw.ok());
  if (epw.ok()) return "";
  EXPECT_EQ(epw.status().code(), absl::StatusCode::kInvalidArgument);
  return std::string(epw.status().message());
}

TEST(EpwTest, ReadsMontevideo) {
  absl::StatusOr<EpwData> epw = ReadEpw(kMontevideo);
  ASSERT_TRUE(epw.ok()) << epw.status();
  EXPECT_EQ(epw->location.city, "MONTEVIDEO");
  EXPECT_EQ(epw->location.country, "URY");
  EXPECT_DOUBLE_EQ(epw->location.latitude_deg, -34.83);
  EXPECT_DOUBLE_EQ(epw->location.longitude_deg, -56.00);
  EXPECT_DOUBLE_EQ(epw->location.time_zone_hours, -3.0);
  EXPECT_DOUBLE_EQ(epw->location.elevation_m, 32.0);
  EXPECT_EQ(epw->records_per_hour, 1);
  ASSERT_EQ(epw->records.size(), 8760u);
  EXPECT_EQ(epw->replaced_radiation_values, 0);

  // Jan 1, hour 13
  const EpwRecord& r = epw->records[12];
  EXPECT_EQ(r.line, 21);
  EXPECT_EQ(r.month, 1);
  EXPECT_EQ(r.day, 1);
  EXPECT_EQ(r.hour, 13);
  EXPECT_EQ(r.minute, 60);
  EXPECT_DOUBLE_EQ(*r.global_horizontal_wm2, 312);
  EXPECT_DOUBLE_EQ(r.direct_normal_wm2, 7);
  EXPECT_DOUBLE_EQ(r.diffuse_horizontal_wm2, 305);
  EXPECT_DOUBLE_EQ(*r.global_horizontal_lux, 37400);
  EXPECT_DOUBLE_EQ(*r.direct_normal_lux, 500);
  EXPECT_DOUBLE_EQ(*r.diffuse_horizontal_lux, 36800);
  EXPECT_DOUBLE_EQ(*r.dew_point_c, 19.0);

  // Annual sums [kWh/m2]
  double ghi = 0, dni = 0, dhi = 0;
  for (const EpwRecord& rec : epw->records) {
    ghi += *rec.global_horizontal_wm2;
    dni += rec.direct_normal_wm2;
    dhi += rec.diffuse_horizontal_wm2;
  }
  EXPECT_NEAR(ghi / 1000, 1676.5, 0.05);
  EXPECT_NEAR(dni / 1000, 1514.1, 0.05);
  EXPECT_NEAR(dhi / 1000, 681.2, 0.05);
}

TEST(EpwTest, MissingFileIsNotFound) {
  absl::StatusOr<EpwData> epw = ReadEpw(kSkyData + "no_such_file.epw");
  ASSERT_FALSE(epw.ok());
  EXPECT_EQ(epw.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(epw.status().message(), HasSubstr("no_such_file.epw"));
}

TEST(EpwTest, TruncatedRowNamesFileAndLine) {
  absl::StatusOr<EpwData> epw = ReadEpw(kSkyData + "truncated.epw");
  ASSERT_FALSE(epw.ok());
  EXPECT_THAT(
      epw.status().message(),
      AllOf(HasSubstr("truncated.epw"), HasSubstr("line 22"),
            HasSubstr("expected 35 comma-separated fields, found 9"), HasSubstr("truncated row")));
}

TEST(EpwTest, WrongFieldCountNamesLine) {
  std::string row = EpwRow(1, 1, 2, 0, 0);
  row.insert(row.size() - 1, ",0");  // 36 fields
  const std::string text = EpwHeader(45, 7, 1) + EpwRow(1, 1, 1, 0, 0) + row;
  EXPECT_THAT(ErrorOf(text), AllOf(HasSubstr("fixture.epw, line 10:"),
                                   HasSubstr("expected 35 comma-separated fields, found 36")));
}

TEST(EpwTest, LatitudeOutOfRange) {
  const std::string text = EpwHeader(123, 7, 1) + EpwRow(1, 1, 1, 0, 0);
  EXPECT_THAT(ErrorOf(text), AllOf(HasSubstr("fixture.epw, line 1:"),
                                   HasSubstr("latitude 123 is outside [-90, 90]")));
}

TEST(EpwTest, LongitudeOutOfRange) {
  const std::string text = EpwHeader(45, -200, 1) + EpwRow(1, 1, 1, 0, 0);
  EXPECT_THAT(ErrorOf(text),
              AllOf(HasSubstr("line 1:"), HasSubstr("longitude -200 is outside [-180, 180]")));
}

TEST(EpwTest, TimeZoneOutOfRange) {
  const std::string text = EpwHeader(45, 7, 40) + EpwRow(1, 1, 1, 0, 0);
  EXPECT_THAT(ErrorOf(text),
              AllOf(HasSubstr("line 1:"), HasSubstr("time zone 40 is outside [-12, 14]")));
}

TEST(EpwTest, TimeZonePlus14IsAccepted) {
  // Kiribati's Line Islands keep UTC+14.
  const std::string text = OneDayHeader(1.9, -157.4, 14) + EpwDay(1, 1);
  absl::StatusOr<EpwData> epw = ParseEpw(text, "fixture.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  EXPECT_DOUBLE_EQ(epw->location.time_zone_hours, 14);
}

TEST(EpwTest, BadLocationNumber) {
  const std::string text = EpwHeader(45, 7, 1, 1, "high") + EpwRow(1, 1, 1, 0, 0);
  EXPECT_THAT(ErrorOf(text),
              AllOf(HasSubstr("line 1:"), HasSubstr("elevation is not a number: 'high'")));
}

TEST(EpwTest, FirstLineMustBeLocation) {
  EXPECT_THAT(ErrorOf("DESIGN CONDITIONS,0\n"),
              AllOf(HasSubstr("line 1:"), HasSubstr("starts with a LOCATION line")));
}

TEST(EpwTest, MissingDataPeriods) {
  const std::string text =
      "LOCATION,A,-,B,C,0,45,7,1,10\nDESIGN CONDITIONS,0\n" + EpwRow(1, 1, 1, 0, 0);
  EXPECT_THAT(ErrorOf(text), AllOf(HasSubstr("line 3:"), HasSubstr("before the DATA PERIODS")));
}

TEST(EpwTest, BadRecordsPerHour) {
  std::string text = EpwHeader(45, 7, 1, 7) + EpwRow(1, 1, 1, 0, 0);
  EXPECT_THAT(ErrorOf(text), AllOf(HasSubstr("line 8:"), HasSubstr("must divide 60")));
}

TEST(EpwTest, BadNumberNamesLineAndColumn) {
  std::string row = EpwRow(1, 1, 12, 500, 100);
  row.replace(row.find(",500,"), 5, ",5x0,");
  const std::string text = EpwHeader(45, 7, 1) + row;
  EXPECT_THAT(ErrorOf(text),
              AllOf(HasSubstr("line 9:"),
                    HasSubstr("column 15 (direct normal radiation) is not a number: '5x0'")));
}

TEST(EpwTest, BadDates) {
  EXPECT_THAT(ErrorOf(EpwHeader(45, 7, 1) + EpwRow(2, 30, 1, 0, 0)),
              AllOf(HasSubstr("line 9:"), HasSubstr("day 30 does not exist in month 2")));
  EXPECT_THAT(ErrorOf(EpwHeader(45, 7, 1) + EpwRow(13, 1, 1, 0, 0)),
              HasSubstr("month 13 is outside [1, 12]"));
  EXPECT_THAT(ErrorOf(EpwHeader(45, 7, 1) + EpwRow(1, 1, 25, 0, 0)),
              HasSubstr("hour 25 is outside [1, 24]"));
  EXPECT_THAT(ErrorOf(EpwHeader(45, 7, 1, 4) + EpwRow(1, 1, 1, 0, 0, /*minute=*/0)),
              HasSubstr("minute 0 is outside [1, 60]"));
}

TEST(EpwTest, MissingRadiationFailsByDefault) {
  const std::string text =
      EpwHeader(45, 7, 1) + EpwRow(1, 1, 1, 300, 100) + EpwRow(1, 1, 2, 9999, 100);
  EXPECT_THAT(ErrorOf(text),
              AllOf(HasSubstr("fixture.epw, line 10:"),
                    HasSubstr("column 15 (direct normal radiation) is missing ('9999')")));
}

TEST(EpwTest, NegativeRadiationFailsByDefault) {
  const std::string text = EpwHeader(45, 7, 1) + EpwRow(1, 1, 12, 300, -3);
  EXPECT_THAT(ErrorOf(text),
              AllOf(HasSubstr("line 9:"),
                    HasSubstr("column 16 (diffuse horizontal radiation) is negative ('-3')")));
}

TEST(EpwTest, TreatMissingAsZeroCountsReplacements) {
  const std::string text = OneDayHeader() + EpwDay(1, 1,
                                                   {{11, EpwRow(1, 1, 11, 300, 100)},
                                                    {12, EpwRow(1, 1, 12, 9999, 100)},
                                                    {13, EpwRow(1, 1, 13, 9999, -1)},
                                                    {14, EpwRow(1, 1, 14, 200, 99999)}});
  absl::StatusOr<EpwData> epw =
      ParseEpw(text, "fixture.epw", EpwReadOptions{.treat_missing_as_zero = true});
  ASSERT_TRUE(epw.ok()) << epw.status();
  EXPECT_EQ(epw->replaced_radiation_values, 4);
  ASSERT_EQ(epw->records.size(), 24u);
  EXPECT_EQ(epw->records[10].direct_normal_wm2, 300);
  EXPECT_EQ(epw->records[11].direct_normal_wm2, 0);
  EXPECT_EQ(epw->records[11].diffuse_horizontal_wm2, 100);
  EXPECT_EQ(epw->records[12].direct_normal_wm2, 0);
  EXPECT_EQ(epw->records[12].diffuse_horizontal_wm2, 0);
  EXPECT_EQ(epw->records[13].direct_normal_wm2, 200);
  EXPECT_EQ(epw->records[13].diffuse_horizontal_wm2, 0);
}

TEST(EpwTest, OptionalFieldsMayBeMissing) {
  const std::string text =
      OneDayHeader() + EpwDay(1, 1, {{12, EpwRow(1, 1, 12, 300, 100, 60, 99.9)}});
  absl::StatusOr<EpwData> epw = ParseEpw(text, "fixture.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  const EpwRecord& r = epw->records[11];
  EXPECT_FALSE(r.dew_point_c.has_value());
  EXPECT_FALSE(r.global_horizontal_wm2.has_value());
  EXPECT_FALSE(r.global_horizontal_lux.has_value());
  EXPECT_FALSE(r.direct_normal_lux.has_value());
  EXPECT_FALSE(r.diffuse_horizontal_lux.has_value());
  EXPECT_DOUBLE_EQ(*r.dry_bulb_c, 20);
}

TEST(EpwTest, CrLfLineEndingsAndTrailingBlankLines) {
  std::string text = OneDayHeader() + EpwDay(1, 1);
  std::string crlf;
  for (char c : text) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  crlf += "\r\n\r\n";
  absl::StatusOr<EpwData> epw = ParseEpw(crlf, "fixture.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  EXPECT_EQ(epw->records.size(), 24u);
  EXPECT_EQ(epw->records[1].hour, 2);
}

TEST(EpwTest, SubHourlyRecords) {
  std::string text = OneDayHeader(45, 7, 1, 4);
  for (int hour = 1; hour <= 24; ++hour) {
    for (int minute : {15, 30, 45, 60}) text += EpwRow(1, 1, hour, 0, 0, minute);
  }
  absl::StatusOr<EpwData> epw = ParseEpw(text, "fixture.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  EXPECT_EQ(epw->records_per_hour, 4);
  ASSERT_EQ(epw->records.size(), 96u);
  EXPECT_EQ(epw->records[0].minute, 15);
}

TEST(EpwTest, LeapDayRows) {
  absl::StatusOr<EpwData> epw = ReadEpw(kSkyData + "leap_day.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  ASSERT_EQ(epw->records.size(), 72u);
  EXPECT_EQ(epw->records[24].month, 2);
  EXPECT_EQ(epw->records[24].day, 29);
  EXPECT_EQ(epw->records[48].month, 3);
}

TEST(EpwTest, NoDataRows) { EXPECT_THAT(ErrorOf(EpwHeader(45, 7, 1)), HasSubstr("no data rows")); }

std::string Montevideo() {
  std::ifstream in(kMontevideo, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The first `lines` lines of `text`.
std::string FirstLines(const std::string& text, int lines) {
  size_t end = 0;
  for (int i = 0; i < lines; ++i) end = text.find('\n', end) + 1;
  return text.substr(0, end);
}

// A file cut at a row boundary parses row by row; only the data period shows it is short.
TEST(EpwTest, FileCutBetweenRowsIsTruncated) {
  EXPECT_THAT(
      ErrorOf(FirstLines(Montevideo(), 8 + 4000)),
      AllOf(HasSubstr("fixture.epw, line 4008:"), HasSubstr("the rows end at 6/16 hour 16"),
            HasSubstr("before the end of data period 1 (1/1 to 12/31)"), HasSubstr("truncated")));
  // Cut inside the last field of a row: still 35 fields, so the row parses
  std::string cut = FirstLines(Montevideo(), 8 + 100);
  cut.resize(cut.size() - 3);
  EXPECT_THAT(ErrorOf(cut), AllOf(HasSubstr("line 108:"), HasSubstr("truncated")));
}

TEST(EpwTest, MissingAndRepeatedHours) {
  std::string gap = OneDayHeader();
  for (int hour = 1; hour <= 24; ++hour) {
    if (hour != 7) gap += EpwRow(1, 1, hour, 0, 0);
  }
  EXPECT_THAT(ErrorOf(gap), AllOf(HasSubstr("line 15:"),
                                  HasSubstr("columns 2-5 (month, day, "
                                            "hour, minute) give 1/1 hour 8"),
                                  HasSubstr("expected the step after 1/1 hour 6")));
  const std::string repeated = OneDayHeader() + EpwDay(1, 1, {{5, EpwRow(1, 1, 4, 0, 0)}});
  EXPECT_THAT(ErrorOf(repeated), AllOf(HasSubstr("line 13:"), HasSubstr("give 1/1 hour 4")));
  EXPECT_THAT(ErrorOf(OneDayHeader() + EpwRow(1, 1, 2, 0, 0)),
              AllOf(HasSubstr("line 9:"), HasSubstr("expected 1/1 hour 1 (the start of data "
                                                    "period 1)")));
  EXPECT_THAT(ErrorOf(OneDayHeader() + EpwDay(1, 1) + EpwRow(1, 2, 1, 0, 0)),
              AllOf(HasSubstr("line 33:"), HasSubstr("after the end of the last data period")));
  std::string quarter = OneDayHeader(45, 7, 1, 4) + EpwRow(1, 1, 1, 0, 0, 10);
  EXPECT_THAT(ErrorOf(quarter),
              AllOf(HasSubstr("line 9:"), HasSubstr("column 5 (minute) 10 is not the end "
                                                    "of a 15-minute interval")));
}

TEST(EpwTest, FebruaryTheTwentyNinthMayBeLeftOut) {
  const std::string text =
      EpwHeader(45, 7, 1, 1, "10", " 2/28", " 3/ 1") + EpwDay(2, 28) + EpwDay(3, 1);
  absl::StatusOr<EpwData> epw = ParseEpw(text, "fixture.epw");
  ASSERT_TRUE(epw.ok()) << epw.status();
  EXPECT_EQ(epw->records.size(), 48u);
}

TEST(EpwTest, BadDataPeriodDates) {
  EXPECT_THAT(ErrorOf(EpwHeader(45, 7, 1, 1, "10", " 1/ 1", "13/40") + EpwDay(1, 1)),
              AllOf(HasSubstr("line 8:"), HasSubstr("start and end date of period 1"),
                    HasSubstr("'13/40'")));
  EXPECT_THAT(ErrorOf("LOCATION,A,-,B,C,0,45,7,1,10\nDATA PERIODS,2,1,Data,Sunday, 1/ 1,12/31\n"),
              AllOf(HasSubstr("line 2:"), HasSubstr("declares 2 periods")));
}

// Not-a-number, infinity and garbage are refused naming the line and the column; the text
// quoted in the message is escaped, so a file cannot inject a line break into a log.
TEST(EpwTest, NotANumberGarbageAndControlCharacters) {
  for (const std::string bad : {"nan", "NaN", "inf", "-Infinity", "1e999"}) {
    std::string row = EpwRow(1, 1, 1, 300, 100);
    row.replace(row.find(",300,"), 5, "," + bad + ",");
    EXPECT_THAT(ErrorOf(OneDayHeader() + row),
                AllOf(HasSubstr("line 9:"), HasSubstr("column 15 (direct normal radiation) is "
                                                      "not a number: '" +
                                                      bad + "'")));
  }
  std::string row = EpwRow(1, 1, 1, 300, 100);
  row.replace(row.find(",100,"), 5, ",1\n2024 [info] forged\x1b[0m,");
  const std::string message = ErrorOf(OneDayHeader() + row);
  EXPECT_THAT(message, AllOf(HasSubstr("line 9:"), HasSubstr("expected 35 comma-separated")));
  row = EpwRow(1, 1, 1, 300, 100);
  row.replace(row.find(",100,"), 5, ",1\x1b[31m,");
  EXPECT_THAT(ErrorOf(OneDayHeader() + row),
              HasSubstr("column 16 (diffuse horizontal radiation) is not a number: '1\\x1b[31m'"));
  EXPECT_THAT(ErrorOf(std::string("\x7f"
                                  "ELF\x02\x01\x01\0\0garbage",
                                  16)),
              AllOf(HasSubstr("line 1:"), HasSubstr("starts with a LOCATION line")));
  const std::string long_field(100000, '7');
  row = EpwRow(1, 1, 1, 300, 100);
  row.replace(row.find(",100,"), 5, ",x" + long_field + ",");
  EXPECT_LT(ErrorOf(OneDayHeader() + row).size(), 300u);
}

}  // namespace
}  // namespace fenestra
