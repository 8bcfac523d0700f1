#include "core/geometry/scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/common/json_proto.h"
#include "core/common/status_macros.h"
#include "core/common/text.h"
#include "core/geometry/material.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/polygon_triangulate.h"

namespace fenestra {
namespace {

// Relative tolerance for planarity and perpendicularity checks.
constexpr double kShapeTolerance = kPolygonShapeTolerance;

// Collects errors as "<file>: <field>: <reason>".
class Checker {
 public:
  explicit Checker(std::string path) : path_(std::move(path)) {}

  absl::Status Error(const std::string& field, const std::string& reason) const {
    return absl::InvalidArgumentError(absl::StrCat(path_, ": ", field, ": ", reason));
  }

  // Whether Point takes `v` (the one rule for it): a check that costs no name.
  static bool Takes(const v1::Vec3& v) {
    for (double c : {v.x(), v.y(), v.z()}) {
      if (!(std::abs(c) <= kMaxCoordinateM)) return false;  // NaN and infinities too
    }
    return true;
  }

  absl::StatusOr<Vec3d> Point(const v1::Vec3& v, const std::string& field) const {
    if (Takes(v)) return Vec3d{v.x(), v.y(), v.z()};
    if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z())) {
      return Error(field, "coordinates must be finite numbers");
    }
    return Within(Vec3d{v.x(), v.y(), v.z()}, field);
  }

  // A point that may be computed (a window corner) must lie within the scene's bounds.
  absl::StatusOr<Vec3d> Within(Vec3d p, const std::string& field) const {
    for (double c : {p.x, p.y, p.z}) {
      if (!(std::abs(c) <= kMaxCoordinateM)) {
        return Error(field,
                     absl::StrCat("(", p.x, ", ", p.y, ", ", p.z, ") lies beyond ", kMaxCoordinateM,
                                  " m from the origin, the scene's bound (the tracer's "
                                  "float coordinates lose millimetres beyond it)"));
      }
    }
    return p;
  }

  absl::StatusOr<Vec3d> Direction(const v1::Vec3& v, const std::string& field) const {
    if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z())) {
      return Error(field, "components must be finite numbers");
    }
    // Scaled first, so that neither tiny nor huge components underflow or overflow
    const double scale = std::max({std::abs(v.x()), std::abs(v.y()), std::abs(v.z())});
    if (!(scale > 0)) return Error(field, "direction must not be zero");
    return Normalize(Vec3d{v.x() / scale, v.y() / scale, v.z() / scale});
  }

  absl::Status Positive(double value, const std::string& field) const {
    if (!std::isfinite(value) || !(value > 0)) {
      return Error(field, absl::StrCat("must be a finite number > 0, got ", value));
    }
    return absl::OkStatus();
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

double TriangleArea(Vec3d a, Vec3d b, Vec3d c) { return 0.5 * Length(Cross(b - a, c - a)); }

// Checks that `value` lies in [0, 1], or in [0, 1) when `below_one`.
absl::Status CheckFraction(double value, bool below_one, const std::string& field,
                           const Checker& check) {
  if (value >= 0 && (below_one ? value < 1 : value <= 1)) return absl::OkStatus();
  return check.Error(field,
                     absl::StrCat("must be in [0, 1", below_one ? ")" : "]", ", got ", value));
}

// The colour, specularity and roughness of a plastic, metal or trans `k` at `field`, checked.
template <typename Kind>
absl::StatusOr<RadianceParameters> LobeParameters(const Kind& k, const std::string& field,
                                                  const Checker& check) {
  FENESTRA_RETURN_IF_ERROR(CheckFraction(k.reflectance(), false, field + ".reflectance", check));
  FENESTRA_RETURN_IF_ERROR(CheckFraction(k.specularity(), true, field + ".specularity", check));
  FENESTRA_RETURN_IF_ERROR(CheckFraction(k.roughness(), false, field + ".roughness", check));
  return RadianceParameters{k.reflectance(), k.specularity(), k.roughness()};
}

// The parts of a Lambertian material (with plain glazing's transmittance), its fields checked.
absl::StatusOr<Material> LambertianParts(const v1::Material& m, const std::string& field,
                                         const Checker& check) {
  Material out;
  out.reflectance = m.reflectance();
  FENESTRA_RETURN_IF_ERROR(CheckFraction(out.reflectance, true, field + ".reflectance", check));
  if (m.has_transmittance()) {
    out.transmittance = m.transmittance();
    FENESTRA_RETURN_IF_ERROR(
        CheckFraction(out.transmittance, false, field + ".transmittance", check));
  }
  return out;
}

// The parts (mesh.h) of material `m`, Lambertian or of a kind, its fields checked; `field`
// names `m`, or its kind's message.
absl::StatusOr<Material> MaterialParts(const v1::Material& m, const std::string& field,
                                       const Checker& check) {
  switch (m.kind_case()) {
    case v1::Material::kPlastic: {
      FENESTRA_ASSIGN_OR_RETURN(p, LobeParameters(m.plastic(), field, check));
      return MaterialOfKind(MaterialKind::kPlastic, p);
    }
    case v1::Material::kMetal: {
      FENESTRA_ASSIGN_OR_RETURN(p, LobeParameters(m.metal(), field, check));
      return MaterialOfKind(MaterialKind::kMetal, p);
    }
    case v1::Material::kTrans: {
      const v1::Material::Trans& t = m.trans();
      FENESTRA_ASSIGN_OR_RETURN(p, LobeParameters(t, field, check));
      FENESTRA_RETURN_IF_ERROR(
          CheckFraction(t.transmissivity(), false, field + ".transmissivity", check));
      FENESTRA_RETURN_IF_ERROR(
          CheckFraction(t.transmitted_specular(), false, field + ".transmitted_specular", check));
      p.transmissivity = t.transmissivity();
      p.transmitted_specular = t.transmitted_specular();
      return MaterialOfKind(MaterialKind::kTrans, p);
    }
    case v1::Material::kGlass: {
      Material glass;
      glass.kind = MaterialKind::kGlass;
      glass.transmittance = m.glass().transmittance();
      if (!(glass.transmittance > 0 && glass.transmittance <= kMaxGlassNormalTransmittance)) {
        return check.Error(field + ".transmittance",
                           absl::StrCat("must be in (0, ", kMaxGlassNormalTransmittance,
                                        "] (a pane of index 1.52 at normal incidence), got ",
                                        glass.transmittance));
      }
      return glass;
    }
    default:
      return LambertianParts(m, field, check);
  }
}

// Material `m` at `field` as its parts: one meaning per setting (Lambertian fields or one
// kind), every parameter in its range, and parts the tracer takes.
absl::StatusOr<Material> BuildMaterial(const v1::Material& m, const std::string& field,
                                       const Checker& check) {
  const bool lambertian = m.kind_case() == v1::Material::KIND_NOT_SET;
  const std::string kind =
      lambertian ? "" : m.GetDescriptor()->FindFieldByNumber(m.kind_case())->name();
  const std::string parts_field = lambertian ? field : field + "." + kind;
  if (!lambertian && (m.has_reflectance() || m.has_transmittance())) {
    return check.Error(field + (m.has_reflectance() ? ".reflectance" : ".transmittance"),
                       absl::StrCat("a material is Lambertian (reflectance, transmittance) or "
                                    "one of plastic, metal, trans and glass, not both: this "
                                    "one also gives ",
                                    kind));
  }
  FENESTRA_ASSIGN_OR_RETURN(material, MaterialParts(m, parts_field, check));
  material.name = m.name();
  if (const absl::Status parts = CheckMaterialParts(material); !parts.ok()) {
    return check.Error(
        parts_field, absl::StrCat("as diffuse, specular and transmitted parts: ", parts.message()));
  }
  return material;
}

absl::StatusOr<std::vector<Material>> BuildMaterials(const v1::Scene& proto, const Checker& check) {
  std::vector<Material> materials;
  for (int i = 0; i < proto.materials_size(); ++i) {
    const v1::Material& m = proto.materials(i);
    const std::string field = absl::StrCat("materials[", i, "]");
    if (m.name().empty()) return check.Error(field + ".name", "must not be empty");
    for (const Material& other : materials) {
      if (other.name == m.name()) {
        return check.Error(field + ".name", absl::StrCat("duplicate material '", m.name(), "'"));
      }
    }
    FENESTRA_ASSIGN_OR_RETURN(material, BuildMaterial(m, field, check));
    materials.push_back(std::move(material));
  }
  if (materials.empty()) return check.Error("materials", "at least one material is required");
  return materials;
}

absl::StatusOr<uint32_t> FindMaterial(const std::vector<Material>& materials,
                                      const std::string& name, const std::string& field,
                                      const Checker& check) {
  for (uint32_t i = 0; i < materials.size(); ++i) {
    if (materials[i].name == name) return i;
  }
  return check.Error(field, absl::StrCat("unknown material '", name, "'"));
}

// The slats' material `name` at `field` (SlatMaterialIndex).
absl::StatusOr<uint32_t> FindSlatMaterial(const std::vector<Material>& materials,
                                          const std::string& name, const std::string& field,
                                          const Checker& check) {
  absl::StatusOr<uint32_t> index = SlatMaterialIndex(materials, name);
  if (!index.ok()) return check.Error(field, std::string(index.status().message()));
  return index;
}

// `surface` names the surface (surfaces[i]); the polygon's own names are made only for an
// error, since a large site has hundreds of thousands of polygons.
absl::Status AddPolygon(const v1::Polygon& polygon, const std::string& surface, uint32_t material,
                        Side side, uint32_t part, const Checker& check, TriangleMesh& mesh) {
  const auto field = [&] { return surface + ".polygon"; };
  const auto vertex = [&](size_t k) { return absl::StrCat(field(), ".vertices[", k, "]"); };
  if (polygon.vertices_size() < 3) {
    return check.Error(field(), "a polygon needs at least 3 vertices");
  }
  std::vector<Vec3d> v;
  v.reserve(polygon.vertices_size());
  for (int k = 0; k < polygon.vertices_size(); ++k) {
    const v1::Vec3& q = polygon.vertices(k);
    if (!Checker::Takes(q)) return check.Point(q, vertex(k)).status();
    v.push_back(Vec3d{q.x(), q.y(), q.z()});
  }
  // Newell's normal, planarity and convexity as every importer checks them
  const PolygonShape shape = ShapeOfPolygon(v);
  if (!shape.area) return check.Error(field(), "degenerate polygon (zero area)");
  if (!shape.planar) return check.Error(vertex(shape.off_plane), "polygon is not planar");
  // Convex: every corner turns the same way, once round (the fan of triangles covers it)
  if (!shape.convex) {
    return check.Error(vertex(shape.concave >= 0 ? shape.concave : 0),
                       "polygon is not convex (split it into convex polygons)");
  }
  for (size_t k = 1; k + 1 < v.size(); ++k) mesh.Add(v[0], v[k], v[k + 1], material, side, part);
  return absl::OkStatus();
}

absl::Status AddBox(const v1::Box& box, const std::string& field, uint32_t material, Side side,
                    uint32_t part, const Checker& check, Scene& scene) {
  FENESTRA_ASSIGN_OR_RETURN(lo, check.Point(box.min(), field + ".min"));
  FENESTRA_ASSIGN_OR_RETURN(hi, check.Point(box.max(), field + ".max"));
  if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z)) {
    return check.Error(field, "min must be below max in x, y and z");
  }
  auto corner = [&](int i) {
    return Vec3d{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
  };
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& f : kFaces) {
    scene.fixed.Add(corner(f[0]), corner(f[1]), corner(f[2]), material, side, part);
    scene.fixed.Add(corner(f[0]), corner(f[2]), corner(f[3]), material, side, part);
  }
  scene.solid_boxes.push_back({lo, hi, part});
  return absl::OkStatus();
}

absl::Status AddObj(const v1::ObjMesh& obj, const std::string& field, uint32_t default_material,
                    Side side, uint32_t part, const std::vector<Material>& materials,
                    const Checker& check, TriangleMesh& mesh, size_t& dropped) {
  if (obj.path().empty()) return check.Error(field + ".path", "must not be empty");
  const std::filesystem::path base = std::filesystem::path(check.path()).parent_path();
  const std::string file = (base / obj.path()).string();
  absl::StatusOr<ObjTriangles> triangles = ReadObj(file);
  if (!triangles.ok()) {
    return check.Error(field + ".path", std::string(triangles.status().message()));
  }
  std::unordered_map<std::string, uint32_t> group_material;
  for (const auto& [group, name] : obj.group_materials()) {
    FENESTRA_ASSIGN_OR_RETURN(
        index, FindMaterial(materials, name, absl::StrCat(field, ".group_materials['", group, "']"),
                            check));
    group_material[group] = index;
  }
  for (size_t t = 0; t < triangles->group.size(); ++t) {
    const Vec3d a = triangles->vertices[3 * t], b = triangles->vertices[3 * t + 1],
                c = triangles->vertices[3 * t + 2];
    for (const Vec3d& v : {a, b, c}) {
      FENESTRA_RETURN_IF_ERROR(check.Within(v, field + ".path: a vertex").status());
    }
    if (!(TriangleArea(a, b, c) > 0)) {
      ++dropped;
      continue;
    }
    auto it = group_material.find(triangles->group[t]);
    mesh.Add(a, b, c, it == group_material.end() ? default_material : it->second, side, part);
  }
  return absl::OkStatus();
}

// A window's name or a blind's group: empty, or at most 64 letters, digits, '_', '-', '.'.
absl::Status CheckWindowName(const std::string& name, const std::string& field,
                             const Checker& check) {
  constexpr size_t kLongest = 64;
  const bool taken =
      name.size() <= kLongest && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
      });
  if (taken) return absl::OkStatus();
  return check.Error(field, "must be at most 64 letters, digits, '_', '-' or '.'");
}

// The window `w`, `field` its place in the scene ("window", "windows[2]").
absl::StatusOr<Window> BuildWindow(const v1::Window& w, const std::string& field,
                                   const Checker& check) {
  Window window;
  FENESTRA_ASSIGN_OR_RETURN(center, check.Point(w.center(), field + ".center"));
  FENESTRA_ASSIGN_OR_RETURN(normal, check.Direction(w.outward_normal(), field + ".outward_normal"));
  FENESTRA_ASSIGN_OR_RETURN(up, check.Direction(w.up(), field + ".up"));
  if (std::abs(Dot(normal, up)) > kShapeTolerance) {
    return check.Error(field + ".up", "must be perpendicular to " + field + ".outward_normal");
  }
  for (const auto& [side, side_field] :
       {std::pair{w.width_m(), field + ".width_m"}, std::pair{w.height_m(), field + ".height_m"}}) {
    if (!(side >= kMinWindowSideM)) {
      return check.Error(side_field,
                         absl::StrCat("must be at least ", kMinWindowSideM, " m, got ", side));
    }
  }
  if (!(w.depth_m() >= 0 && w.depth_m() <= kMaxWindowDepthM)) {
    return check.Error(field + ".depth_m",
                       absl::StrCat("must be in [0, ", kMaxWindowDepthM,
                                    "] m (the wall's thickness), got ", w.depth_m()));
  }
  window.center = center;
  window.normal = normal;
  window.up = up;
  window.across = Normalize(Cross(up, normal));
  window.width_m = w.width_m();
  window.height_m = w.height_m();
  window.depth_m = w.depth_m();
  // Its corners, outer and inner face, within the scene's bounds
  for (const double a : {-0.5, 0.5}) {
    for (const double b : {-0.5, 0.5}) {
      for (const double d : {0.0, w.depth_m()}) {
        const Vec3d corner =
            center + (a * w.width_m()) * window.across + (b * w.height_m()) * up - d * normal;
        FENESTRA_RETURN_IF_ERROR(check.Within(corner, field + ": a corner").status());
      }
    }
  }
  return window;
}

// Appends the upward sensors at the cell centres of grid `i`.
absl::Status AddGridSensors(const v1::SensorGrid& g, int i, const Checker& check,
                            std::vector<Sensor>& sensors) {
  const std::string field = absl::StrCat("sensor_grids[", i, "]");
  FENESTRA_RETURN_IF_ERROR(check.Positive(g.spacing_m(), field + ".spacing_m"));
  for (double v : {g.z_m(), g.x_min_m(), g.x_max_m(), g.y_min_m(), g.y_max_m()}) {
    if (!std::isfinite(v)) return check.Error(field, "coordinates must be finite numbers");
    if (!(std::abs(v) <= kMaxCoordinateM)) {
      return check.Error(field, absl::StrCat("coordinate ", v, " lies beyond ", kMaxCoordinateM,
                                             " m, the scene's bound"));
    }
  }
  const double nx = std::floor((g.x_max_m() - g.x_min_m()) / g.spacing_m() + 1e-9);
  const double ny = std::floor((g.y_max_m() - g.y_min_m()) / g.spacing_m() + 1e-9);
  if (!(nx >= 1 && ny >= 1))
    return check.Error(field, "the grid holds no cell of the given spacing");
  if (!(nx * ny + static_cast<double>(sensors.size()) <= kMaxSceneSensors)) {
    return check.Error(field,
                       absl::StrCat("the grid holds ", nx * ny, " cells; a scene holds at most ",
                                    kMaxSceneSensors, " sensors"));
  }
  const std::string prefix = g.name().empty() ? absl::StrCat("grid", i) : g.name();
  for (long iy = 0; iy < static_cast<long>(ny); ++iy) {
    for (long ix = 0; ix < static_cast<long>(nx); ++ix) {
      sensors.push_back({absl::StrCat(prefix, "_", sensors.size()),
                         {g.x_min_m() + (ix + 0.5) * g.spacing_m(),
                          g.y_min_m() + (iy + 0.5) * g.spacing_m(), g.z_m()},
                         {0, 0, 1},
                         field});
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<std::vector<ViewPoint>> BuildViews(const v1::Scene& proto, const Checker& check) {
  if (proto.views_size() > kMaxSceneViews) {
    return check.Error("views", absl::StrCat("a scene holds at most ", kMaxSceneViews,
                                             " views, got ", proto.views_size()));
  }
  std::vector<ViewPoint> views;
  std::set<std::string> names;
  for (int i = 0; i < proto.views_size(); ++i) {
    const v1::ViewPoint& v = proto.views(i);
    const std::string field = absl::StrCat("views[", i, "]");
    FENESTRA_ASSIGN_OR_RETURN(position, check.Point(v.position(), field + ".position"));
    FENESTRA_ASSIGN_OR_RETURN(direction, check.Direction(v.direction(), field + ".direction"));
    Vec3d up{0, 0, 1};
    if (v.has_up()) {
      FENESTRA_ASSIGN_OR_RETURN(given, check.Direction(v.up(), field + ".up"));
      up = given;
    }
    if (Length(Cross(direction, up)) < 1e-3) {
      return check.Error(field + ".up", "must not lie along the view direction");
    }
    const std::string name = v.name().empty() ? absl::StrCat("v", i + 1) : v.name();
    if (!names.insert(name).second) {
      return check.Error(field + ".name", absl::StrCat("\"", name, "\" names another view too"));
    }
    views.push_back({name, position, direction, up, field});
  }
  return views;
}

absl::StatusOr<std::vector<Sensor>> BuildSensors(const v1::Scene& proto, const Checker& check) {
  std::vector<Sensor> sensors;
  if (proto.sensors_size() > kMaxSceneSensors) {
    return check.Error("sensors", absl::StrCat("a scene holds at most ", kMaxSceneSensors,
                                               " sensors, got ", proto.sensors_size()));
  }
  for (int i = 0; i < proto.sensors_size(); ++i) {
    const v1::Sensor& s = proto.sensors(i);
    const std::string field = absl::StrCat("sensors[", i, "]");
    FENESTRA_ASSIGN_OR_RETURN(position, check.Point(s.position(), field + ".position"));
    FENESTRA_ASSIGN_OR_RETURN(direction, check.Direction(s.direction(), field + ".direction"));
    sensors.push_back(
        {s.name().empty() ? absl::StrCat("s", i + 1) : s.name(), position, direction, field});
  }
  for (int i = 0; i < proto.sensor_grids_size(); ++i) {
    FENESTRA_RETURN_IF_ERROR(AddGridSensors(proto.sensor_grids(i), i, check, sensors));
  }
  if (sensors.empty()) return check.Error("sensors", "at least one sensor is required");
  return sensors;
}

absl::StatusOr<ParameterRange> BuildParameter(const v1::Parameter& p, const std::string& field,
                                              ParameterBounds bounds, const char* unit,
                                              const Checker& check) {
  for (double v : {p.value(), p.min(), p.max()}) {
    if (!std::isfinite(v)) return check.Error(field, "value, min and max must be finite");
  }
  ParameterRange range{p.value(), p.min(), p.max()};
  if (range.min == 0 && range.max == 0) range.min = range.max = range.value;  // fixed value
  if (range.min > range.max) return check.Error(field, "min must not exceed max");
  if (range.value < range.min || range.value > range.max) {
    return check.Error(field, absl::StrCat("value ", range.value, " is outside [", range.min, ", ",
                                           range.max, "]"));
  }
  constexpr double kRounding = 1e-12;  // π/2 written in decimal
  if (range.min < bounds.lowest - kRounding || range.max > bounds.highest + kRounding) {
    return check.Error(
        field, absl::StrCat("[", range.min, ", ", range.max, "] must stay within [", bounds.lowest,
                            ", ", bounds.highest, "] ", unit, ", the range of a real blind"));
  }
  return range;
}

absl::StatusOr<bool> IsVertical(const v1::VenetianBlind& b, const std::string& field,
                                const Checker& check) {
  switch (b.orientation()) {
    case v1::VenetianBlind::ORIENTATION_UNSPECIFIED:
    case v1::VenetianBlind::HORIZONTAL:
      return false;
    case v1::VenetianBlind::VERTICAL:
      return true;
    default:
      return check.Error(
          field + ".orientation",
          absl::StrCat("must be HORIZONTAL or VERTICAL, got ", static_cast<int>(b.orientation())));
  }
}

absl::Status CheckLength(double value, double highest, const std::string& field,
                         const Checker& check) {
  if (!(value >= 0 && value <= highest)) {
    return check.Error(field, absl::StrCat("must be in [0, ", highest, "] m, got ", value));
  }
  return absl::OkStatus();
}

absl::StatusOr<BlindSpec> BuildBlind(const v1::VenetianBlind& b,
                                     const std::vector<Material>& materials, const Window& window,
                                     const std::string& field, const Checker& check) {
  BlindSpec spec;
  FENESTRA_ASSIGN_OR_RETURN(material,
                            FindSlatMaterial(materials, b.material(), field + ".material", check));
  spec.material = material;
  if (b.has_outer_material()) {
    FENESTRA_ASSIGN_OR_RETURN(
        outer, FindSlatMaterial(materials, b.outer_material(), field + ".outer_material", check));
    spec.outer_material = outer;
  }
  FENESTRA_ASSIGN_OR_RETURN(vertical, IsVertical(b, field, check));
  spec.vertical = vertical;
  FENESTRA_ASSIGN_OR_RETURN(
      tilt, BuildParameter(b.tilt_rad(), field + ".tilt_rad", kTiltBoundsRad, "rad", check));
  FENESTRA_ASSIGN_OR_RETURN(width, BuildParameter(b.slat_width_m(), field + ".slat_width_m",
                                                  kSlatWidthBoundsM, "m", check));
  FENESTRA_ASSIGN_OR_RETURN(spacing, BuildParameter(b.slat_spacing_m(), field + ".slat_spacing_m",
                                                    kSlatSpacingBoundsM, "m", check));
  FENESTRA_ASSIGN_OR_RETURN(thickness,
                            BuildParameter(b.slat_thickness_m(), field + ".slat_thickness_m",
                                           kSlatThicknessBoundsM, "m", check));
  spec.tilt_rad = tilt;
  spec.slat_width_m = width;
  spec.slat_spacing_m = spacing;
  spec.slat_thickness_m = thickness;
  if (b.has_wall_gap_m()) {
    FENESTRA_RETURN_IF_ERROR(
        CheckLength(b.wall_gap_m(), kMaxWallGapM, field + ".wall_gap_m", check));
    spec.wall_gap_m = b.wall_gap_m();
  }
  FENESTRA_RETURN_IF_ERROR(
      CheckLength(b.side_margin_m(), kMaxSideMarginM, field + ".side_margin_m", check));
  spec.side_margin_m = b.side_margin_m();
  if (!v1::VenetianBlind::Operation_IsValid(b.operation())) {
    return check.Error(field + ".operation",
                       absl::StrCat("unknown operation ", static_cast<int>(b.operation()),
                                    " (STATIC or AUTOMATED_SUN)"));
  }
  spec.automated_sun = b.operation() == v1::VenetianBlind::AUTOMATED_SUN;
  FENESTRA_RETURN_IF_ERROR(CheckWindowName(b.group(), field + ".group", check));
  spec.group = b.group();
  if (absl::Status fits = CheckBlindFits(spec, window); !fits.ok()) {
    return check.Error(field, std::string(fits.message()));
  }
  return spec;
}

absl::StatusOr<Site> BuildSite(const v1::Scene& proto, const Checker& check) {
  Site site;
  if (!proto.has_site()) return site;
  const v1::Site& s = proto.site();
  if (!(s.latitude_deg() >= -90 && s.latitude_deg() <= 90)) {
    return check.Error("site.latitude_deg",
                       absl::StrCat("must be in [-90, 90], got ", s.latitude_deg()));
  }
  if (!(s.longitude_deg() >= -180 && s.longitude_deg() <= 180)) {
    return check.Error("site.longitude_deg",
                       absl::StrCat("must be in [-180, 180], got ", s.longitude_deg()));
  }
  if (!(s.time_zone_h() >= -12 && s.time_zone_h() <= 14)) {
    return check.Error("site.time_zone_h",
                       absl::StrCat("must be in [-12, 14], got ", s.time_zone_h()));
  }
  site.latitude_deg = s.latitude_deg();
  site.longitude_deg = s.longitude_deg();
  site.time_zone_h = s.time_zone_h();
  if (!s.weather_file().empty()) {
    const std::filesystem::path base = std::filesystem::path(check.path()).parent_path();
    site.weather_file = (base / s.weather_file()).lexically_normal().string();
  }
  if (s.has_ground_reflectance()) {
    if (!(s.ground_reflectance() >= 0 && s.ground_reflectance() < 1)) {
      return check.Error("site.ground_reflectance", "must be in [0, 1)");
    }
    site.ground_reflectance = s.ground_reflectance();
  }
  return site;
}

absl::StatusOr<Side> SideOf(const v1::Surface& s, const std::string& field, const Checker& check) {
  switch (s.side()) {
    case v1::SIDE_INDOOR:
      return Side::kIndoor;
    case v1::SIDE_OUTDOOR:
      return Side::kOutdoor;
    default:
      return check.Error(field, absl::StrCat("must be SIDE_INDOOR or SIDE_OUTDOOR, got ",
                                             static_cast<int>(s.side())));
  }
}

// Triangulates every surface into scene.fixed; boxes are also kept as solids.
absl::Status BuildSurfaces(const v1::Scene& proto, const Checker& check, Scene& scene) {
  for (int i = 0; i < proto.surfaces_size(); ++i) {
    const v1::Surface& s = proto.surfaces(i);
    const std::string field = absl::StrCat("surfaces[", i, "]");
    FENESTRA_ASSIGN_OR_RETURN(
        material, FindMaterial(scene.materials, s.material(), field + ".material", check));
    FENESTRA_ASSIGN_OR_RETURN(side, SideOf(s, field + ".side", check));
    const uint32_t part = static_cast<uint32_t>(scene.fixed.part_names.size());
    scene.fixed.part_names.push_back(s.name().empty() ? field : s.name());
    absl::Status status;
    switch (s.shape_case()) {
      case v1::Surface::kPolygon:
        status = AddPolygon(s.polygon(), field, material, side, part, check, scene.fixed);
        break;
      case v1::Surface::kBox:
        status = AddBox(s.box(), field + ".box", material, side, part, check, scene);
        break;
      case v1::Surface::kObj:
        status = AddObj(s.obj(), field + ".obj", material, side, part, scene.materials, check,
                        scene.fixed, scene.dropped_degenerate);
        break;
      default:
        status = check.Error(field, "needs one of polygon, box or obj");
    }
    FENESTRA_RETURN_IF_ERROR(status);
  }
  return absl::OkStatus();
}

// A blind in the list after the first must share the first's group and ranges: the scene
// has one design so far (DefaultDesign).
absl::Status CheckSharedBlind(const BlindSpec& first, const BlindSpec& blind,
                              const std::string& field, const Checker& check) {
  if (first.group.empty() || blind.group != first.group) {
    return absl::UnimplementedError(absl::StrCat(
        check.path(), ": ", field,
        ".group: blinds share one design so far: give every blind the same non-empty group"));
  }
  const auto same = [](const ParameterRange& a, const ParameterRange& b) {
    return a.value == b.value && a.min == b.min && a.max == b.max;
  };
  if (!same(first.tilt_rad, blind.tilt_rad) || !same(first.slat_width_m, blind.slat_width_m) ||
      !same(first.slat_spacing_m, blind.slat_spacing_m) ||
      !same(first.slat_thickness_m, blind.slat_thickness_m)) {
    return check.Error(field, absl::StrCat("blinds of group '", blind.group,
                                           "' share their design: give them the same tilt_rad, "
                                           "slat_width_m, slat_spacing_m and slat_thickness_m"));
  }
  return absl::OkStatus();
}

// Appends windows[i] (`field`) of the list form with its blind.
absl::Status AddListedWindow(const v1::Window& w, int i, const Checker& check, Scene& scene) {
  const std::string field = absl::StrCat("windows[", i, "]");
  FENESTRA_RETURN_IF_ERROR(CheckWindowName(w.name(), field + ".name", check));
  SceneWindow added;
  added.name = w.name().empty() ? absl::StrCat("window_", i) : w.name();
  for (const SceneWindow& other : scene.windows) {
    if (other.name == added.name) {
      return check.Error(field + ".name", absl::StrCat("duplicate window '", added.name, "'"));
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(window, BuildWindow(w, field, check));
  added.window = window;
  if (w.has_blind()) {
    FENESTRA_ASSIGN_OR_RETURN(
        blind, BuildBlind(w.blind(), scene.materials, added.window, field + ".blind", check));
    for (const SceneWindow& other : scene.windows) {
      if (other.blind) {
        FENESTRA_RETURN_IF_ERROR(CheckSharedBlind(*other.blind, blind, field + ".blind", check));
        break;
      }
    }
    added.blind = blind;
  }
  scene.windows.push_back(std::move(added));
  return absl::OkStatus();
}

// The scene's windows and their blinds, from the one-window form (`window`, `blind`) or from
// `windows`.
absl::Status BuildWindows(const v1::Scene& proto, const Checker& check, Scene& scene) {
  scene.windows.clear();
  if (proto.has_window() && proto.windows_size() > 0) {
    return check.Error("windows", "a scene gives either window (with blind) or windows");
  }
  if (proto.has_window()) {
    SceneWindow only;
    only.name = kOneWindowName;
    FENESTRA_ASSIGN_OR_RETURN(window, BuildWindow(proto.window(), "window", check));
    only.window = window;
    if (proto.has_blind()) {
      FENESTRA_ASSIGN_OR_RETURN(
          blind, BuildBlind(proto.blind(), scene.materials, only.window, "blind", check));
      only.blind = blind;
    }
    scene.windows.push_back(std::move(only));
    return absl::OkStatus();
  }
  if (proto.windows_size() == 0) return check.Error("window", "is required (or windows)");
  if (proto.has_blind()) {
    return check.Error("blind", "belongs to window; with windows each window has its blind");
  }
  if (proto.windows_size() > kMaxSceneWindows) {
    return check.Error("windows", absl::StrCat("at most ", kMaxSceneWindows, " windows, got ",
                                               proto.windows_size()));
  }
  for (int i = 0; i < proto.windows_size(); ++i) {
    FENESTRA_RETURN_IF_ERROR(AddListedWindow(proto.windows(i), i, check, scene));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<v1::Scene> ReadSceneProto(const std::string& path) {
  v1::Scene scene;
  FENESTRA_RETURN_IF_ERROR(ReadJsonProtoFile(path, "scene", &scene));
  return scene;
}

absl::StatusOr<Scene> BuildScene(const v1::Scene& proto, const std::string& path) {
  const Checker check(path);
  FENESTRA_RETURN_IF_ERROR(CheckMessageText(proto, path + ": "));
  Scene scene;
  scene.name = proto.name();
  scene.source_path = path;
  FENESTRA_ASSIGN_OR_RETURN(materials, BuildMaterials(proto, check));
  scene.materials = std::move(materials);
  FENESTRA_RETURN_IF_ERROR(BuildSurfaces(proto, check, scene));
  FENESTRA_RETURN_IF_ERROR(BuildWindows(proto, check, scene));
  FENESTRA_ASSIGN_OR_RETURN(sensors, BuildSensors(proto, check));
  scene.sensors = std::move(sensors);
  FENESTRA_ASSIGN_OR_RETURN(views, BuildViews(proto, check));
  scene.views = std::move(views);
  FENESTRA_ASSIGN_OR_RETURN(site, BuildSite(proto, check));
  scene.site = site;
  return scene;
}

absl::StatusOr<Scene> LoadScene(const std::string& path) {
  FENESTRA_ASSIGN_OR_RETURN(proto, ReadSceneProto(path));
  return BuildScene(proto, path);
}

TriangleMesh AssembleMesh(const Scene& scene, const BlindDesign& design) {
  TriangleMesh mesh = scene.fixed;
  if (!design.has_blind) return mesh;
  for (const SceneWindow& w : scene.windows) {
    if (!w.blind) continue;
    const uint32_t part = static_cast<uint32_t>(mesh.part_names.size());
    // One window: its blind is "blind", as the one-window form always named it
    mesh.part_names.push_back(scene.windows.size() == 1 ? "blind" : "blind " + w.name);
    GenerateBlind(w.window, *w.blind, design, part, mesh);
  }
  return mesh;
}

bool IsDegenerateTriangle(Vec3d a, Vec3d b, Vec3d c) {
  const double edge = std::max({Length(b - a), Length(c - b), Length(a - c)});
  return !(TriangleArea(a, b, c) > kShapeTolerance * edge * edge);
}

BlindDesign DefaultDesign(const Scene& scene) {
  BlindDesign design;
  if (!scene.blind()) return design;
  design.has_blind = true;
  design.tilt_rad = scene.blind()->tilt_rad.value;
  design.slat_width_m = scene.blind()->slat_width_m.value;
  design.slat_spacing_m = scene.blind()->slat_spacing_m.value;
  design.slat_thickness_m = scene.blind()->slat_thickness_m.value;
  return design;
}

absl::StatusOr<BlindDesign> DesignWithOverrides(const Scene& scene,
                                                const std::map<std::string, double>& values) {
  BlindDesign design = DefaultDesign(scene);
  if (values.empty()) return design;
  if (!scene.blind()) {
    return absl::InvalidArgumentError(
        absl::StrCat(scene.source_path, ": design values given but the scene has no blind"));
  }
  struct Variable {
    const char* name;
    const ParameterRange* range;
    double* value;
  };
  const Variable variables[] = {
      {"alpha", &scene.blind()->tilt_rad, &design.tilt_rad},
      {"width", &scene.blind()->slat_width_m, &design.slat_width_m},
      {"spacing", &scene.blind()->slat_spacing_m, &design.slat_spacing_m},
      {"thickness", &scene.blind()->slat_thickness_m, &design.slat_thickness_m},
  };
  for (const auto& [name, value] : values) {
    const Variable* match = nullptr;
    for (const Variable& v : variables) {
      if (name == v.name) match = &v;
    }
    if (!match) {
      return absl::InvalidArgumentError(absl::StrCat(
          "unknown design variable '", name, "' (known: alpha, width, spacing, thickness)"));
    }
    if (!std::isfinite(value) || value < match->range->min || value > match->range->max) {
      return absl::OutOfRangeError(absl::StrCat("design variable ", name, " = ", value,
                                                " is outside its range [", match->range->min, ", ",
                                                match->range->max, "] in ", scene.source_path));
    }
    *match->value = value;
  }
  return design;
}

absl::StatusOr<uint32_t> SlatMaterialIndex(const std::vector<Material>& materials,
                                           const std::string& name) {
  for (uint32_t i = 0; i < materials.size(); ++i) {
    if (materials[i].name != name) continue;
    if (materials[i].kind == MaterialKind::kGlass) {
      return absl::InvalidArgumentError(absl::StrCat(
          "'", name, "' is a glass: slats of glass make no blind (trans makes translucent slats)"));
    }
    return i;
  }
  return absl::InvalidArgumentError(absl::StrCat("unknown material '", name, "'"));
}

}  // namespace fenestra
