#include "core/metrics/occupancy.h"

#include <gtest/gtest.h>

#include <vector>

namespace fenestra {
namespace {

// Step centres of an hourly 365-day year: record h of a day is centred at h - 0.5.
std::vector<double> HourlyYear() {
  std::vector<double> hours;
  for (int day = 0; day < 365; ++day) {
    for (int h = 1; h <= 24; ++h) hours.push_back(h - 0.5);
  }
  return hours;
}

int Count(const std::vector<bool>& flags) {
  int n = 0;
  for (const bool f : flags) n += f;
  return n;
}

TEST(OccupancyTest, DefaultIs3650HoursRecords9To18) {
  absl::StatusOr<std::vector<bool>> occupied = OccupiedSteps(HourlyYear());
  ASSERT_TRUE(occupied.ok());
  ASSERT_EQ(occupied->size(), 8760u);
  EXPECT_EQ(Count(*occupied), 3650);
  for (int h = 1; h <= 24; ++h) {
    EXPECT_EQ((*occupied)[24 * 100 + h - 1], h >= 9 && h <= 18) << "record hour " << h;
  }
}

TEST(OccupancyTest, ConfigurableAndWrappingSchedules) {
  absl::StatusOr<std::vector<bool>> nine_to_five = OccupiedSteps(HourlyYear(), {9, 17});
  ASSERT_TRUE(nine_to_five.ok());
  EXPECT_EQ(Count(*nine_to_five), 8 * 365);

  absl::StatusOr<std::vector<bool>> night = OccupiedSteps(HourlyYear(), {22, 6});
  ASSERT_TRUE(night.ok());
  EXPECT_EQ(Count(*night), 8 * 365);
  EXPECT_TRUE((*night)[0]);   // 00:30
  EXPECT_FALSE((*night)[6]);  // 06:30
  EXPECT_TRUE((*night)[22]);  // 22:30
}

TEST(OccupancyTest, RejectsBadSchedules) {
  EXPECT_FALSE(OccupiedSteps(HourlyYear(), {8, 8}).ok());
  EXPECT_FALSE(OccupiedSteps(HourlyYear(), {-1, 8}).ok());
  EXPECT_FALSE(OccupiedSteps(HourlyYear(), {8, 25}).ok());
}

}  // namespace
}  // namespace fenestra
