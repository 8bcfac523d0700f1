// Ear clipping of planar polygons with holes: the triangles tile the region (their areas add
// up to it, each turns the outline's way, none lies in a hole), and bad polygons are refused.
#include "core/geometry/polygon_triangulate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace fenestra {
namespace {

using ::testing::HasSubstr;

using Ring = std::vector<Vec3d>;
using Triangles = std::vector<std::array<Vec3d, 3>>;

// A ring in the plane z = 0 from (x, y) pairs.
Ring Flat(std::initializer_list<std::pair<double, double>> xy) {
  Ring ring;
  for (const auto& [x, y] : xy) ring.push_back({x, y, 0});
  return ring;
}

Ring Reversed(Ring ring) {
  std::reverse(ring.begin(), ring.end());
  return ring;
}

Vec3d TriangleNormal(const std::array<Vec3d, 3>& t) { return Cross(t[1] - t[0], t[2] - t[0]); }

double Area(const Triangles& triangles) {
  double area = 0;
  for (const auto& t : triangles) area += 0.5 * Length(TriangleNormal(t));
  return area;
}

// Every triangle turns about `normal` (has area), and its centroid lies in none of the
// axis-aligned boxes `holes` (given as min, max corners in x and y).
void ExpectTiling(const Triangles& triangles, Vec3d normal, double area,
                  const std::vector<std::array<double, 4>>& hole_boxes = {}) {
  EXPECT_NEAR(Area(triangles), area, 1e-9 * area);
  for (const auto& t : triangles) {
    EXPECT_GT(Dot(TriangleNormal(t), normal), 1e-12) << "a triangle without area or turned over";
    const Vec3d c = (t[0] + t[1] + t[2]) / 3.0;
    for (const auto& box : hole_boxes) {
      EXPECT_FALSE(c.x > box[0] && c.x < box[2] && c.y > box[1] && c.y < box[3])
          << "a triangle in a hole at (" << c.x << ", " << c.y << ")";
    }
  }
}

// +1 when `ring` turns counterclockwise about +z, -1 when clockwise.
double Turn(const Ring& ring) {
  double twice = 0;
  for (size_t k = 0; k < ring.size(); ++k) twice += Cross(ring[k], ring[(k + 1) % ring.size()]).z;
  return twice > 0 ? 1 : -1;
}

const Ring kSquare = Flat({{0, 0}, {4, 0}, {4, 4}, {0, 4}});
const Ring kSquareHole = Flat({{1, 1}, {3, 1}, {3, 3}, {1, 3}});

TEST(TriangulatePlanarPolygonTest, ConvexPolygonGivesItsFan) {
  const auto triangles = TriangulatePlanarPolygon(kSquare);
  ASSERT_TRUE(triangles.ok()) << triangles.status();
  EXPECT_EQ(triangles->size(), 2u);
  ExpectTiling(*triangles, {0, 0, 1}, 16);
}

TEST(TriangulatePlanarPolygonTest, SquareWithASquareHoleEitherWayRound) {
  for (const Ring& hole : {kSquareHole, Reversed(kSquareHole)}) {
    for (const Ring& outline : {kSquare, Reversed(kSquare)}) {
      const std::vector<Ring> holes{hole};
      const auto triangles = TriangulatePlanarPolygon(outline, holes);
      ASSERT_TRUE(triangles.ok()) << triangles.status();
      EXPECT_EQ(triangles->size(), 8u);  // n + 2h - 2 triangles for n vertices, h holes
      ExpectTiling(*triangles, {0, 0, Turn(outline)}, 12, {{1, 1, 3, 3}});
    }
  }
}

TEST(TriangulatePlanarPolygonTest, TwoHoles) {
  const Ring outline = Flat({{0, 0}, {10, 0}, {10, 4}, {0, 4}});
  const std::vector<Ring> holes{Flat({{1, 1}, {3, 1}, {3, 3}, {1, 3}}),
                                Flat({{6, 1}, {9, 1}, {9, 2}, {6, 2}})};
  const auto triangles = TriangulatePlanarPolygon(outline, holes);
  ASSERT_TRUE(triangles.ok()) << triangles.status();
  EXPECT_EQ(triangles->size(), 12u + 2 * 2 - 2);
  ExpectTiling(*triangles, {0, 0, 1}, 40 - 4 - 3, {{1, 1, 3, 3}, {6, 1, 9, 2}});
}

TEST(TriangulatePlanarPolygonTest, LShapeAndUShape) {
  const Ring l = Flat({{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}});
  const auto l_triangles = TriangulatePlanarPolygon(l);
  ASSERT_TRUE(l_triangles.ok()) << l_triangles.status();
  EXPECT_EQ(l_triangles->size(), 4u);
  ExpectTiling(*l_triangles, {0, 0, 1}, 5, {{1, 1, 3, 3}});

  const Ring u = Flat({{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}});
  const auto u_triangles = TriangulatePlanarPolygon(u);
  ASSERT_TRUE(u_triangles.ok()) << u_triangles.status();
  EXPECT_EQ(u_triangles->size(), 6u);
  ExpectTiling(*u_triangles, {0, 0, 1}, 7, {{1, 1, 2, 3}});
}

TEST(TriangulatePlanarPolygonTest, CollinearPointsMakeNoZeroAreaTriangles) {
  const Ring outline =
      Flat({{0, 0}, {1, 0}, {2, 0}, {3, 0}, {3, 1}, {3, 2}, {1.5, 2}, {0, 2}, {0, 1}});
  const auto triangles = TriangulatePlanarPolygon(outline);
  ASSERT_TRUE(triangles.ok()) << triangles.status();
  ExpectTiling(*triangles, {0, 0, 1}, 6);
  // A hole with a vertex in the middle of an edge
  const std::vector<Ring> holes{Flat({{1, 0.5}, {1.5, 0.5}, {2, 0.5}, {2, 1.5}, {1, 1.5}})};
  const auto holed = TriangulatePlanarPolygon(outline, holes);
  ASSERT_TRUE(holed.ok()) << holed.status();
  ExpectTiling(*holed, {0, 0, 1}, 5, {{1, 0.5, 2, 1.5}});
}

TEST(TriangulatePlanarPolygonTest, OutlineWithASeamToAHoleAndRepeatedVertices) {
  // As Radiance writes a polygon with a hole: the outline, back to its first vertex, a cut to
  // the hole, round the hole (clockwise), back to the hole's first vertex and along the cut
  const Ring seam =
      Flat({{0, 0}, {4, 0}, {4, 4}, {0, 4}, {0, 0}, {1, 1}, {1, 3}, {3, 3}, {3, 1}, {1, 1}});
  const auto triangles = TriangulatePlanarPolygon(seam);
  ASSERT_TRUE(triangles.ok()) << triangles.status();
  ExpectTiling(*triangles, {0, 0, 1}, 12, {{1, 1, 3, 3}});
  // The same with the seam in the middle of the outline and a vertex given twice in a row
  const Ring middle = Flat({{0, 0},
                            {4, 0},
                            {4, 0},
                            {4, 2},
                            {3, 2},
                            {3, 1},
                            {1, 1},
                            {1, 3},
                            {3, 3},
                            {3, 2},
                            {4, 2},
                            {4, 4},
                            {0, 4}});
  const auto middle_triangles = TriangulatePlanarPolygon(middle);
  ASSERT_TRUE(middle_triangles.ok()) << middle_triangles.status();
  ExpectTiling(*middle_triangles, {0, 0, 1}, 12, {{1, 1, 3, 3}});
  // Two holes on seams of their own
  const Ring two = Flat({{0, 0},
                         {8, 0},
                         {8, 4},
                         {0, 4},
                         {0, 0},
                         {1, 1},
                         {1, 3},
                         {3, 3},
                         {3, 1},
                         {1, 1},
                         {0, 0},
                         {5, 1},
                         {5, 3},
                         {7, 3},
                         {7, 1},
                         {5, 1}});
  const auto two_triangles = TriangulatePlanarPolygon(two);
  ASSERT_TRUE(two_triangles.ok()) << two_triangles.status();
  ExpectTiling(*two_triangles, {0, 0, 1}, 32 - 8, {{1, 1, 3, 3}, {5, 1, 7, 3}});
}

TEST(TriangulatePlanarPolygonTest, HolesTouchingTheOutlineAndEachOther) {
  // A door from the floor up and a window beside it, sharing its edge with the door
  const Ring wall = Flat({{0, 0}, {6, 0}, {6, 3}, {0, 3}});
  const std::vector<Ring> holes{Flat({{1, 0}, {2, 0}, {2, 2}, {1, 2}}),
                                Flat({{2, 1}, {4, 1}, {4, 2}, {2, 2}})};
  const auto triangles = TriangulatePlanarPolygon(wall, holes);
  ASSERT_TRUE(triangles.ok()) << triangles.status();
  ExpectTiling(*triangles, {0, 0, 1}, 18 - 2 - 2, {{1, 0, 2, 2}, {2, 1, 4, 2}});
  // A window filling the wall's width
  const std::vector<Ring> band{Flat({{0, 1}, {6, 1}, {6, 2}, {0, 2}})};
  const auto banded = TriangulatePlanarPolygon(wall, band);
  ASSERT_TRUE(banded.ok()) << banded.status();
  ExpectTiling(*banded, {0, 0, 1}, 12, {{0, 1, 6, 2}});
}

TEST(TriangulatePlanarPolygonTest, WallInSpaceKeepsItsPointsAndTurn) {
  // A south wall (normal -y) with a window, in 3D
  const Ring wall{{0, 0, 0}, {5, 0, 0}, {5, 0, 3}, {0, 0, 3}};
  const std::vector<Ring> window{{{1, 0, 1}, {4, 0, 1}, {4, 0, 2}, {1, 0, 2}}};
  const auto triangles = TriangulatePlanarPolygon(wall, window);
  ASSERT_TRUE(triangles.ok()) << triangles.status();
  EXPECT_NEAR(Area(*triangles), 12, 1e-12);
  for (const auto& t : *triangles) {
    EXPECT_GT(Dot(TriangleNormal(t), Vec3d{0, -1, 0}), 0);
    for (const Vec3d& p : t) {
      EXPECT_EQ(p.y, 0);
      const bool given = (p.x == 0 || p.x == 5 || p.x == 1 || p.x == 4) &&
                         (p.z == 0 || p.z == 3 || p.z == 1 || p.z == 2);
      EXPECT_TRUE(given) << "a point that is not a vertex: " << p.x << ", " << p.z;
    }
  }
}

TEST(TriangulatePlanarPolygonTest, RandomStarsWithHolesTileTheirArea) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    // A star: vertices at random radii in [1, 2] about the origin, by angle
    const int n = 8 + static_cast<int>(unit(random) * 40);
    Ring outline;
    for (int k = 0; k < n; ++k) {
      const double angle = 2 * std::numbers::pi * (k + 0.8 * unit(random)) / n;
      const double radius = 1 + unit(random);
      outline.push_back({radius * std::cos(angle), radius * std::sin(angle), 0});
    }
    // Up to three squares, apart, within 0.7 of the origin: inside the star, whose edges stay
    // cos(81 / 2 degrees) = 0.76 from it at least
    std::vector<Ring> holes;
    std::vector<std::array<double, 4>> boxes;
    const int hole_count = static_cast<int>(unit(random) * 4);
    for (int h = 0; h < hole_count; ++h) {
      const double x = -0.5 + 0.35 * h, y = -0.45 + 0.7 * unit(random),
                   s = 0.05 + 0.15 * unit(random);
      holes.push_back(Flat({{x, y}, {x + s, y}, {x + s, y + s}, {x, y + s}}));
      boxes.push_back({x, y, x + s, y + s});
    }
    double area = 0;
    for (int k = 0; k < n; ++k) area += 0.5 * Cross(outline[k], outline[(k + 1) % n]).z;
    for (const auto& b : boxes) area -= (b[2] - b[0]) * (b[3] - b[1]);
    const auto triangles = TriangulatePlanarPolygon(outline, holes);
    ASSERT_TRUE(triangles.ok()) << "trial " << trial << ": " << triangles.status();
    ExpectTiling(*triangles, {0, 0, 1}, area, boxes);
    const auto pieces = ConvexPiecesOfPlanarPolygon(outline, holes);
    ASSERT_TRUE(pieces.ok()) << pieces.status();
    EXPECT_LE(pieces->size(), triangles->size());
  }
}

TEST(TriangulatePlanarPolygonTest, RandomTouchingHolesOnAGridTileTheirArea) {
  // Rectangles of whole metres in a wall of whole metres: holes touch each other and the
  // wall's edges at corners and along edges, and may cut the wall into several parts
  std::mt19937_64 random(11);
  const auto whole = [&](int below) {
    return static_cast<int>(random() % static_cast<uint64_t>(below));
  };
  for (int trial = 0; trial < 400; ++trial) {
    const int w = 2 + whole(7), h = 2 + whole(7);
    std::vector<std::array<double, 4>> boxes;
    for (int attempt = 0; attempt < 12 && boxes.size() < 5; ++attempt) {
      const int x0 = whole(w), y0 = whole(h);
      const int x1 = x0 + 1 + whole(w - x0), y1 = y0 + 1 + whole(h - y0);
      if (x1 - x0 == w && y1 - y0 == h) continue;  // the whole wall
      bool apart = true;
      for (const auto& b : boxes)
        apart = apart && (x1 <= b[0] || x0 >= b[2] || y1 <= b[1] || y0 >= b[3]);
      if (apart) boxes.push_back({double(x0), double(y0), double(x1), double(y1)});
    }
    std::vector<Ring> holes;
    double area = w * h;
    for (const auto& b : boxes) {
      Ring hole = Flat({{b[0], b[1]}, {b[2], b[1]}, {b[2], b[3]}, {b[0], b[3]}});
      holes.push_back(trial % 2 ? hole : Reversed(hole));
      area -= (b[2] - b[0]) * (b[3] - b[1]);
    }
    const Ring wall = Flat({{0, 0}, {double(w), 0}, {double(w), double(h)}, {0, double(h)}});
    const auto triangles = TriangulatePlanarPolygon(wall, holes);
    ASSERT_TRUE(triangles.ok()) << "trial " << trial << ": " << triangles.status();
    ExpectTiling(*triangles, {0, 0, 1}, area, boxes);
    const auto pieces = ConvexPiecesOfPlanarPolygon(wall, holes);
    ASSERT_TRUE(pieces.ok()) << "trial " << trial << ": " << pieces.status();
  }
}

// Twice the signed area of each corner of `piece` about +z.
std::vector<double> Turns(const std::vector<Vec3d>& piece) {
  std::vector<double> turns;
  for (size_t k = 0; k < piece.size(); ++k) {
    const Vec3d a = piece[k], b = piece[(k + 1) % piece.size()], c = piece[(k + 2) % piece.size()];
    turns.push_back(Cross(b - a, c - b).z);
  }
  return turns;
}

TEST(ConvexPiecesOfPlanarPolygonTest, PiecesAreConvexAndCoverTheRegion) {
  const std::vector<Ring> holes{kSquareHole};
  const auto pieces = ConvexPiecesOfPlanarPolygon(kSquare, holes);
  ASSERT_TRUE(pieces.ok()) << pieces.status();
  EXPECT_LT(pieces->size(), 8u);  // fewer than the 8 triangles
  EXPECT_GE(pieces->size(), 4u);  // a frame needs 4 convex pieces
  double area = 0;
  for (const auto& piece : *pieces) {
    for (const double turn : Turns(piece)) EXPECT_GE(turn, -1e-12);
    for (size_t k = 1; k + 1 < piece.size(); ++k) {
      area += 0.5 * Cross(piece[k] - piece[0], piece[k + 1] - piece[0]).z;
    }
  }
  EXPECT_NEAR(area, 12, 1e-12);

  const Ring l = Flat({{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}});
  const auto l_pieces = ConvexPiecesOfPlanarPolygon(l);
  ASSERT_TRUE(l_pieces.ok()) << l_pieces.status();
  EXPECT_EQ(l_pieces->size(), 2u);
}

TEST(TriangulatePlanarPolygonTest, RefusesSelfIntersectingOutlines) {
  const auto bow_tie = TriangulatePlanarPolygon(Flat({{0, 0}, {4, 4}, {4, 0}, {0, 2}}));
  EXPECT_EQ(bow_tie.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bow_tie.status().message(), HasSubstr("the outline crosses itself"));
  const auto figure = TriangulatePlanarPolygon(
      Flat({{0, 0}, {4, 0}, {4, 2}, {1, 2}, {1, -1}, {2, -1}, {2, 3}, {0, 3}}));
  EXPECT_THAT(figure.status().message(), HasSubstr("the outline crosses itself"));
}

TEST(TriangulatePlanarPolygonTest, RefusesHolesOutsideCrossingOrOverlapping) {
  const std::vector<Ring> outside{Flat({{5, 5}, {6, 5}, {6, 6}, {5, 6}})};
  EXPECT_THAT(TriangulatePlanarPolygon(kSquare, outside).status().message(),
              HasSubstr("hole 0 lies outside the outline"));
  const std::vector<Ring> crossing{Flat({{3, 1}, {5, 1}, {5, 2}, {3, 2}})};
  EXPECT_THAT(TriangulatePlanarPolygon(kSquare, crossing).status().message(),
              HasSubstr("hole 0 lies outside the outline"));
  const std::vector<Ring> across{Flat({{-1, 1}, {5, 1}, {5, 2}, {-1, 2}})};
  EXPECT_EQ(TriangulatePlanarPolygon(kSquare, across).status().code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<Ring> overlapping{kSquareHole, Flat({{2, 2}, {3.5, 2}, {3.5, 3.5}, {2, 3.5}})};
  EXPECT_THAT(TriangulatePlanarPolygon(kSquare, overlapping).status().message(),
              HasSubstr("holes 0 and 1 overlap"));
  const std::vector<Ring> twice{kSquareHole, Reversed(kSquareHole)};
  EXPECT_THAT(TriangulatePlanarPolygon(kSquare, twice).status().message(),
              HasSubstr("holes 0 and 1 overlap"));
  const std::vector<Ring> nested{kSquareHole, Flat({{1.5, 1.5}, {2, 1.5}, {2, 2}, {1.5, 2}})};
  EXPECT_THAT(TriangulatePlanarPolygon(kSquare, nested).status().message(),
              HasSubstr("holes 0 and 1 overlap"));
}

TEST(TriangulatePlanarPolygonTest, RefusesBadInput) {
  const auto message = [](std::span<const Vec3d> outline,
                          std::span<const std::vector<Vec3d>> holes = {}) {
    const auto result = TriangulatePlanarPolygon(outline, holes);
    EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(result.status().message());
  };
  EXPECT_THAT(message(Flat({{0, 0}, {1, 0}})), HasSubstr("at least 3 vertices"));
  EXPECT_THAT(message(Flat({{0, 0}, {1, 0}, {1, 0}, {0, 0}})), HasSubstr("no area"));
  EXPECT_THAT(message(Flat({{0, 0}, {1, 0}, {2, 0}})), HasSubstr("no area"));
  Ring bent = kSquare;
  bent[2].z = 0.5;
  EXPECT_THAT(message(bent), HasSubstr("off the outline's plane: the polygon is not planar"));
  Ring nan = kSquare;
  nan[1].y = std::nan("");
  EXPECT_THAT(message(nan), HasSubstr("outline vertex 1: coordinates must be finite"));
  Ring infinite = kSquare;
  infinite[3].x = HUGE_VAL;
  EXPECT_THAT(message(infinite), HasSubstr("outline vertex 3: coordinates must be finite"));
  const std::vector<Ring> flat_hole{Flat({{1, 1}, {2, 2}, {3, 3}})};
  EXPECT_THAT(message(kSquare, flat_hole), HasSubstr("hole 0 has no area"));
  Ring circle;
  for (size_t k = 0; k <= kMaxTriangulatedVertices; ++k) {
    const double angle = 2 * std::numbers::pi * static_cast<double>(k) / 3000;
    circle.push_back({std::cos(angle), std::sin(angle), 0});
  }
  EXPECT_THAT(message(circle), HasSubstr("more than the 2048"));
  circle.resize(kMaxTriangulatedVertices);
  const auto many = TriangulatePlanarPolygon(circle);
  ASSERT_TRUE(many.ok()) << many.status();
  EXPECT_EQ(many->size(), kMaxTriangulatedVertices - 2);
}

}  // namespace
}  // namespace fenestra
