#include "core/trace/share_blocks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fenestra {
namespace {

using ::testing::ElementsAre;

TEST(ShareBlocksTest, BlocksFollowTheWork) {
  // 3 : 2 : 1 of 12 blocks, one each first: 1 + 4.5, 1 + 3, 1 + 1.5; the halves go to the
  // first remainders in row order
  EXPECT_THAT(ShareBlocks({3, 2, 1}, 12), ElementsAre(0, 6, 10, 12));
  // No work anywhere: equal shares
  EXPECT_THAT(ShareBlocks({0, 0, 0, 0}, 8), ElementsAre(0, 2, 4, 6, 8));
  // A row without work still gets its block
  EXPECT_THAT(ShareBlocks({0, 5}, 4), ElementsAre(0, 1, 4));
}

TEST(ShareBlocksTest, EveryRowGetsABlockWhenRowsOutnumberThem) {
  EXPECT_THAT(ShareBlocks({1, 100, 1}, 2), ElementsAre(0, 1, 2, 3));
  EXPECT_THAT(ShareBlocks({}, 5), ElementsAre(0));
}

TEST(ShareBlocksTest, EachRowGetsItsShareWithinOneBlock) {
  std::vector<double> work;
  double sum = 0;
  for (int y = 0; y < 72; ++y) {
    work.push_back(1.0 + (y % 9) * 0.37);
    sum += work.back();
  }
  const std::vector<unsigned int> first = ShareBlocks(work, 528);
  ASSERT_EQ(first.size(), 73u);
  EXPECT_EQ(first.back(), 528u);
  for (size_t y = 0; y < work.size(); ++y) {
    const double share = 1 + (528 - 72) * work[y] / sum;
    EXPECT_NEAR(first[y + 1] - first[y], share, 1.0) << "row " << y;
  }
}

}  // namespace
}  // namespace fenestra
