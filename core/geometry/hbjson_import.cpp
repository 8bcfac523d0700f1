#include "core/geometry/hbjson_import.h"

#include <cmath>
#include <numbers>
#include <optional>
#include <set>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/status_macros.h"
#include "core/common/text.h"
#include "core/geometry/hbjson_json.h"
#include "core/geometry/hbjson_materials.h"
#include "core/geometry/hbjson_shapes.h"
#include "core/geometry/polygon_triangulate.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

using hbjson::Assigned;
using hbjson::Json;
using hbjson::Modifiers;
using hbjson::Shape;
using hbjson::Slot;
using hbjson::SurfaceWriter;
using hbjson::Tolerances;

struct Unit {
  const char* name;
  double metres;
};
constexpr Unit kUnits[] = {{"Meters", 1},
                           {"Millimeters", 0.001},
                           {"Centimeters", 0.01},
                           {"Feet", 0.3048},
                           {"Inches", 0.0254}};
// The largest tolerance taken [m]: beyond it a model's checks would pass anything.
constexpr double kMaxToleranceM = 0.1;
// The smallest tolerances used, where a model gives 0 ("no checks"): lengths [m], angles [deg].
constexpr double kMinToleranceM = 1e-6;
constexpr double kMinAngleToleranceDeg = 1e-3;
constexpr double kMaxAngleToleranceDeg = 30;
// At most this many names are listed in a message.
constexpr size_t kNamesListed = 20;

// "'a', 'b', ... (N in all)"
std::string Listed(const std::vector<std::string>& names) {
  std::vector<std::string> quoted;
  for (size_t i = 0; i < names.size() && i < kNamesListed; ++i) {
    quoted.push_back(absl::StrCat("'", names[i], "'"));
  }
  std::string text = absl::StrJoin(quoted, ", ");
  if (names.size() > kNamesListed) absl::StrAppend(&text, ", ... (", names.size(), " in all)");
  return text;
}

struct Box {
  Vec3d lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  void Add(Vec3d p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  bool Holds(Vec3d p, double margin) const {
    for (int i = 0; i < 3; ++i) {
      if (!(p[i] >= lo[i] - margin && p[i] <= hi[i] + margin)) return false;
    }
    return true;
  }
  Vec3d Centre() const { return 0.5 * (lo + hi); }
};

// A sensor grid of the model.
struct Grid {
  std::string identifier;
  std::string room;                              // its room_identifier, or empty
  std::vector<std::pair<Vec3d, Vec3d>> sensors;  // position [m], direction
};

// A face's type and boundary condition, and the room a Surface condition names.
struct FaceKind {
  std::string type, boundary, adjacent_room;
};

absl::StatusOr<std::string> BoundaryType(const Json& element) {
  FENESTRA_ASSIGN_OR_RETURN(condition, element.Get("boundary_condition"));
  FENESTRA_ASSIGN_OR_RETURN(type, condition.Get("type"));
  return type.String();
}

absl::StatusOr<FaceKind> ReadFaceKind(const Json& face) {
  FaceKind kind;
  FENESTRA_ASSIGN_OR_RETURN(type, face.Get("face_type"));
  FENESTRA_ASSIGN_OR_RETURN(type_name, type.String());
  kind.type = type_name;
  if (kind.type != "Wall" && kind.type != "Floor" && kind.type != "RoofCeiling" &&
      kind.type != "AirBoundary") {
    return type.Error("must be Wall, Floor, RoofCeiling or AirBoundary, got " +
                      QuoteText(kind.type));
  }
  FENESTRA_ASSIGN_OR_RETURN(boundary, BoundaryType(face));
  kind.boundary = boundary;
  if (kind.boundary == "Surface") {
    FENESTRA_ASSIGN_OR_RETURN(condition, face.Get("boundary_condition"));
    FENESTRA_ASSIGN_OR_RETURN(objects,
                              condition.ListOf("boundary_condition_objects", 3, "objects"));
    if (!objects.empty()) {
      FENESTRA_ASSIGN_OR_RETURN(room, objects.back().String());
      kind.adjacent_room = room;
    }
  } else if (kind.boundary != "Outdoors" && kind.boundary != "Ground" &&
             kind.boundary != "Adiabatic" && kind.boundary != "OtherSideTemperature") {
    FENESTRA_ASSIGN_OR_RETURN(condition, face.Get("boundary_condition"));
    return condition.Error(
        "type must be Outdoors, Ground, Adiabatic, Surface or "
        "OtherSideTemperature, got " +
        QuoteText(kind.boundary));
  }
  return kind;
}

Slot FaceSlot(const FaceKind& kind) {
  const bool out = kind.boundary == "Outdoors";
  if (kind.type == "Wall") return out ? Slot::kWallExterior : Slot::kWallInterior;
  if (kind.type == "Floor") return out ? Slot::kFloorExterior : Slot::kFloorInterior;
  return out ? Slot::kRoofCeilingExterior : Slot::kRoofCeilingInterior;
}

class Importer {
 public:
  Importer(const Json& model, const HoneybeeImportOptions& options)
      : model_(model), options_(options), writer_(scene_) {}

  absl::StatusOr<v1::Scene> Run(HoneybeeImportSummary& summary);

 private:
  absl::Status ReadUnits();
  absl::Status ReadGrids(const std::optional<Json>& radiance);
  absl::StatusOr<Box> RoomBox(const Json& room) const;
  std::optional<size_t> RoomOfGrid(const Grid& grid) const;
  absl::StatusOr<size_t> ChooseRoom(const std::vector<Json>& rooms) const;
  absl::StatusOr<std::vector<const Grid*>> ChooseGrids(size_t room) const;
  absl::Status AddRoom(const Json& room, bool chosen);
  absl::Status AddFace(const Json& face, int set, bool chosen);
  absl::StatusOr<std::vector<Vec3d>> AddOpening(const Json& opening, bool door, const Shape& face,
                                                const FaceKind& kind, int set, bool chosen);
  absl::Status AddShades(const Json& parent, int set, bool chosen);
  absl::Status AddShade(const Json& shade, int set, bool indoor, bool orphan, v1::Side side);
  absl::Status AddShadeMesh(const Json& mesh);
  absl::Status AddOrphans();
  absl::StatusOr<Assigned> Material(const Json& element, int set, Slot slot) {
    FENESTRA_ASSIGN_OR_RETURN(assigned, modifiers_.For(element, set, slot));
    if (assigned.is_void()) ++summary_.void_elements;
    return assigned;
  }

  const Json& model_;
  const HoneybeeImportOptions& options_;
  double scale_ = 1;
  Tolerances tolerances_;
  Modifiers modifiers_;
  std::vector<Grid> grids_;
  std::vector<std::string> room_ids_;
  std::vector<Box> room_boxes_;
  std::string room_id_;     // the room simulated
  double room_volume_ = 0;  // its faces' enclosed volume about room_centre_ [m^3]
  Vec3d room_centre_{0, 0, 0};
  v1::Scene scene_;
  SurfaceWriter writer_;
  std::set<std::string> window_names_;
  HoneybeeImportSummary summary_;
};

absl::Status Importer::ReadUnits() {
  FENESTRA_ASSIGN_OR_RETURN(type, model_.StringOr("type", "Model"));
  if (type != "Model") return model_.Error("type is " + QuoteText(type) + ", not a Honeybee Model");
  FENESTRA_ASSIGN_OR_RETURN(units, model_.StringOr("units", "Meters"));
  const Unit* unit = nullptr;
  for (const Unit& u : kUnits) {
    if (units == u.name) unit = &u;
  }
  if (unit == nullptr) {
    FENESTRA_ASSIGN_OR_RETURN(field, model_.Get("units"));
    return field.Error("must be Meters, Millimeters, Centimeters, Feet or Inches, got " +
                       QuoteText(units) + "'");
  }
  scale_ = unit->metres;
  FENESTRA_ASSIGN_OR_RETURN(tolerance, model_.NumberOr("tolerance", 0.01));
  if (!(tolerance >= 0 && tolerance * scale_ <= kMaxToleranceM)) {
    FENESTRA_ASSIGN_OR_RETURN(field, model_.Get("tolerance"));
    return field.Error(absl::StrCat("must be at least 0 and at most ", kMaxToleranceM,
                                    " m in the model's units, got ", tolerance));
  }
  tolerances_.length = std::max(tolerance * scale_, kMinToleranceM);
  FENESTRA_ASSIGN_OR_RETURN(angle, model_.NumberOr("angle_tolerance", 1.0));
  if (!(angle >= 0 && angle <= kMaxAngleToleranceDeg)) {
    FENESTRA_ASSIGN_OR_RETURN(field, model_.Get("angle_tolerance"));
    return field.Error(
        absl::StrCat("must be in [0, ", kMaxAngleToleranceDeg, "] degrees, got ", angle));
  }
  tolerances_.angle = std::max(angle, kMinAngleToleranceDeg) * std::numbers::pi / 180;
  return absl::OkStatus();
}

absl::Status Importer::ReadGrids(const std::optional<Json>& radiance) {
  if (!radiance) return absl::OkStatus();
  FENESTRA_ASSIGN_OR_RETURN(grids, radiance->ListOf("sensor_grids", kMaxHoneybeeGrids, "grids"));
  size_t total = 0;
  for (const Json& g : grids) {
    Grid grid;
    FENESTRA_ASSIGN_OR_RETURN(identifier, g.Get("identifier"));
    FENESTRA_ASSIGN_OR_RETURN(id, hbjson::Identifier(identifier));
    grid.identifier = id;
    FENESTRA_ASSIGN_OR_RETURN(room, g.Find("room_identifier"));
    if (room) {
      FENESTRA_ASSIGN_OR_RETURN(room_id, hbjson::Identifier(*room));
      grid.room = room_id;
    }
    FENESTRA_ASSIGN_OR_RETURN(sensors, g.Get("sensors"));
    const size_t left = static_cast<size_t>(kMaxSceneSensors) - total;
    FENESTRA_ASSIGN_OR_RETURN(list, sensors.List(left, "sensors (the model's grids together)"));
    total += list.size();
    for (const Json& s : list) {
      FENESTRA_ASSIGN_OR_RETURN(pos, s.Get("pos"));
      FENESTRA_ASSIGN_OR_RETURN(position, pos.Point(scale_));
      if (!(std::abs(position.x) <= kMaxCoordinateM && std::abs(position.y) <= kMaxCoordinateM &&
            std::abs(position.z) <= kMaxCoordinateM)) {
        return pos.Error(
            absl::StrCat("lies beyond ", kMaxCoordinateM, " m from the origin, the scene's bound"));
      }
      FENESTRA_ASSIGN_OR_RETURN(dir, s.Get("dir"));
      FENESTRA_ASSIGN_OR_RETURN(direction, dir.Point(1.0));
      const double longest =
          std::max({std::abs(direction.x), std::abs(direction.y), std::abs(direction.z)});
      if (!(longest > 0)) return dir.Error("must not be zero");
      grid.sensors.push_back({position, Normalize(direction / longest)});
    }
    grids_.push_back(std::move(grid));
  }
  return absl::OkStatus();
}

absl::StatusOr<Box> Importer::RoomBox(const Json& room) const {
  Box box;
  FENESTRA_ASSIGN_OR_RETURN(faces, room.ListOf("faces", kMaxHoneybeeElements, "faces"));
  for (const Json& face : faces) {
    FENESTRA_ASSIGN_OR_RETURN(geometry, face.Get("geometry"));
    FENESTRA_ASSIGN_OR_RETURN(boundary, geometry.Get("boundary"));
    FENESTRA_ASSIGN_OR_RETURN(points, boundary.Points(scale_, kMaxTriangulatedVertices));
    for (const Vec3d& p : points) box.Add(p);
  }
  return box;
}

std::optional<size_t> Importer::RoomOfGrid(const Grid& grid) const {
  for (size_t r = 0; r < room_ids_.size(); ++r) {
    if (!grid.room.empty() && grid.room == room_ids_[r]) return r;
  }
  std::optional<size_t> found;
  for (size_t r = 0; r < room_boxes_.size(); ++r) {
    bool holds = !grid.sensors.empty();
    for (const auto& [position, direction] : grid.sensors) {
      holds = holds && room_boxes_[r].Holds(position, tolerances_.length);
    }
    if (!holds) continue;
    if (found) return std::nullopt;  // in more than one room's box
    found = r;
  }
  return found;
}

absl::StatusOr<size_t> Importer::ChooseRoom(const std::vector<Json>& rooms) const {
  if (!options_.room.empty()) {
    for (size_t r = 0; r < room_ids_.size(); ++r) {
      if (room_ids_[r] == options_.room) return r;
    }
    return model_.Error(absl::StrCat("no room ", QuoteText(options_.room),
                                     "; the model's rooms are ",
                                     room_ids_.empty() ? "none" : Listed(room_ids_)));
  }
  if (rooms.empty()) return model_.Error("the model has no room");
  if (rooms.size() == 1) return 0;
  std::vector<const Grid*> candidates;
  for (const Grid& grid : grids_) {
    if (options_.sensor_grid.empty() || grid.identifier == options_.sensor_grid) {
      candidates.push_back(&grid);
    }
  }
  std::string reason = grids_.empty() ? "the model has no sensor grid"
                                      : "no sensor grid " + QuoteText(options_.sensor_grid);
  std::set<size_t> found;
  for (const Grid* grid : candidates) {
    const std::optional<size_t> room = RoomOfGrid(*grid);
    if (!room) {
      reason = "sensor grid '" + grid->identifier +
               "' names no room of the model and lies in no single room's bounding box";
      found.clear();
      break;
    }
    found.insert(*room);
    reason = absl::StrCat("the sensor grids lie in ", found.size(), " rooms");
  }
  if (found.size() == 1) return *found.begin();
  return model_.Error(absl::StrCat("cannot tell which of its ", rooms.size(),
                                   " rooms to simulate: ", reason, "; choose one of ",
                                   Listed(room_ids_)));
}

absl::StatusOr<std::vector<const Grid*>> Importer::ChooseGrids(size_t room) const {
  if (grids_.empty()) {
    return model_.Error("the model has no sensor grid (properties.radiance.sensor_grids)");
  }
  std::vector<const Grid*> chosen;
  std::vector<std::string> ids;
  for (const Grid& grid : grids_) {
    ids.push_back(grid.identifier);
    const bool taken = options_.sensor_grid.empty() ? RoomOfGrid(grid) == room
                                                    : grid.identifier == options_.sensor_grid;
    if (taken) chosen.push_back(&grid);
  }
  if (chosen.empty()) {
    return model_.Error(
        options_.sensor_grid.empty()
            ? absl::StrCat("no sensor grid lies in room '", room_ids_[room],
                           "' (names it as its room_identifier or lies in its bounding box); "
                           "the model's grids are ",
                           Listed(ids))
            : absl::StrCat("no sensor grid ", QuoteText(options_.sensor_grid),
                           "; the model's grids are ", Listed(ids)));
  }
  size_t sensors = 0;
  for (const Grid* grid : chosen) sensors += grid->sensors.size();
  if (sensors == 0) {
    return model_.Error(absl::StrCat("the sensor grid '", chosen[0]->identifier,
                                     "' has no sensor (a scene needs one)"));
  }
  std::set<std::string> seen;
  for (const Grid* grid : chosen) {
    if (!seen.insert(grid->identifier).second) {
      return model_.Error(absl::StrCat(
          "more than one of the sensor grids taken is named '", grid->identifier,
          "': their sensors' names would clash; choose another grid by its identifier"));
    }
  }
  return chosen;
}

absl::Status Importer::AddRoom(const Json& room, bool chosen) {
  FENESTRA_ASSIGN_OR_RETURN(set, modifiers_.RoomSet(room));
  FENESTRA_ASSIGN_OR_RETURN(faces, room.ListOf("faces", kMaxHoneybeeElements, "faces"));
  for (const Json& face : faces) FENESTRA_RETURN_IF_ERROR(AddFace(face, set, chosen));
  return AddShades(room, set, chosen);
}

absl::Status Importer::AddFace(const Json& face, int set, bool chosen) {
  FENESTRA_ASSIGN_OR_RETURN(identifier, face.Get("identifier"));
  FENESTRA_ASSIGN_OR_RETURN(id, hbjson::Identifier(identifier));
  FENESTRA_ASSIGN_OR_RETURN(kind, ReadFaceKind(face));
  if (kind.type == "AirBoundary" && chosen) {
    return face.Error(
        "an AirBoundary face (an opening into another room) is not supported: "
        "Fenestra simulates one room closed by its faces and windows");
  }
  if (!chosen && (kind.type == "AirBoundary" ||
                  (kind.boundary == "Surface" && kind.adjacent_room == room_id_))) {
    ++summary_.hidden_faces;  // air, or the room's own face seen from the other side
    return absl::OkStatus();
  }
  FENESTRA_ASSIGN_OR_RETURN(geometry, face.Get("geometry"));
  FENESTRA_ASSIGN_OR_RETURN(shape, ReadShape(geometry, scale_, tolerances_));
  std::vector<std::vector<Vec3d>> holes = shape.holes;
  std::vector<std::string> legend;  // which hole is which, for errors
  for (size_t h = 0; h < shape.holes.size(); ++h) legend.push_back("geometry.holes");
  for (const bool door : {false, true}) {
    const char* key = door ? "doors" : "apertures";
    FENESTRA_ASSIGN_OR_RETURN(openings, face.ListOf(key, kMaxHoneybeeElements, key));
    for (size_t i = 0; i < openings.size(); ++i) {
      FENESTRA_ASSIGN_OR_RETURN(outline, AddOpening(openings[i], door, shape, kind, set, chosen));
      holes.push_back(std::move(outline));
      legend.push_back(absl::StrCat(key, "[", i, "]"));
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(material, Material(face, set, FaceSlot(kind)));
  const v1::Side side = chosen ? v1::SIDE_INDOOR : v1::SIDE_OUTDOOR;
  if (!material.is_void()) {
    absl::Status added =
        writer_.Add(id, material.material, side, shape.outline, holes, shape.normal, geometry);
    if (!added.ok() && !legend.empty()) {
      std::vector<std::string> named;
      for (size_t h = 0; h < legend.size(); ++h) named.push_back(absl::StrCat(h, ": ", legend[h]));
      return absl::InvalidArgumentError(
          absl::StrCat(added.message(), " (its holes: ", absl::StrJoin(named, ", "), ")"));
    }
    FENESTRA_RETURN_IF_ERROR(added);
  }
  if (chosen) {
    ++summary_.faces;
    // The face's share of the volume its room's faces enclose about the room's centre
    double area = 0.5 * Length(hbjson::NewellNormal(shape.outline));
    for (const auto& hole : shape.holes) area -= 0.5 * Length(hbjson::NewellNormal(hole));
    room_volume_ += area * Dot(shape.origin - room_centre_, shape.normal) / 3;
  } else {
    ++summary_.context_faces;
  }
  FENESTRA_RETURN_IF_ERROR(AddShades(face, set, chosen));
  return absl::OkStatus();
}

absl::StatusOr<std::vector<Vec3d>> Importer::AddOpening(const Json& opening, bool door,
                                                        const Shape& face, const FaceKind& kind,
                                                        int set, bool chosen) {
  FENESTRA_ASSIGN_OR_RETURN(identifier, opening.Get("identifier"));
  FENESTRA_ASSIGN_OR_RETURN(id, hbjson::Identifier(identifier));
  FENESTRA_ASSIGN_OR_RETURN(boundary, BoundaryType(opening));
  if (boundary != "Outdoors" && boundary != "Surface") {
    FENESTRA_ASSIGN_OR_RETURN(condition, opening.Get("boundary_condition"));
    return condition.Error("type must be Outdoors or Surface, got " + QuoteText(boundary));
  }
  const bool outdoors = boundary == "Outdoors";
  Slot slot;
  if (door) {
    FENESTRA_ASSIGN_OR_RETURN(glass, opening.BoolOr("is_glass", false));
    slot = outdoors ? (glass ? Slot::kDoorExteriorGlass
                             : (kind.type == "Wall" ? Slot::kDoorExterior : Slot::kDoorOverhead))
                    : (glass ? Slot::kDoorInteriorGlass : Slot::kDoorInterior);
  } else {
    FENESTRA_ASSIGN_OR_RETURN(operable, opening.BoolOr("is_operable", false));
    slot = outdoors ? (operable ? Slot::kOperableWindow
                                : (kind.type == "Wall" ? Slot::kWindow : Slot::kSkylight))
                    : Slot::kInteriorAperture;
  }
  FENESTRA_ASSIGN_OR_RETURN(geometry, opening.Get("geometry"));
  FENESTRA_ASSIGN_OR_RETURN(shape, ReadShape(geometry, scale_, tolerances_));
  FENESTRA_ASSIGN_OR_RETURN(outline, hbjson::OntoPlane(face, shape.outline, tolerances_, geometry));
  FENESTRA_ASSIGN_OR_RETURN(material, Material(opening, set, slot));
  const bool window =
      chosen && kind.boundary == "Outdoors" && outdoors && (!door || material.is_glass);
  if (chosen) ++(door ? summary_.doors : summary_.apertures);
  if (window) {
    if (!shape.holes.empty()) {
      return geometry.Error(
          "a window must be a rectangle (4 vertices, right angles); this one "
          "has holes");
    }
    FENESTRA_ASSIGN_OR_RETURN(rectangle,
                              hbjson::RectangleWindow(outline, face, tolerances_, geometry));
    rectangle.set_name(hbjson::WindowName(id, window_names_));
    *scene_.add_windows() = rectangle;
    ++summary_.windows;
    if (!material.is_void()) {
      FENESTRA_RETURN_IF_ERROR(writer_.Add(id + "#pane", material.material, v1::SIDE_INDOOR,
                                           hbjson::WindowCorners(rectangle, kGlazingInsetM), {},
                                           face.normal, geometry));
    }
  } else if (!material.is_void()) {
    std::vector<std::vector<Vec3d>> holes;
    for (const auto& hole : shape.holes) {
      FENESTRA_ASSIGN_OR_RETURN(flat, hbjson::OntoPlane(face, hole, tolerances_, geometry));
      holes.push_back(std::move(flat));
    }
    FENESTRA_RETURN_IF_ERROR(writer_.Add(id, material.material,
                                         chosen ? v1::SIDE_INDOOR : v1::SIDE_OUTDOOR, outline,
                                         holes, face.normal, geometry));
  }
  FENESTRA_RETURN_IF_ERROR(AddShades(opening, set, chosen));
  return outline;
}

absl::Status Importer::AddShades(const Json& parent, int set, bool chosen) {
  for (const bool indoor : {true, false}) {
    const char* key = indoor ? "indoor_shades" : "outdoor_shades";
    FENESTRA_ASSIGN_OR_RETURN(shades, parent.ListOf(key, kMaxHoneybeeElements, key));
    const v1::Side side = indoor && chosen ? v1::SIDE_INDOOR : v1::SIDE_OUTDOOR;
    for (const Json& shade : shades) {
      FENESTRA_RETURN_IF_ERROR(AddShade(shade, set, indoor, false, side));
    }
  }
  return absl::OkStatus();
}

absl::Status Importer::AddShade(const Json& shade, int set, bool indoor, bool orphan,
                                v1::Side side) {
  FENESTRA_ASSIGN_OR_RETURN(identifier, shade.Get("identifier"));
  FENESTRA_ASSIGN_OR_RETURN(id, hbjson::Identifier(identifier));
  FENESTRA_ASSIGN_OR_RETURN(detached, shade.BoolOr("is_detached", false));
  const Slot slot = orphan ? (detached ? Slot::kContext : Slot::kShadeExterior)
                           : (indoor ? Slot::kShadeInterior : Slot::kShadeExterior);
  FENESTRA_ASSIGN_OR_RETURN(geometry, shade.Get("geometry"));
  FENESTRA_ASSIGN_OR_RETURN(shape, ReadShape(geometry, scale_, tolerances_));
  FENESTRA_ASSIGN_OR_RETURN(material, Material(shade, set, slot));
  ++summary_.shades;
  if (material.is_void()) return absl::OkStatus();
  return writer_.Add(id, material.material, side, shape.outline, shape.holes, shape.normal,
                     geometry);
}

absl::Status Importer::AddShadeMesh(const Json& mesh) {
  FENESTRA_ASSIGN_OR_RETURN(identifier, mesh.Get("identifier"));
  FENESTRA_ASSIGN_OR_RETURN(id, hbjson::Identifier(identifier));
  FENESTRA_ASSIGN_OR_RETURN(detached, mesh.BoolOr("is_detached", true));
  FENESTRA_ASSIGN_OR_RETURN(material, Material(mesh, Modifiers::kGenericSet,
                                               detached ? Slot::kContext : Slot::kShadeExterior));
  ++summary_.shades;
  FENESTRA_ASSIGN_OR_RETURN(geometry, mesh.Get("geometry"));
  FENESTRA_ASSIGN_OR_RETURN(vertices_json, geometry.Get("vertices"));
  FENESTRA_ASSIGN_OR_RETURN(vertices, vertices_json.Points(scale_, kMaxHoneybeeSurfaces));
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (!(std::abs(vertices[i].x) <= kMaxCoordinateM &&
          std::abs(vertices[i].y) <= kMaxCoordinateM &&
          std::abs(vertices[i].z) <= kMaxCoordinateM)) {
      return vertices_json.At(i).Error(
          absl::StrCat("lies beyond ", kMaxCoordinateM, " m from the origin, the scene's bound"));
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(faces, geometry.ListOf("faces", kMaxHoneybeeSurfaces, "faces"));
  if (material.is_void()) return absl::OkStatus();
  for (size_t f = 0; f < faces.size(); ++f) {
    FENESTRA_ASSIGN_OR_RETURN(corners, faces[f].List(4, "vertex indices"));
    if (corners.size() < 3) return faces[f].Error("a mesh face has 3 or 4 vertex indices");
    std::vector<Vec3d> polygon;
    for (const Json& corner : corners) {
      FENESTRA_ASSIGN_OR_RETURN(index, corner.Number());
      if (!(index >= 0 && index < static_cast<double>(vertices.size()) &&
            index == std::floor(index))) {
        return corner.Error(absl::StrCat("must be the index of a vertex, in [0, ", vertices.size(),
                                         "), got ", index));
      }
      polygon.push_back(vertices[static_cast<size_t>(index)]);
    }
    // A quad off its plane becomes two triangles
    std::vector<std::vector<Vec3d>> parts{polygon};
    if (polygon.size() == 4) {
      const Vec3d n = hbjson::NewellNormal(polygon);
      const double off = Length(n) > 0 ? std::abs(Dot(polygon[2] - polygon[0], Normalize(n))) : 0;
      if (off > tolerances_.length || Length(n) == 0) {
        parts = {{polygon[0], polygon[1], polygon[2]}, {polygon[0], polygon[2], polygon[3]}};
      }
    }
    for (size_t p = 0; p < parts.size(); ++p) {
      if (hbjson::IsDegeneratePolygon(parts[p])) {
        ++summary_.degenerate_pieces;
        continue;
      }
      const Vec3d normal = Normalize(hbjson::NewellNormal(parts[p]));
      const std::string name =
          parts.size() > 1 ? absl::StrCat(id, "#", f, ".", p) : absl::StrCat(id, "#", f);
      FENESTRA_RETURN_IF_ERROR(
          writer_.Add(name, material.material, v1::SIDE_OUTDOOR, parts[p], {}, normal, faces[f]));
    }
  }
  return absl::OkStatus();
}

absl::Status Importer::AddOrphans() {
  const int generic = Modifiers::kGenericSet;
  FENESTRA_ASSIGN_OR_RETURN(faces, model_.ListOf("orphaned_faces", kMaxHoneybeeElements, "faces"));
  for (const Json& face : faces) FENESTRA_RETURN_IF_ERROR(AddFace(face, generic, false));
  // Loose apertures and doors: in a wall of their own plane, to no room
  for (const bool door : {false, true}) {
    const char* key = door ? "orphaned_doors" : "orphaned_apertures";
    FENESTRA_ASSIGN_OR_RETURN(openings, model_.ListOf(key, kMaxHoneybeeElements, key));
    for (const Json& opening : openings) {
      FENESTRA_ASSIGN_OR_RETURN(geometry, opening.Get("geometry"));
      FENESTRA_ASSIGN_OR_RETURN(shape, ReadShape(geometry, scale_, tolerances_));
      FENESTRA_RETURN_IF_ERROR(
          AddOpening(opening, door, shape, FaceKind{"Wall", "Outdoors", ""}, generic, false)
              .status());
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(shades,
                            model_.ListOf("orphaned_shades", kMaxHoneybeeElements, "shades"));
  for (const Json& shade : shades) {
    FENESTRA_RETURN_IF_ERROR(AddShade(shade, generic, false, true, v1::SIDE_OUTDOOR));
  }
  FENESTRA_ASSIGN_OR_RETURN(meshes, model_.ListOf("shade_meshes", kMaxHoneybeeElements, "meshes"));
  for (const Json& mesh : meshes) FENESTRA_RETURN_IF_ERROR(AddShadeMesh(mesh));
  return absl::OkStatus();
}

absl::StatusOr<v1::Scene> Importer::Run(HoneybeeImportSummary& summary) {
  FENESTRA_RETURN_IF_ERROR(ReadUnits());
  FENESTRA_ASSIGN_OR_RETURN(properties, model_.Find("properties"));
  std::optional<Json> radiance;
  if (properties) {
    FENESTRA_ASSIGN_OR_RETURN(found, properties->Find("radiance"));
    radiance = found;
  }
  FENESTRA_ASSIGN_OR_RETURN(modifiers, Modifiers::Read(radiance));
  modifiers_ = std::move(modifiers);
  FENESTRA_RETURN_IF_ERROR(ReadGrids(radiance));

  // Choose the room and its sensors
  FENESTRA_ASSIGN_OR_RETURN(rooms, model_.ListOf("rooms", kMaxHoneybeeRooms, "rooms"));
  for (const Json& room : rooms) {
    FENESTRA_ASSIGN_OR_RETURN(identifier, room.Get("identifier"));
    FENESTRA_ASSIGN_OR_RETURN(id, hbjson::Identifier(identifier));
    room_ids_.push_back(id);
    FENESTRA_ASSIGN_OR_RETURN(box, RoomBox(room));
    room_boxes_.push_back(box);
  }
  FENESTRA_ASSIGN_OR_RETURN(chosen, ChooseRoom(rooms));
  FENESTRA_ASSIGN_OR_RETURN(grids, ChooseGrids(chosen));
  room_id_ = room_ids_[chosen];
  room_centre_ = room_boxes_[chosen].Centre();

  // The geometry: the room first, then what it sees
  FENESTRA_RETURN_IF_ERROR(AddRoom(rooms[chosen], true));
  if (!(room_volume_ > 0)) {
    return rooms[chosen].Error(absl::StrCat(
        "its faces' normals enclose a volume of ", room_volume_,
        " m^3 about the room's centre: they must point out of the room, as Honeybee's do"));
  }
  for (size_t r = 0; r < rooms.size(); ++r) {
    if (r != chosen) FENESTRA_RETURN_IF_ERROR(AddRoom(rooms[r], false));
  }
  FENESTRA_RETURN_IF_ERROR(AddOrphans());
  if (scene_.windows_size() == 0) {
    return rooms[chosen].Error(
        "the room has no aperture in a face to the outdoors: a scene "
        "needs a window");
  }

  // The sensors
  for (const Grid* grid : grids) {
    summary_.sensor_grids.push_back(grid->identifier);
    for (size_t k = 0; k < grid->sensors.size(); ++k) {
      v1::Sensor* sensor = scene_.add_sensors();
      sensor->set_name(absl::StrCat(grid->identifier, "_", k));
      const auto& [position, direction] = grid->sensors[k];
      sensor->mutable_position()->set_x(position.x);
      sensor->mutable_position()->set_y(position.y);
      sensor->mutable_position()->set_z(position.z);
      sensor->mutable_direction()->set_x(direction.x);
      sensor->mutable_direction()->set_y(direction.y);
      sensor->mutable_direction()->set_z(direction.z);
    }
  }
  scene_.set_name(room_id_);
  for (const v1::Material& m : modifiers_.materials()) *scene_.add_materials() = m;

  summary_.room = room_id_;
  summary_.rooms = rooms.size();
  summary_.sensors = static_cast<size_t>(scene_.sensors_size());
  summary_.surfaces = static_cast<size_t>(scene_.surfaces_size());
  summary_.degenerate_pieces += writer_.degenerate();
  summary = summary_;
  return std::move(scene_);
}

}  // namespace

absl::StatusOr<v1::Scene> ImportHoneybee(std::string_view json, const std::string& source_name,
                                         const HoneybeeImportOptions& options,
                                         HoneybeeImportSummary* summary) {
  FENESTRA_ASSIGN_OR_RETURN(root, hbjson::ParseJson(json, source_name, options.max_bytes));
  const Json model(root, "", source_name);
  if (root.kind_case() != google::protobuf::Value::kStructValue) {
    return model.Error("a Honeybee model is a JSON object");
  }
  Importer importer(model, options);
  HoneybeeImportSummary taken;
  FENESTRA_ASSIGN_OR_RETURN(scene, importer.Run(taken));
  if (summary != nullptr) *summary = std::move(taken);
  return scene;
}

}  // namespace fenestra
