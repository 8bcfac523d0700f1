#include "core/geometry/hbjson_shapes.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geometry/hbjson_import.h"
#include "core/geometry/polygon_triangulate.h"
#include "core/geometry/scene.h"

namespace fenestra::hbjson {
namespace {

// A corner of a convex polygon may turn back by this much, relative to its longest edge
// squared: a thousandth of what a scene's convexity check allows.
constexpr double kConvexTurn = 1e-9;
// A piece is dropped when its area is at most this times its longest edge squared (twice
// where a scene refuses a polygon as degenerate), or its longest edge is below 1 micrometre.
constexpr double kDegenerateArea = 2e-6;
constexpr double kShortestEdgeM = 1e-6;
// Longest window name (scene.proto's Window.name).
constexpr size_t kMaxWindowName = 64;

Vec3d Newell(const std::vector<Vec3d>& ring) {
  Vec3d n{0, 0, 0};
  for (size_t k = 0; k < ring.size(); ++k) {
    n += Cross(ring[k] - ring[0], ring[(k + 1) % ring.size()] - ring[0]);
  }
  return n;
}

double LongestEdge(const std::vector<Vec3d>& ring) {
  double longest = 0;
  for (size_t k = 0; k < ring.size(); ++k) {
    longest = std::max(longest, Length(ring[(k + 1) % ring.size()] - ring[k]));
  }
  return longest;
}

bool WithinScene(Vec3d p) {
  return std::abs(p.x) <= kMaxCoordinateM && std::abs(p.y) <= kMaxCoordinateM &&
         std::abs(p.z) <= kMaxCoordinateM;
}

// The points of array `points` times `scale`, each within the scene's bounds.
absl::StatusOr<std::vector<Vec3d>> ReadRing(const Json& points, double scale) {
  FENESTRA_ASSIGN_OR_RETURN(ring, points.Points(scale, kMaxTriangulatedVertices));
  for (size_t i = 0; i < ring.size(); ++i) {
    if (!WithinScene(ring[i])) {
      return points.At(i).Error(
          absl::StrCat("lies beyond ", kMaxCoordinateM, " m from the origin, the scene's bound"));
    }
  }
  return ring;
}

// Whether `ring` (turning counterclockwise about `normal`) is convex: no corner turns back,
// and the corners turn once round in all.
bool IsConvex(const std::vector<Vec3d>& ring, Vec3d normal) {
  const double longest = LongestEdge(ring);
  double turning = 0;
  for (size_t k = 0; k < ring.size(); ++k) {
    const Vec3d a = ring[k], b = ring[(k + 1) % ring.size()], c = ring[(k + 2) % ring.size()];
    const Vec3d in = b - a, out = c - b;
    if (Length(in) == 0 || Length(out) == 0) continue;
    const double turn = Dot(Cross(in, out), normal);
    if (turn < -kConvexTurn * longest * longest) return false;
    turning += std::atan2(turn, Dot(in, out));
  }
  return std::abs(turning - 2 * std::numbers::pi) < 1e-6;
}

}  // namespace

bool IsDegeneratePolygon(const std::vector<Vec3d>& polygon) {
  if (polygon.size() < 3) return true;
  const double longest = LongestEdge(polygon);
  return !(longest >= kShortestEdgeM) ||
         !(0.5 * Length(Newell(polygon)) > kDegenerateArea * longest * longest);
}

Vec3d NewellNormal(const std::vector<Vec3d>& ring) { return Newell(ring); }

absl::StatusOr<Shape> ReadShape(const Json& geometry, double scale, const Tolerances& tolerances) {
  Shape shape;
  FENESTRA_ASSIGN_OR_RETURN(boundary, geometry.Get("boundary"));
  FENESTRA_ASSIGN_OR_RETURN(outline, ReadRing(boundary, scale));
  shape.outline = std::move(outline);
  if (shape.outline.size() < 3) return boundary.Error("a polygon needs at least 3 points");
  FENESTRA_ASSIGN_OR_RETURN(holes, geometry.ListOf("holes", kMaxTriangulatedVertices, "holes"));
  size_t total = shape.outline.size();
  for (const Json& hole : holes) {
    FENESTRA_ASSIGN_OR_RETURN(ring, ReadRing(hole, scale));
    total += ring.size();
    if (total > kMaxTriangulatedVertices) {
      return geometry.Error(absl::StrCat("more than ", kMaxTriangulatedVertices,
                                         " points in its boundary and holes"));
    }
    shape.holes.push_back(std::move(ring));
  }
  const Vec3d newell = Newell(shape.outline);
  const double longest = LongestEdge(shape.outline);
  if (!(0.5 * Length(newell) > kDegenerateArea * longest * longest)) {
    return geometry.Error("the polygon has no area");
  }
  shape.normal = Normalize(newell);
  Vec3d sum{0, 0, 0};
  for (const Vec3d& p : shape.outline) sum += p;
  shape.origin = sum / static_cast<double>(shape.outline.size());

  // Flatten onto the plane, within the tolerance
  const auto flatten = [&](std::vector<Vec3d>& ring, const Json& where) -> absl::Status {
    for (size_t i = 0; i < ring.size(); ++i) {
      const double off = Dot(ring[i] - shape.origin, shape.normal);
      if (std::abs(off) > tolerances.length) {
        return where.At(i).Error(absl::StrCat("lies ", std::abs(off),
                                              " m off its polygon's plane, more than the "
                                              "model's tolerance of ",
                                              tolerances.length, " m: it is not planar"));
      }
      ring[i] = ring[i] - off * shape.normal;
    }
    return absl::OkStatus();
  };
  FENESTRA_RETURN_IF_ERROR(flatten(shape.outline, boundary));
  for (size_t h = 0; h < shape.holes.size(); ++h) {
    FENESTRA_RETURN_IF_ERROR(flatten(shape.holes[h], holes[h]));
  }
  return shape;
}

absl::StatusOr<std::vector<Vec3d>> OntoPlane(const Shape& face, const std::vector<Vec3d>& points,
                                             const Tolerances& tolerances, const Json& where) {
  std::vector<Vec3d> out;
  for (const Vec3d& p : points) {
    const double off = Dot(p - face.origin, face.normal);
    if (std::abs(off) > tolerances.length) {
      return where.Error(absl::StrCat("lies ", std::abs(off),
                                      " m off its face's plane, more than the model's tolerance "
                                      "of ",
                                      tolerances.length, " m"));
    }
    out.push_back(p - off * face.normal);
  }
  return out;
}

absl::StatusOr<v1::Window> RectangleWindow(const std::vector<Vec3d>& corners, const Shape& face,
                                           const Tolerances& tolerances, const Json& where) {
  if (corners.size() != 4) {
    return where.Error(
        absl::StrCat("a window must be a rectangle (4 vertices, right angles); "
                     "this one has ",
                     corners.size(), " vertices"));
  }
  Vec3d edge[4];
  double length[4];
  for (int k = 0; k < 4; ++k) {
    edge[k] = corners[(k + 1) % 4] - corners[k];
    length[k] = Length(edge[k]);
    if (!(length[k] >= kMinWindowSideM)) {
      return where.Error(absl::StrCat("a window's side must be at least ", kMinWindowSideM,
                                      " m; side ", k, " is ", length[k], " m"));
    }
  }
  double turn_sign = 0;
  for (int k = 0; k < 4; ++k) {
    const double cosine = Dot(edge[k], edge[(k + 1) % 4]) / (length[k] * length[(k + 1) % 4]);
    const double turn = Dot(Cross(edge[k], edge[(k + 1) % 4]), face.normal);
    if (std::abs(cosine) > std::sin(tolerances.angle) || (k > 0 && turn * turn_sign <= 0)) {
      return where.Error(absl::StrCat(
          "a window must be a rectangle (4 vertices, right angles); its corner ", (k + 1) % 4,
          " is ", std::acos(std::clamp(cosine, -1.0, 1.0)) * 180 / std::numbers::pi,
          " degrees, more than the model's angle tolerance from 90"));
    }
    turn_sign = turn;
  }
  // The two directions of the sides, in the face's plane
  const auto in_plane = [&](Vec3d v) { return Normalize(v - Dot(v, face.normal) * face.normal); };
  const Vec3d along[2] = {in_plane(edge[0] - edge[2]), in_plane(edge[1] - edge[3])};
  const double extent[2] = {0.5 * (length[0] + length[2]), 0.5 * (length[1] + length[3])};
  const bool level = std::max(std::abs(along[0].z), std::abs(along[1].z)) <= 1e-9;
  const auto rise = [&](Vec3d v) { return level ? v.y : v.z; };
  const int u = std::abs(rise(along[1])) > std::abs(rise(along[0])) ? 1 : 0;
  const Vec3d up = rise(along[u]) < 0 ? -along[u] : along[u];
  Vec3d center{0, 0, 0};
  for (const Vec3d& c : corners) center += c;
  center = center / 4.0;
  v1::Window window;
  *window.mutable_center() = [&] {
    v1::Vec3 v;
    v.set_x(center.x), v.set_y(center.y), v.set_z(center.z);
    return v;
  }();
  window.mutable_outward_normal()->set_x(face.normal.x);
  window.mutable_outward_normal()->set_y(face.normal.y);
  window.mutable_outward_normal()->set_z(face.normal.z);
  window.mutable_up()->set_x(up.x);
  window.mutable_up()->set_y(up.y);
  window.mutable_up()->set_z(up.z);
  window.set_height_m(extent[u]);
  window.set_width_m(extent[1 - u]);
  window.set_depth_m(0);
  return window;
}

std::vector<Vec3d> WindowCorners(const v1::Window& window, double inset) {
  const auto vec = [](const v1::Vec3& v) { return Vec3d{v.x(), v.y(), v.z()}; };
  const Vec3d center = vec(window.center()), normal = vec(window.outward_normal());
  const Vec3d up = vec(window.up()), across = Cross(up, normal);
  const double w = 0.5 * window.width_m(), h = 0.5 * window.height_m();
  const Vec3d base = center - inset * normal;
  return {base - w * across - h * up, base + w * across - h * up, base + w * across + h * up,
          base - w * across + h * up};
}

absl::Status SurfaceWriter::AddPolygon(const std::string& name, const std::string& material,
                                       v1::Side side, const std::vector<Vec3d>& vertices,
                                       const Json& where) {
  if (static_cast<size_t>(scene_.surfaces_size()) >= kMaxHoneybeeSurfaces) {
    return where.Error(
        absl::StrCat("the scene would have more than ", kMaxHoneybeeSurfaces, " surfaces"));
  }
  std::string unique = name;
  for (int n = 2; !names_.insert(unique).second; ++n) unique = absl::StrCat(name, "~", n);
  v1::Surface* surface = scene_.add_surfaces();
  surface->set_name(unique);
  surface->set_material(material);
  surface->set_side(side);
  for (const Vec3d& p : vertices) {
    v1::Vec3* v = surface->mutable_polygon()->add_vertices();
    v->set_x(p.x), v->set_y(p.y), v->set_z(p.z);
  }
  return absl::OkStatus();
}

absl::Status SurfaceWriter::Add(const std::string& name, const std::string& material, v1::Side side,
                                const std::vector<Vec3d>& outline,
                                const std::vector<std::vector<Vec3d>>& holes, Vec3d normal,
                                const Json& where) {
  if (holes.empty() && IsConvex(outline, normal)) {
    return AddPolygon(name, material, side, outline, where);
  }
  absl::StatusOr<std::vector<std::vector<Vec3d>>> pieces =
      ConvexPiecesOfPlanarPolygon(outline, holes);
  if (!pieces.ok()) return where.Error(std::string(pieces.status().message()));
  int k = 0;
  for (const std::vector<Vec3d>& piece : *pieces) {
    if (IsDegeneratePolygon(piece)) {
      ++degenerate_;
      continue;
    }
    FENESTRA_RETURN_IF_ERROR(
        AddPolygon(absl::StrCat(name, "#", k++), material, side, piece, where));
  }
  return absl::OkStatus();
}

std::string WindowName(const std::string& id, std::set<std::string>& taken) {
  std::string base;
  for (const char c : id) {
    const bool kept =
        std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
    base.push_back(kept && static_cast<unsigned char>(c) < 0x80 ? c : '_');
    if (base.size() == kMaxWindowName) break;
  }
  std::string name = base;
  for (int n = 2; !taken.insert(name).second; ++n) {
    const std::string suffix = absl::StrCat("_", n);
    name = base.substr(0, kMaxWindowName - suffix.size()) + suffix;
  }
  return name;
}

}  // namespace fenestra::hbjson
