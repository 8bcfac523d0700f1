#include "core/geometry/rad_import.h"

#include <google/protobuf/util/field_comparator.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/common/vec3.h"
#include "core/geometry/scene.h"
#include "core/trace/glass.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

const std::string kModel = FENESTRA_SOURCE_DIR "/tests/data/models/matrix_tutorial_room/";

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in) << path;
  return std::string(std::istreambuf_iterator<char>(in), {});
}

absl::StatusOr<v1::Scene> Import(const std::string& rad, const std::string& pts = "",
                                 const RadImportOptions& options = {},
                                 RadImportSummary* summary = nullptr) {
  return ImportRadiance({{"room.rad", rad}}, {"room.pts", pts}, options, summary);
}

// The message of an import that must fail, InvalidArgument.
std::string Refusal(const std::string& rad, const std::string& pts = "",
                    const RadImportOptions& options = {}) {
  const absl::StatusOr<v1::Scene> scene = Import(rad, pts, options);
  EXPECT_FALSE(scene.ok()) << rad;
  if (scene.ok()) return "";
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument) << scene.status();
  return std::string(scene.status().message());
}

// Equal, doubles within 1e-12 relative, a field at 0 as one not given.
void ExpectSameScene(const v1::Scene& expected, const v1::Scene& actual) {
  google::protobuf::util::DefaultFieldComparator comparator;
  comparator.set_float_comparison(google::protobuf::util::DefaultFieldComparator::APPROXIMATE);
  comparator.SetDefaultFractionAndMargin(1e-12, 1e-300);
  google::protobuf::util::MessageDifferencer differ;
  differ.set_field_comparator(&comparator);
  // A field at its default counts as unset: protobuf's JSON leaves out a -0
  differ.set_message_field_comparison(google::protobuf::util::MessageDifferencer::EQUIVALENT);
  std::string report;
  differ.ReportDifferencesToString(&report);
  EXPECT_TRUE(differ.Compare(expected, actual)) << report;
}

// ImportRadiance(ExportRadiance(scene)) is RadianceRoundTripForm(scene).
void ExpectRoundTrip(const v1::Scene& scene) {
  std::string points;
  const absl::StatusOr<std::string> rad = ExportRadiance(scene, &points);
  ASSERT_TRUE(rad.ok()) << rad.status();
  const absl::StatusOr<v1::Scene> back =
      ImportRadiance({{"export.rad", *rad}}, {"export.pts", points});
  ASSERT_TRUE(back.ok()) << back.status() << "\n" << *rad;
  const absl::StatusOr<v1::Scene> form = RadianceRoundTripForm(scene);
  ASSERT_TRUE(form.ok()) << form.status();
  ExpectSameScene(*form, *back);
}

// A closed 4 x 4 x 3 m room, its south wall (y = 0) with a 2 x 1.5 m opening at
// x in [1, 3], z in [1, 2.5] as Radiance writes it (one outline with a seam to the hole),
// a glass window in the opening and a sensor in the middle.
constexpr char kRoomRad[] = R"(
void plastic wall
0
0
5 0.5 0.5 0.5 0 0

void glass pane
0
0
3 0.96 0.96 0.96

wall polygon floor 0 0 12  0 0 0  4 0 0  4 4 0  0 4 0
wall polygon ceiling 0 0 12  0 0 3  0 4 3  4 4 3  4 0 3
wall polygon north 0 0 12  0 4 0  4 4 0  4 4 3  0 4 3
wall polygon west 0 0 12  0 0 0  0 4 0  0 4 3  0 0 3
wall polygon east 0 0 12  4 0 0  4 0 3  4 4 3  4 4 0
wall polygon south 0 0 30
  0 0 0  4 0 0  4 0 3  0 0 3  0 0 0
  1 0 1  1 0 2.5  3 0 2.5  3 0 1  1 0 1
pane polygon south_window 0 0 12  1 0 1  3 0 1  3 0 2.5  1 0 2.5
)";
constexpr char kRoomPts[] = "2 2 0.8 0 0 1\n";

TEST(RadImportTest, ReadsEachMaterialTypeWithItsParameters) {
  const std::string rad = absl::StrCat(R"(
void plastic grey 0 0 5 0.5 0.5 0.5 0.02 0.1
void plastic red 0 0 5 0.8 0.1 0.2 0 0
void metal alu 0 0 5 0.8 0.8 0.8 0.9 0.05
void trans fabric 0 0 7 0.6 0.6 0.6 0 0 0.3 0.1
void glass clear 0 0 4 0.96 0.96 0.96 1.52
)",
                                       kRoomRad);
  absl::StatusOr<v1::Scene> scene = Import(rad, kRoomPts);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->materials_size(), 7);
  const v1::Material& grey = scene->materials(0);
  EXPECT_EQ(grey.name(), "grey");
  EXPECT_DOUBLE_EQ(grey.plastic().reflectance(), 0.5);
  EXPECT_DOUBLE_EQ(grey.plastic().specularity(), 0.02);
  EXPECT_DOUBLE_EQ(grey.plastic().roughness(), 0.1);
  // Grey by Radiance's `bright`: 0.265 r + 0.670 g + 0.065 b
  EXPECT_DOUBLE_EQ(scene->materials(1).plastic().reflectance(),
                   0.265 * 0.8 + 0.670 * 0.1 + 0.065 * 0.2);
  EXPECT_DOUBLE_EQ(scene->materials(2).metal().reflectance(), 0.8);
  EXPECT_DOUBLE_EQ(scene->materials(2).metal().specularity(), 0.9);
  EXPECT_DOUBLE_EQ(scene->materials(2).metal().roughness(), 0.05);
  const v1::Material::Trans& fabric = scene->materials(3).trans();
  EXPECT_DOUBLE_EQ(fabric.reflectance(), 0.6);
  EXPECT_DOUBLE_EQ(fabric.transmissivity(), 0.3);
  EXPECT_DOUBLE_EQ(fabric.transmitted_specular(), 0.1);
  // Radiance's glass of transmissivity 0.96 lets 0.88 through at normal incidence
  EXPECT_NEAR(scene->materials(4).glass().transmittance(), 0.8815, 5e-4);
  EXPECT_DOUBLE_EQ(scene->materials(4).glass().transmittance(),
                   GlassPane::NormalTransmittance(0.96));
  EXPECT_NEAR(GlassPane::NormalTransmittance(0.96), GlassPane{0.96f}.Transmittance(1.0f), 1e-6);
  EXPECT_TRUE(BuildScene(*scene, "room.rad").ok()) << BuildScene(*scene, "room.rad").status();
}

// A -0 reads as 0, from Radiance's arguments and from a directive's JSON (a -0 once broke
// the search for a trans's parameters: tests/fuzz/regressions/rad_import).
TEST(RadImportTest, NegativeZeroesReadAsZero) {
  absl::StatusOr<v1::Scene> scene = Import(
      "void trans a 0 0 7 0 0.6 0.6 0.1 0 -0 0\n"
      "#@fenestra material {\"name\": \"b\", \"trans\": {\"reflectance\": 0.5, "
      "\"specularity\": 0.1, \"transmissivity\": -0}}\n"
      "void trans b 0 0 7 0.5 0.5 0.5 0.1 0 0 0\n");
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->materials_size(), 2);
  EXPECT_FALSE(std::signbit(scene->materials(0).trans().transmissivity()));
  EXPECT_EQ(scene->materials(1).trans().transmissivity(), 0);
  ExpectRoundTrip(*scene);
}

TEST(RadImportTest, CommentsAndPrimitivesAcrossLines) {
  const std::string rad =
      "# a comment line\r\n"
      "void # the modifier, then a comment\r\n"
      "  plastic\twall\r\n"
      "0 # no strings\n"
      "0\n"
      "5 0.5\n0.5 0.5\n\n0 0   # grey\n"
      "wall polygon p#1 0 0 9\n"
      "# a comment inside the vertices\n"
      "0 0 0\n1 0 0\n"
      "1 1 0";
  absl::StatusOr<v1::Scene> scene = Import(rad);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->materials_size(), 1);
  EXPECT_DOUBLE_EQ(scene->materials(0).plastic().reflectance(), 0.5);
  ASSERT_EQ(scene->surfaces_size(), 1);
  EXPECT_EQ(scene->surfaces(0).name(), "p#1");  // '#' inside a word is no comment
  EXPECT_EQ(scene->surfaces(0).polygon().vertices_size(), 3);
  EXPECT_EQ(scene->surfaces(0).side(), v1::SIDE_INDOOR);
  EXPECT_EQ(scene->name(), "room");  // the first source's stem
}

TEST(RadImportTest, RefusesWhatItDoesNotReadNamingFileAndLine) {
  const std::string wall = "void plastic wall 0 0 5 0.5 0.5 0.5 0 0\n";
  struct Case {
    std::string rad, message;
  };
  const std::vector<Case> cases = {
      {wall + "wall sphere ball 0 0 4 0 0 0 1\n", "room.rad:2: unsupported primitive 'sphere'"},
      {wall + "\n!xform -t 1 0 0 chair.rad\n", "room.rad:3: unsupported primitive '!xform'"},
      {"void light lamp 0 0 3 100 100 100\n", "room.rad:1: unsupported primitive 'light'"},
      {"wall polygon p 0 0 9 0 0 0 1 0 0 1 1 0\n",
       "room.rad:1: modifier 'wall' of polygon 'p' is not defined before it"},
      {wall + wall, "room.rad:2: modifier 'wall' is defined twice (first at room.rad:1)"},
      {"tex plastic wall 0 0 5 0.5 0.5 0.5 0 0\n",
       "room.rad:1: plastic 'wall': a material's "
       "modifier must be void"},
      {"void plastic void 0 0 5 0.5 0.5 0.5 0 0\n", "room.rad:1: a modifier cannot be named void"},
      {"void plastic wall 0 0 4 0.5 0.5 0.5 0\n",
       "room.rad:1: plastic 'wall' takes 5 real arguments, got 4"},
      {"void glass pane 0 0 5 1 1 1 1.52 0\n",
       "room.rad:1: glass 'pane' takes 3 or 4 real arguments, got 5"},
      {"void plastic wall 1 x 0 5 0.5 0.5 0.5 0 0\n",
       "room.rad:1: plastic 'wall' takes no string arguments, got 1"},
      {"void plastic wall 0 2 1 1 5 0.5 0.5 0.5 0 0\n",
       "room.rad:1: plastic 'wall' takes no integer arguments, got 2"},
      {"void plastic wall 0 0 -5\n", "room.rad:1: '-5' is not a count of plastic 'wall''s real"},
      {wall + "wall polygon p 0 0 8 0 0 0 1 0 0 1 1\n",
       "room.rad:2: polygon 'p' takes 3 real arguments per vertex, 3 to 10000 vertices, got 8"},
      {"void plastic wall 0 0 5 0.5 nan 0.5 0 0\n",
       "room.rad:1: real argument 2 of plastic 'wall', 'nan', is not a finite number"},
      {wall + "wall polygon p 0 0 9\n0 0 0\n1 0 inf\n1 1 0\n",
       "room.rad:4: real argument 6 of polygon 'p', 'inf', is not a finite number"},
      {wall + "wall polygon p 0 0 9 0 0 0 1 0 0 1 0x 0\n",
       "room.rad:2: real argument 8 of polygon 'p', '0x', is not a finite number"},
      {wall + "wall polygon p 0 0 9 0 0 0 1 0 0 200000 1 0\n",
       "room.rad:2: vertex 3 of polygon 'p' lies beyond 100000 m"},
      {wall + "wall polygon p 0 0 9 0 0 0 1 0 0 2 0 0\n", "room.rad:2: zero-area polygon 'p'"},
      {wall + "wall polygon p 0 0 12 0 0 0 1 0 0 1 1 0 0 1 0.5\n",
       "room.rad:2: polygon 'p' is not planar"},
      {"void glass pane 0 0 3 0.9 0.9 0.9\npane polygon w 0 0 9 0 0 0 1 0 0 1 0 1\n",
       "room.rad:2: windows must be rectangles: glass polygon 'w' has 3 vertices"},
      {"void glass pane 0 0 3 0.9 0.9 0.9\npane polygon w 0 0 12 0 0 0 1 0 0 1.5 0 1 0 0 1\n",
       "room.rad:2: windows must be rectangles: glass polygon 'w' is not right-angled at vertex 2"},
      {"void plastic wall 0 0 5 1.2 1.2 1.2 0 0\n",
       "room.rad:1: plastic 'wall': plastic.reflectance: must be in [0, 1], got 1.2"},
      {"void glass pane 0 0 4 0.9 0.9 0.9 1.4\n",
       "room.rad:1: glass 'pane': index of refraction 1.4; Fenestra's glass has 1.52"},
      {"void glass pane 0 0 3 1 1 1\n",
       "room.rad:1: glass 'pane': glass.transmittance: must be "
       "in (0, 0.9]"},
      {"void plastic wall 0 0 5 0.5 0.5 0.5 0\n",
       "room.rad:2: the file ends before plastic "
       "'wall''s real arguments"},
      {"#@fenestra color red\n", "room.rad:1: unknown directive 'color'"},
      {"\n#@fenestra site {\"latitudeDeg\": 91}\n",
       "room.rad:2: site.latitude_deg: must be in [-90, 90], got 91"},
      {"#@fenestra window {\"centre\": {}}\n", "room.rad:1: malformed window JSON"},
      {"#@fenestra material {\"name\": \"x\", \"reflectance\": 0.5}\n",
       "room.rad:1: the material directive describes no material"},
      {"#@fenestra material {\"name\": \"x\", \"reflectance\": 0.5}\n"
       "void plastic wall 0 0 5 0.6 0.6 0.6 0 0\n",
       "room.rad:1: the material directive's plastic does not match plastic 'wall'"},
      {"#@fenestra blind-geometry begin\nwall polygon p 0 0 9 0 0 0 1 0 0 1 1 0\n",
       "room.rad:1: the blind-geometry block has no end"},
      {wall + "#@fenestra surface a\n#@fenestra surface b\n",
       "room.rad:3: a surface directive follows another"},
      {"#@fenestra side up\n", "room.rad:1: the side is indoor or outdoor"},
      {"#@fenestra sensors " + std::string(9, '[') + std::string(9, ']') + "\n",
       "room.rad:1: malformed sensors JSON: nested deeper than 8 levels"},
  };
  for (const Case& c : cases) {
    EXPECT_NE(Refusal(c.rad).find(c.message), std::string::npos)
        << "input:\n"
        << c.rad << "\nmessage: " << Refusal(c.rad) << "\nexpected: " << c.message;
  }
}

TEST(RadImportTest, RefusesBadPointsFilesNamingFileAndLine) {
  struct Case {
    std::string rad, pts, message;
  };
  const std::vector<Case> cases = {
      {"", "0 0 1 0 0 1\n1 2 3 0 0\n", "room.pts:2: a sensor's line holds 6 numbers"},
      {"", "0 0 1 0 0 1 7\n", "room.pts:1: more than 6 numbers on a sensor's line"},
      {"", "\n# header\n0 0 nan 0 0 1\n", "room.pts:3: 'nan' is not a finite number"},
      {"", "0 0 1 0 0 0\n", "room.pts:1: the sensor's direction is zero"},
      {"", "0 0 1e6 0 0 1\n", "room.pts:1: the sensor lies beyond 100000 m"},
      {"#@fenestra sensors [\"a\", \"b\"]\n", "0 0 1 0 0 1\n",
       "room.rad:1: 2 sensor names for 1 sensors in the points file"},
      {"#@fenestra sensors [\"a\", 2]\n", "0 0 1 0 0 1\n",
       "room.rad:1: sensor names are JSON strings"},
  };
  for (const Case& c : cases) {
    EXPECT_NE(Refusal(c.rad, c.pts).find(c.message), std::string::npos)
        << Refusal(c.rad, c.pts) << "\nexpected: " << c.message;
  }
  // Named sensors, and the default names of a plain points file
  absl::StatusOr<v1::Scene> named = Import("#@fenestra sensors [\"desk\"]\n", "1 2 3 0 0 1\n");
  ASSERT_TRUE(named.ok()) << named.status();
  EXPECT_EQ(named->sensors(0).name(), "desk");
  absl::StatusOr<v1::Scene> plain = Import("", "1 2 3 0 0 1\n\n4 5 6 0 1 0");
  ASSERT_TRUE(plain.ok()) << plain.status();
  ASSERT_EQ(plain->sensors_size(), 2);
  EXPECT_EQ(plain->sensors(1).name(), "sensor_1");
  EXPECT_DOUBLE_EQ(plain->sensors(1).position().z(), 6);
  EXPECT_DOUBLE_EQ(plain->sensors(1).direction().y(), 1);
}

// Sizes read from the input are bounded before anything is allocated for them.
TEST(RadImportTest, RefusesHugeInputs) {
  const std::string wall = "void plastic wall 0 0 5 0.5 0.5 0.5 0 0\n";
  std::string many = wall + "wall polygon p 0 0 30003\n";
  for (int k = 0; k < 10001; ++k) absl::StrAppend(&many, std::cos(k), " ", std::sin(k), " 0\n");
  EXPECT_NE(Refusal(many).find("room.rad:2: polygon 'p' takes 3 real arguments per vertex, 3 to "
                               "10000 vertices, got 30003"),
            std::string::npos);
  EXPECT_NE(Refusal(wall + "wall polygon p 0 0 999999999999999999\n").find("got 999999999999"),
            std::string::npos);
  RadImportOptions small;
  small.max_source_bytes = 64;
  EXPECT_NE(Refusal(wall + wall, "", small).find("room.rad:1: the file holds more than 64 bytes"),
            std::string::npos);
  EXPECT_NE(Refusal("", std::string(65, ' '), small).find("room.pts:1: the points file holds more"),
            std::string::npos);
  small = {};
  small.max_primitives = 2;
  const std::string triangle = "wall polygon p 0 0 9 0 0 0 1 0 0 1 1 0\n";
  EXPECT_NE(Refusal(wall + triangle + triangle, "", small)
                .find("room.rad:3: more than 2 primitives, the import's bound"),
            std::string::npos);
  small = {};
  small.max_vertices = 5;
  EXPECT_NE(Refusal(wall + triangle + triangle, "", small)
                .find("room.rad:3: more than 5 polygon vertices, the import's bound"),
            std::string::npos);
  std::string long_directive = "#@fenestra scene " + std::string(kMaxRadDirectiveBytes, 'a');
  EXPECT_NE(Refusal(long_directive).find("room.rad:1: a directive holds at most"),
            std::string::npos);
  EXPECT_NE(Refusal("#@fenestra scene " + std::string(300, 'a'))
                .find("room.rad:1: the scene's "
                      "name"),
            std::string::npos);
}

TEST(RadImportTest, VoidPolygonsAreSkippedAndCounted) {
  RadImportSummary summary;
  absl::StatusOr<v1::Scene> scene =
      Import(absl::StrCat(kRoomRad, "void polygon hidden 0 0 9 0 0 0 1 0 0 1 1 0\n"), kRoomPts, {},
             &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(summary.polygons, 8);
  EXPECT_EQ(summary.void_polygons, 1);
  EXPECT_EQ(summary.materials, 2);
  EXPECT_EQ(summary.windows, 1);
  EXPECT_EQ(summary.triangulated_polygons, 1);
  for (const v1::Surface& s : scene->surfaces()) EXPECT_NE(s.name(), "hidden");
  EXPECT_NE(DescribeRadImport(summary, scene->surfaces_size()).find("1 void polygons skipped"),
            std::string::npos)
      << DescribeRadImport(summary, scene->surfaces_size());
}

double PolygonArea(const v1::Polygon& p) {
  Vec3d normal{0, 0, 0};
  for (int k = 0; k < p.vertices_size(); ++k) {
    const v1::Vec3 &a = p.vertices(k), &b = p.vertices((k + 1) % p.vertices_size());
    normal += Cross(Vec3d{a.x(), a.y(), a.z()}, Vec3d{b.x(), b.y(), b.z()});
  }
  return 0.5 * Length(normal);
}

// A wall with its window punched through a seam becomes triangles covering the wall less the
// hole, named after the polygon.
TEST(RadImportTest, NonConvexPolygonsBecomeTriangles) {
  RadImportSummary summary;
  absl::StatusOr<v1::Scene> scene = Import(kRoomRad, kRoomPts, {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  double area = 0;
  int triangles = 0;
  for (const v1::Surface& s : scene->surfaces()) {
    if (s.name().rfind("south#", 0) != 0) continue;
    EXPECT_EQ(s.name(), absl::StrCat("south#", triangles));
    EXPECT_EQ(s.polygon().vertices_size(), 3);
    area += PolygonArea(s.polygon());
    ++triangles;
  }
  EXPECT_GE(triangles, 6);
  EXPECT_NEAR(area, 4 * 3 - 2 * 1.5, 1e-12);
  EXPECT_EQ(summary.triangulated_polygons, 1);
  EXPECT_EQ(scene->surfaces_size(), 5 + triangles + 1);  // 5 walls, the triangles, the glazing
  EXPECT_TRUE(BuildScene(*scene, "room.rad").ok()) << BuildScene(*scene, "room.rad").status();
  // A polygon that crosses itself cannot be split: a five-pointed star, whose corners all
  // turn one way
  const std::string star =
      "void plastic wall 0 0 5 0.5 0.5 0.5 0 0\n"
      "wall polygon star 0 0 15  0 1 0  -0.588 -0.809 0  0.951 0.309 0\n"
      "  -0.951 0.309 0  0.588 -0.809 0\n";
  EXPECT_NE(Refusal(star).find("room.rad:2: non-convex polygon 'star' cannot be split into "
                               "triangles: the outline crosses itself"),
            std::string::npos)
      << Refusal(star);
  // The triangulation's bound on vertices: a comb of 2049
  std::string comb = "void plastic wall 0 0 5 0.5 0.5 0.5 0 0\nwall polygon comb 0 0 6147\n";
  for (int k = 0; k < 2047; ++k) absl::StrAppend(&comb, 0.01 * k, " ", 1 + 0.5 * (k % 2), " 0\n");
  absl::StrAppend(&comb, "20.46 0 0\n0 0 0\n");
  EXPECT_NE(Refusal(comb).find("room.rad:2: non-convex polygon 'comb' cannot be split into "
                               "triangles"),
            std::string::npos)
      << Refusal(comb);
}

// Seams as exporters write them: the hole run either way round, two holes reached one
// through the other (a seam from the first hole's corner to the second's).
TEST(RadImportTest, SeamsOpenTheirHolesWhicheverWayTheyRun) {
  const std::string wall = "void plastic wall 0 0 5 0.5 0.5 0.5 0 0\n";
  struct Case {
    const char* vertices;  // x z pairs in the plane y = 0
    double area;
  };
  const Case cases[] = {
      // Outline counterclockwise, hole counterclockwise too (the tutorial model's way)
      {"-1 3  0 2.5  0 1  3 1  3 2.5  0 2.5  -1 3  -1 0  4 0  4 3", 5 * 3 - 3 * 1.5},
      // Hole clockwise: the seam of a simple polygon
      {"-1 3  0 2.5  3 2.5  3 1  0 1  0 2.5  -1 3  -1 0  4 0  4 3", 5 * 3 - 3 * 1.5},
      // Two holes, the second reached from the first's corner
      {"4 0  4 3  2 3  0 3  0.5 2.75  3.5 2.75  3.5 2.25  0.5 2.25  0.5 2  3.5 2  3.5 0.6"
       "  0.5 0.6  0.5 2  0.5 2.25  0.5 2.75  0 3  0 0  2 0",
       4 * 3 - 3 * 0.5 - 3 * 1.4},
  };
  for (const Case& c : cases) {
    std::vector<std::string> numbers = absl::StrSplit(c.vertices, ' ', absl::SkipEmpty());
    std::string polygon = absl::StrCat("wall polygon w 0 0 ", numbers.size() / 2 * 3, "\n");
    for (size_t k = 0; k + 1 < numbers.size(); k += 2) {
      absl::StrAppend(&polygon, numbers[k], " 0 ", numbers[k + 1], "\n");
    }
    absl::StatusOr<v1::Scene> scene = Import(wall + polygon);
    ASSERT_TRUE(scene.ok()) << scene.status() << "\n" << polygon;
    double area = 0;
    for (const v1::Surface& s : scene->surfaces()) area += PolygonArea(s.polygon());
    EXPECT_NEAR(area, c.area, 1e-9) << polygon;
  }
}

// A glass rectangle becomes a window (the opening, its normal away from the sensors) and a
// glazing surface 1 mm into the room.
TEST(RadImportTest, GlassRectanglesBecomeWindowsAndGlazing) {
  absl::StatusOr<v1::Scene> scene = Import(kRoomRad, kRoomPts);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->windows_size(), 1);
  const v1::Window& w = scene->windows(0);
  EXPECT_EQ(w.name(), "south_window");
  EXPECT_DOUBLE_EQ(w.center().x(), 2);
  EXPECT_DOUBLE_EQ(w.center().y(), 0);
  EXPECT_DOUBLE_EQ(w.center().z(), 1.75);
  EXPECT_DOUBLE_EQ(w.outward_normal().y(), -1);  // the sensor is at y = 2
  EXPECT_DOUBLE_EQ(w.up().z(), 1);
  EXPECT_DOUBLE_EQ(w.width_m(), 2);
  EXPECT_DOUBLE_EQ(w.height_m(), 1.5);
  EXPECT_EQ(w.depth_m(), 0);
  EXPECT_FALSE(w.has_blind());
  const v1::Surface& glazing = scene->surfaces(scene->surfaces_size() - 1);
  EXPECT_EQ(glazing.name(), "south_window");
  EXPECT_EQ(glazing.material(), "pane");
  for (const v1::Vec3& v : glazing.polygon().vertices()) EXPECT_DOUBLE_EQ(v.y(), 0.001);

  // A skylight: up along the edge closest to +y; names made window names, unique
  const std::string skylights = R"(
void glass pane 0 0 3 0.9 0.9 0.9
pane polygon sky/light 0 0 12  0 0 3  0 2 3  1 2 3  1 0 3
pane polygon sky:light 0 0 12  2 0 3  2 1 3  4 1 3  4 0 3
)";
  absl::StatusOr<v1::Scene> roof = Import(skylights, "0.5 0.5 1 0 0 1\n");
  ASSERT_TRUE(roof.ok()) << roof.status();
  ASSERT_EQ(roof->windows_size(), 2);
  EXPECT_EQ(roof->windows(0).name(), "sky_light");
  EXPECT_EQ(roof->windows(1).name(), "sky_light_2");
  EXPECT_DOUBLE_EQ(roof->windows(0).outward_normal().z(), 1);
  EXPECT_DOUBLE_EQ(roof->windows(0).up().y(), 1);
  EXPECT_DOUBLE_EQ(roof->windows(0).height_m(), 2);
  EXPECT_DOUBLE_EQ(roof->windows(1).up().y(), 1);
  EXPECT_DOUBLE_EQ(roof->windows(1).width_m(), 2);
  EXPECT_DOUBLE_EQ(roof->windows(1).height_m(), 1);
  // Glass outdoors, or after a surface directive, is a surface
  absl::StatusOr<v1::Scene> context = ImportRadiance(
      {{"room.rad", "void glass pane 0 0 3 0.9 0.9 0.9\n"},
       {"city.rad", "pane polygon tower 0 0 12  0 0 3  0 2 3  1 2 3  1 0 3\n", true},
       {"room2.rad",
        "#@fenestra surface glazing\npane polygon g 0 0 12 0 0 3 0 2 3 1 2 3 1 0 3\n"}},
      {"room.pts", ""});
  ASSERT_TRUE(context.ok()) << context.status();
  EXPECT_EQ(context->windows_size(), 0);
  ASSERT_EQ(context->surfaces_size(), 2);
  EXPECT_EQ(context->surfaces(0).side(), v1::SIDE_OUTDOOR);
  EXPECT_EQ(context->surfaces(1).name(), "glazing");
  EXPECT_EQ(context->surfaces(1).side(), v1::SIDE_INDOOR);
}

// Radiance's tutorial room: its counts as the files give them, a scene BuildScene takes, and
// the room check's verdict on a window whose glazing lies in its opening.
TEST(RadImportTest, ReadsAPublicModel) {
  std::vector<RadSource> sources;
  int polygons = 0;
  for (const char* file :
       {"materials.rad", "objects/Floor.rad", "objects/InteriorWall.rad", "objects/Ceiling.rad",
        "objects/Glazing.rad", "objects/ExteriorWalls.rad", "objects/Ground.rad"}) {
    const std::string text = ReadText(kModel + file);
    for (size_t at = text.find(" polygon "); at != std::string::npos;
         at = text.find(" polygon ", at + 1)) {
      ++polygons;
    }
    sources.push_back({file, text,
                       std::string(file).find("Exterior") != std::string::npos ||
                           std::string(file).find("Ground") != std::string::npos});
  }
  const std::string points = ReadText(kModel + "points.txt");
  RadImportSummary summary;
  absl::StatusOr<v1::Scene> scene = ImportRadiance(sources, {"points.txt", points}, {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(polygons, 19);
  EXPECT_EQ(summary.polygons, polygons);
  EXPECT_EQ(summary.materials, 6);
  EXPECT_EQ(summary.windows, 1);
  EXPECT_EQ(summary.void_polygons, 0);
  EXPECT_EQ(summary.triangulated_polygons, 2);  // the exterior wall's face and the ground ring
  EXPECT_EQ(scene->sensors_size(), 100);
  ASSERT_EQ(scene->windows_size(), 1);
  const v1::Window& w = scene->windows(0);
  EXPECT_EQ(w.name(), "f_18_0");
  EXPECT_NEAR(w.center().x(), 3.048, 1e-12);
  EXPECT_NEAR(w.center().z(), 1.6764, 1e-12);
  EXPECT_DOUBLE_EQ(w.outward_normal().y(), -1);
  EXPECT_DOUBLE_EQ(w.up().z(), 1);
  EXPECT_NEAR(w.width_m(), 6.096, 1e-12);
  EXPECT_NEAR(w.height_m(), 1.524, 1e-12);
  absl::StatusOr<Scene> built = BuildScene(*scene, "room.rad");
  ASSERT_TRUE(built.ok()) << built.status();

  // As a room: the glazing, 1 mm behind the window, leaves the opening open
  const absl::StatusOr<Scene> room = ValidateScene(*scene, "room.rad");
  EXPECT_TRUE(room.ok()) << room.status();

  ExpectRoundTrip(*scene);
  // The model's own scene file runs `!xform` commands, which are not run
  absl::StatusOr<v1::Scene> listed =
      ImportRadiance({{"room.rad", ReadText(kModel + "room.rad")}}, {"points.txt", points});
  ASSERT_FALSE(listed.ok());
  EXPECT_NE(listed.status().message().find("room.rad:1: unsupported primitive '!xform'"),
            std::string::npos)
      << listed.status();
}

TEST(RadImportTest, ExportReadsBackTheLightwell) {
  absl::StatusOr<v1::Scene> lightwell =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/lightwell/scene.json");
  ASSERT_TRUE(lightwell.ok()) << lightwell.status();
  ExpectRoundTrip(*lightwell);
  // The round trip keeps it a room
  std::string points;
  absl::StatusOr<std::string> rad = ExportRadiance(*lightwell, &points);
  ASSERT_TRUE(rad.ok()) << rad.status();
  absl::StatusOr<v1::Scene> back = ImportRadiance({{"lightwell.rad", *rad}}, {"l.pts", points});
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->name(), lightwell->name());
  EXPECT_TRUE(ValidateScene(*back, FENESTRA_SOURCE_DIR "/examples/lightwell/scene.json").ok());
}

// The city office has boxes and its blind in the one-window form: its round-trip form has
// polygons and `windows`; the blind reads back from its window, its slats written for Radiance.
TEST(RadImportTest, ExportReadsBackTheCityOfficeWithItsBlind) {
  absl::StatusOr<v1::Scene> office =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(office.ok()) << office.status();
  ExpectRoundTrip(*office);
  absl::StatusOr<v1::Scene> form = RadianceRoundTripForm(*office);
  ASSERT_TRUE(form.ok()) << form.status();
  int boxes = 0;
  for (const v1::Surface& s : office->surfaces()) boxes += s.has_box();
  EXPECT_EQ(form->surfaces_size(), office->surfaces_size() + 5 * boxes);
  ASSERT_EQ(form->windows_size(), 1);
  EXPECT_FALSE(form->has_window());
  EXPECT_TRUE(form->windows(0).has_blind());
  std::string points;
  absl::StatusOr<std::string> rad = ExportRadiance(*office, &points);
  ASSERT_TRUE(rad.ok()) << rad.status();
  const size_t begin = rad->find("#@fenestra blind-geometry begin\n");
  const size_t end = rad->find("#@fenestra blind-geometry end\n");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  int slat_polygons = 0;
  for (size_t at = rad->find(" polygon w0_slat_", begin); at < end;
       at = rad->find(" polygon w0_slat_", at + 1)) {
    ++slat_polygons;
  }
  EXPECT_EQ(slat_polygons, 10 * 12);  // 10 slats (the README's summary), 12 triangles each
  absl::StatusOr<v1::Scene> back = ImportRadiance({{"office.rad", *rad}}, {"o.pts", points});
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(ValidateScene(*back, FENESTRA_SOURCE_DIR "/examples/city_office/scene.json").ok());
}

// Every kind of material, names Radiance does not take, outdoor surfaces, two windows (one
// with a blind), sensors and a site read back as they were.
TEST(RadImportTest, ExportReadsBackEveryPartOfAPolygonScene) {
  v1::Scene scene;
  ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(R"({
    "name": "two windows: a test",
    "materials": [
      {"name": "white wall", "reflectance": 0.7},
      {"name": "clear glazing", "reflectance": 0.08, "transmittance": 0.72},
      {"name": "void", "plastic": {"reflectance": 0.5, "specularity": 0.03, "roughness": 0.1}},
      {"name": "alu", "metal": {"reflectance": 0.8, "specularity": 0.9, "roughness": 0.05}},
      {"name": "fabric", "trans": {"reflectance": 0.6, "specularity": 0.01, "roughness": 0.02,
                                   "transmissivity": 0.3, "transmittedSpecular": 0.1}},
      {"name": "pane", "glass": {"transmittance": 0.9}}
    ],
    "surfaces": [
      {"name": "floor", "material": "white wall", "side": "SIDE_INDOOR",
       "polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 0.1, "y": 0, "z": 0},
                                {"x": 0.1, "y": 0.3, "z": 1e-17}]}},
      {"name": "", "material": "clear glazing", "side": "SIDE_INDOOR",
       "polygon": {"vertices": [{"x": 1, "y": 0, "z": 0}, {"x": 2, "y": 0, "z": 0},
                                {"x": 2, "y": 0, "z": 1}, {"x": 1, "y": 0, "z": 1}]}},
      {"name": "  city block #3 ", "material": "void", "side": "SIDE_OUTDOOR",
       "box": {"min": {"x": -9, "y": 5, "z": 0}, "max": {"x": -8, "y": 6, "z": 0.3333333333333333}}},
      {"name": "pane", "material": "pane", "side": "SIDE_INDOOR",
       "polygon": {"vertices": [{"x": 1, "y": 0, "z": 0}, {"x": 2, "y": 0, "z": 0},
                                {"x": 2, "y": 0, "z": 1}]}}
    ],
    "windows": [
      {"name": "east", "center": {"x": 4, "y": 2, "z": 1.5},
       "outwardNormal": {"x": 1, "y": 0, "z": 0}, "up": {"x": 0, "y": 0, "z": 1},
       "widthM": 1.2, "heightM": 1.1, "depthM": 0.2,
       "blind": {"material": "alu", "outerMaterial": "fabric", "orientation": "VERTICAL",
                 "tiltRad": {"value": 0.3, "min": -1, "max": 1.5},
                 "slatWidthM": {"value": 0.05, "min": 0.02, "max": 0.08},
                 "slatSpacingM": {"value": 0.01, "min": 0, "max": 0.05},
                 "slatThicknessM": {"value": 0.002, "min": 0.001, "max": 0.003},
                 "wallGapM": 0.02, "operation": "AUTOMATED_SUN", "group": "g1"}},
      {"center": {"x": 2, "y": 0, "z": 1}, "outwardNormal": {"x": 0, "y": -1, "z": 0},
       "up": {"x": 0, "y": 0, "z": 1}, "widthM": 0.5, "heightM": 0.5}
    ],
    "sensors": [
      {"name": "desk \"1\"", "position": {"x": 0.1, "y": 0.2, "z": 0.7},
       "direction": {"x": 0, "y": 0, "z": 2}},
      {"name": "", "position": {"x": -1e-300, "y": 3.3, "z": 0.7},
       "direction": {"x": 0.3, "y": 0.4, "z": 0.5}}
    ],
    "site": {"latitudeDeg": -34.83, "longitudeDeg": -56, "timeZoneH": -3,
             "weatherFile": "../weather/montevideo.epw", "groundReflectance": 0}
  })",
                                                          &scene)
                  .ok());
  ExpectRoundTrip(scene);
  // Many sensors: names on several lines
  for (int i = 0; i < 250; ++i) {
    v1::Sensor* s = scene.add_sensors();
    s->set_name(absl::StrCat("grid ", i));
    s->mutable_position()->set_x(0.001 * i);
    s->mutable_direction()->set_z(1);
  }
  ExpectRoundTrip(scene);
}

TEST(RadImportTest, ExportRefusesWhatItCannotWrite) {
  absl::StatusOr<v1::Scene> office =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(office.ok()) << office.status();
  v1::Scene obj = *office;
  obj.mutable_surfaces(0)->mutable_obj()->set_path("chair.obj");
  std::string points;
  absl::StatusOr<std::string> rad = ExportRadiance(obj, &points);
  EXPECT_EQ(rad.status().code(), absl::StatusCode::kFailedPrecondition) << rad.status();
  EXPECT_NE(rad.status().message().find("surfaces[0] is an OBJ mesh"), std::string::npos);
  v1::Scene unknown = *office;
  unknown.mutable_surfaces(1)->set_material("marble");
  rad = ExportRadiance(unknown, &points);
  EXPECT_EQ(rad.status().code(), absl::StatusCode::kInvalidArgument) << rad.status();
  EXPECT_NE(rad.status().message().find("surfaces[1].material: unknown material 'marble'"),
            std::string::npos)
      << rad.status();
  v1::Scene wide = *office;
  wide.mutable_blind()->mutable_slat_width_m()->set_value(5);
  rad = ExportRadiance(wide, &points);
  EXPECT_NE(rad.status().message().find("scene: windows[0]: blind.slat_width_m"), std::string::npos)
      << rad.status();
}

}  // namespace
}  // namespace fenestra
