#include "server/log_safe.h"

#include <gtest/gtest.h>

#include <string>

namespace fenestra {
namespace {

using namespace std::string_literals;

TEST(LogSafeTest, PlainTextAndUtf8StayAsTheyAre) {
  EXPECT_EQ(LogSafe("tilt experiment 3"), "tilt experiment 3");
  EXPECT_EQ(LogSafe("Montevideo Cañón 東京"), "Montevideo Cañón 東京");
  EXPECT_EQ(LogSafe(""), "");
}

TEST(LogSafeTest, ControlCharactersQuotesAndBackslashesAreEscaped) {
  EXPECT_EQ(LogSafe("a\nb\rc\td"), "a\\nb\\rc\\td");
  EXPECT_EQ(LogSafe("nul\0esc\x1b[31m del\x7f"s), "nul\\x00esc\\x1b[31m del\\x7f");
  EXPECT_EQ(LogSafe("say \"hi\" \\n"), "say \\\"hi\\\" \\\\n");
  // C1 controls (NEL), line separator, right-to-left override
  EXPECT_EQ(LogSafe("a\xc2\x85"
                    "b\xe2\x80\xa8"
                    "c\xe2\x80\xae"
                    "d"),
            "a\\u0085b\\u2028c\\u202ed");
}

TEST(LogSafeTest, BytesThatAreNotUtf8AreEscaped) {
  EXPECT_EQ(LogSafe("a\xff"
                    "b"),
            "a\\xffb");
  EXPECT_EQ(LogSafe("\xc3"), "\\xc3");                    // cut sequence
  EXPECT_EQ(LogSafe("\xc0\xaf"), "\\xc0\\xaf");           // overlong '/'
  EXPECT_EQ(LogSafe("\xed\xa0\x80"), "\\xed\\xa0\\x80");  // surrogate
}

TEST(LogSafeTest, LongTextIsCutWithAMarker) {
  EXPECT_EQ(LogSafe(std::string(kLogSafeMaxBytes, 'x')), std::string(kLogSafeMaxBytes, 'x'));
  EXPECT_EQ(LogSafe(std::string(250, 'x')), std::string(200, 'x') + "...(+50 bytes)");
  EXPECT_EQ(LogSafe("abcdef", 4), "abcd...(+2 bytes)");
  // Never inside a character
  EXPECT_EQ(LogSafe("abcñ", 4), "abc...(+2 bytes)");
  // The cut counts input bytes: escapes do not shorten what is shown
  EXPECT_EQ(LogSafe(std::string(3, '\n'), 2), "\\n\\n...(+1 bytes)");
}

}  // namespace
}  // namespace fenestra
