#include "core/common/text.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fenestra/v1/scene.pb.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

std::string ErrorOf(const std::string& text, size_t max_bytes = kMaxNameBytes) {
  const absl::Status status = CheckText(text, "f", max_bytes);
  EXPECT_FALSE(status.ok()) << text;
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  return std::string(status.message());
}

TEST(TextTest, PrintableUtf8Passes) {
  for (const std::string& ok :
       std::vector<std::string>{"", "desk 2", "Büro Süd", "東京 office", "emoji \xF0\x9F\x8C\x9E",
                                std::string(256, 'x')}) {
    EXPECT_TRUE(CheckText(ok, "f").ok()) << ok;
  }
}

TEST(TextTest, InvalidUtf8IsRefusedWithItsOffset) {
  EXPECT_THAT(ErrorOf("ab\xff"), HasSubstr("f: is not valid UTF-8 (byte 0xFF at offset 2)"));
  EXPECT_THAT(ErrorOf("\xC0\xAF"), HasSubstr("offset 0"));           // overlong '/'
  EXPECT_THAT(ErrorOf("\xED\xA0\x80"), HasSubstr("not valid"));      // a surrogate
  EXPECT_THAT(ErrorOf("\xF4\x90\x80\x80"), HasSubstr("not valid"));  // above U+10FFFF
  EXPECT_THAT(ErrorOf("x\xE6\x9D"), HasSubstr("offset 1"));          // cut short
}

TEST(TextTest, ControlCharactersAndLength) {
  EXPECT_THAT(ErrorOf("a\nb"), HasSubstr("control character U+000A at offset 1"));
  EXPECT_THAT(ErrorOf(std::string("a\0b", 3)), HasSubstr("U+0000"));
  EXPECT_THAT(ErrorOf("\x7F"), HasSubstr("U+007F"));
  EXPECT_THAT(ErrorOf("a\xC2\x85"), HasSubstr("U+0085"));         // C1 next line
  EXPECT_THAT(ErrorOf("a\xE2\x80\xA8"), HasSubstr("U+2028"));     // line separator
  EXPECT_THAT(ErrorOf("evil\xE2\x80\xAE"), HasSubstr("U+202E"));  // right-to-left override
  EXPECT_THAT(ErrorOf(std::string(257, 'x')), HasSubstr("f: is 257 bytes long, more than the "
                                                        "256 allowed"));
  EXPECT_TRUE(CheckText(std::string(4096, 'p'), "f", kMaxPathBytes).ok());
}

TEST(TextTest, MessagesNameTheFieldPath) {
  v1::Scene scene;
  scene.set_name("ok");
  scene.add_sensors()->set_name("s1");
  scene.add_sensors()->set_name("s\r2");
  EXPECT_THAT(CheckMessageText(scene, "scene.json: ").message(),
              HasSubstr("scene.json: sensors[1].name: holds the control character U+000D"));
  scene.mutable_sensors(1)->set_name("s2");
  v1::ObjMesh& obj = *scene.add_surfaces()->mutable_obj();
  (*obj.mutable_group_materials())["group\t1"] = "wall";
  EXPECT_THAT(CheckMessageText(scene, "").message(),
              HasSubstr("surfaces[0].obj.group_materials[0].key: holds the control character"));
  obj.clear_group_materials();
  obj.set_path(std::string(300, 'p'));  // a path may be longer than a name
  EXPECT_TRUE(CheckMessageText(scene, "").ok());
  scene.mutable_site()->set_weather_file(std::string(5000, 'w'));
  EXPECT_THAT(CheckMessageText(scene, "").message(), HasSubstr("site.weather_file: is 5000 bytes"));
}

TEST(TextTest, QuotedAndLoggedTextIsEscapedAndCut) {
  EXPECT_EQ(QuoteText("5x0"), "'5x0'");
  EXPECT_EQ(QuoteText("a\nb\x1b[0m"), "'a\\nb\\x1b[0m'");
  EXPECT_EQ(QuoteText(std::string(100, 'z'), 4), "'zzzz...'");
}

}  // namespace
}  // namespace fenestra
