#include "client/report/svg.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

namespace fenestra {
namespace {

using ::testing::ElementsAre;

TEST(SvgTest, NiceTicksStepByOneTwoOrFive) {
  EXPECT_THAT(NiceTicks(0, 1, 5), ElementsAre(0, 0.2, 0.4, 0.6000000000000001, 0.8, 1));
  EXPECT_THAT(NiceTicks(0.5, 14.5, 6), ElementsAre(2, 4, 6, 8, 10, 12, 14));
  EXPECT_THAT(NiceTicks(-0.25, 0.7, 5), ElementsAre(-0.2, 0, 0.2, 0.4, 0.6000000000000001));
  EXPECT_THAT(NiceTicks(27, 53, 5), ElementsAre(30, 35, 40, 45, 50));
  // Degenerate ranges give one tick, never a loop
  EXPECT_THAT(NiceTicks(3, 3, 5), ElementsAre(3));
  EXPECT_EQ(NiceTicks(0, NAN, 5).size(), 1u);
  // Counts tick whole numbers only
  EXPECT_THAT(AxisTicks({"n", 0.5, 4.5, true}, 6), ElementsAre(1, 2, 3, 4));
}

TEST(SvgTest, LabelsAndCoordinates) {
  EXPECT_EQ(TickLabel(0.6000000000000001, 0.2), "0.6");
  EXPECT_EQ(TickLabel(-0.0, 0.5), "0.0");
  EXPECT_EQ(TickLabel(1500, 500), "1500");
  EXPECT_EQ(Px(12.0), "12");
  EXPECT_EQ(Px(-0.001), "0");
  EXPECT_EQ(Px(3.14159), "3.14");
  EXPECT_DOUBLE_EQ(TextWidth("± α", 10), TextWidth("abc", 10));  // characters, not bytes
}

TEST(SvgTest, TextIsEscaped) {
  EXPECT_EQ(EscapeXml("<a href=\"x\">Tom & 'Jerry'</a>\x01"),
            "&lt;a href=&quot;x&quot;&gt;Tom &amp; &#39;Jerry&#39;&lt;/a&gt; ");
  Svg svg("id\"><script>", "c", 10, 10, "</title><script>");
  svg.Text(1, 2, "<b>", "label");
  const std::string markup = svg.Finish();
  EXPECT_EQ(markup.find("<script>"), std::string::npos) << markup;
  EXPECT_NE(markup.find("&lt;b&gt;"), std::string::npos);
}

TEST(SvgTest, ConvexHullDropsInnerAndRepeatedPoints) {
  EXPECT_EQ(ConvexHull({{1, 1}, {0, 0}, {0.5, 0.5}, {1, 0}, {0, 1}, {1, 1}, {0, 0.5}}),
            (Points{{0, 0}, {1, 0}, {1, 1}, {0, 1}}));
  EXPECT_EQ(ConvexHull({{2, 3}, {2, 3}}), (Points{{2, 3}}));
}

TEST(SvgTest, ViridisRunsFromPurpleToYellow) {
  EXPECT_EQ(ViridisColor(0), "#440154");
  EXPECT_EQ(ViridisColor(1), "#fde725");
  EXPECT_EQ(ViridisColor(0.5), "#21918c");
  EXPECT_EQ(ViridisColor(-3), "#440154");
  EXPECT_EQ(ViridisColor(NAN), "#440154");
  EXPECT_EQ(ViridisStops().size(), 9u);
}

}  // namespace
}  // namespace fenestra
