// ExportRadiance and RadianceRoundTripForm (rad_import.h describes the format).
#include <google/protobuf/struct.pb.h>

#include <cctype>
#include <set>
#include <unordered_map>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geometry/rad_common.h"
#include "core/geometry/rad_import.h"
#include "core/geometry/rad_io.h"

namespace fenestra {
namespace {

// Whether `name` serves as a Radiance identifier as it is: letters, digits, '_', '-', '.'.
bool IsRadIdentifier(const std::string& name) {
  if (name.empty() || name == "void") return false;
  for (const char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') {
      return false;
    }
  }
  return true;
}

// Appends `vertices` as a Radiance polygon of modifier `modifier` named `id`.
void AppendRadPolygon(std::string& out, const std::string& modifier, const std::string& id,
                      const std::vector<Vec3d>& vertices) {
  absl::StrAppend(&out, modifier, " polygon ", id, "\n0\n0\n", 3 * vertices.size(), "\n");
  for (const Vec3d& v : vertices) {
    absl::StrAppend(&out, "  ", RadReal(v.x), " ", RadReal(v.y), " ", RadReal(v.z), "\n");
  }
  out += '\n';
}

void AppendRadDirective(std::string& out, absl::string_view keyword, absl::string_view argument) {
  absl::StrAppend(&out, kRadDirective, keyword, " ", argument, "\n");
}

// Writes a scene in its round-trip form, every part of it checked by BuildScene first.
class RadWriter {
 public:
  absl::Status Write(const v1::Scene& scene);
  std::string rad, points;

 private:
  absl::Status WriteMaterials(const v1::Scene& scene);
  absl::Status WriteWindow(const v1::Scene& scene, int index);
  absl::Status WriteSurfaces(const v1::Scene& scene);
  void WriteSensors(const v1::Scene& scene);

  std::vector<Material> materials_;                   // as BuildScene makes them
  std::unordered_map<std::string, std::string> ids_;  // material name -> Radiance identifier
};

absl::Status RadWriter::Write(const v1::Scene& scene) {
  // Every part but the windows at once (BuildScene builds one window at a time)
  v1::Scene part = scene;
  part.clear_windows();
  FENESTRA_ASSIGN_OR_RETURN(built, BuildRadPart(part, "scene"));
  if (scene.materials_size() > 0) materials_ = built.materials;
  absl::StrAppend(&rad,
                  "# Fenestra scene: Radiance renders it as it is; the #@fenestra lines "
                  "carry what\n# Radiance has no words for, so that Fenestra reads back "
                  "the same scene.\n");
  AppendRadDirective(rad, "scene", scene.name());
  if (scene.has_site()) AppendRadDirective(rad, "site", RadJson(scene.site()));
  WriteSensors(scene);
  rad += '\n';
  FENESTRA_RETURN_IF_ERROR(WriteMaterials(scene));
  for (int i = 0; i < scene.windows_size(); ++i) FENESTRA_RETURN_IF_ERROR(WriteWindow(scene, i));
  return WriteSurfaces(scene);
}

absl::Status RadWriter::WriteMaterials(const v1::Scene& scene) {
  std::set<std::string> taken;
  for (int i = 0; i < scene.materials_size(); ++i) {
    const v1::Material& m = scene.materials(i);
    std::string id = IsRadIdentifier(m.name()) && !taken.contains(m.name())
                         ? m.name()
                         : RadianceName(static_cast<uint32_t>(i), m.name());
    for (int n = 2; taken.contains(id); ++n) {
      id = absl::StrCat(RadianceName(static_cast<uint32_t>(i), m.name()), "_", n);
    }
    taken.insert(id);
    ids_[m.name()] = id;
    const RadianceModifier modifier = RadianceModifierOf(materials_[i]);
    AppendRadDirective(rad, "material", RadJson(m));
    absl::StrAppend(&rad, "void ", modifier.type, " ", id, "\n0\n0\n", modifier.reals.size());
    for (const double v : modifier.reals) absl::StrAppend(&rad, " ", RadReal(v));
    rad += "\n\n";
  }
  return absl::OkStatus();
}

// The window as its directive and, with a blind, the slats at its design for Radiance.
absl::Status RadWriter::WriteWindow(const v1::Scene& scene, int index) {
  const v1::Window& w = scene.windows(index);
  v1::Scene part;
  *part.mutable_materials() = scene.materials();
  *part.add_windows() = w;
  FENESTRA_ASSIGN_OR_RETURN(
      built, BuildRadPart(part, "scene", "windows[0]", absl::StrCat("windows[", index, "]")));
  AppendRadDirective(rad, "window", RadJson(w));
  if (!built.blind()) return absl::OkStatus();
  const TriangleMesh slats = AssembleMesh(built, DefaultDesign(built));
  absl::StrAppend(&rad, kRadDirective, kRadBlindBegin, "\n");
  for (size_t t = 0; t < slats.TriangleCount(); ++t) {
    const std::vector<Vec3d> corners(slats.vertices.begin() + 3 * t,
                                     slats.vertices.begin() + 3 * t + 3);
    AppendRadPolygon(rad, ids_[scene.materials(slats.material[t]).name()],
                     absl::StrCat("w", index, "_slat_", t), corners);
  }
  absl::StrAppend(&rad, kRadDirective, kRadBlindEnd, "\n\n");
  return absl::OkStatus();
}

absl::Status RadWriter::WriteSurfaces(const v1::Scene& scene) {
  v1::Side side = v1::SIDE_UNSPECIFIED;
  for (int i = 0; i < scene.surfaces_size(); ++i) {
    const v1::Surface& s = scene.surfaces(i);
    if (s.side() != side) {
      side = s.side();
      AppendRadDirective(rad, "side", side == v1::SIDE_INDOOR ? "indoor" : "outdoor");
    }
    AppendRadDirective(rad, "surface", s.name());
    std::vector<Vec3d> vertices;
    for (const v1::Vec3& v : s.polygon().vertices()) vertices.push_back({v.x(), v.y(), v.z()});
    // "s<i>_<name>", the name's characters Radiance takes in a name kept
    const std::string id =
        absl::StrCat("s", RadianceName(static_cast<uint32_t>(i), s.name()).substr(1));
    AppendRadPolygon(rad, ids_[s.material()], id, vertices);
  }
  return absl::OkStatus();
}

void RadWriter::WriteSensors(const v1::Scene& scene) {
  for (int first = 0; first < scene.sensors_size(); first += kRadSensorNamesPerLine) {
    google::protobuf::ListValue names;
    for (int i = first; i < std::min(scene.sensors_size(), first + kRadSensorNamesPerLine); ++i) {
      names.add_values()->set_string_value(scene.sensors(i).name());
    }
    AppendRadDirective(rad, "sensors", RadJson(names));
  }
  for (const v1::Sensor& s : scene.sensors()) {
    const v1::Vec3 &p = s.position(), &d = s.direction();
    absl::StrAppend(&points, RadReal(p.x()), " ", RadReal(p.y()), " ", RadReal(p.z()), " ",
                    RadReal(d.x()), " ", RadReal(d.y()), " ", RadReal(d.z()), "\n");
  }
}

// The 6 faces of a box, BuildScene's (scene.cpp's AddBox), each a polygon surface.
void AppendBoxFaces(const v1::Surface& box, v1::Scene& out) {
  const v1::Vec3 &lo = box.box().min(), &hi = box.box().max();
  static constexpr int kFaces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                                       {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& face : kFaces) {
    v1::Surface* s = out.add_surfaces();
    s->set_name(box.name());
    s->set_material(box.material());
    s->set_side(box.side());
    for (const int i : face) {
      v1::Vec3* v = s->mutable_polygon()->add_vertices();
      v->set_x((i & 1) ? hi.x() : lo.x());
      v->set_y((i & 2) ? hi.y() : lo.y());
      v->set_z((i & 4) ? hi.z() : lo.z());
    }
  }
}

}  // namespace

absl::StatusOr<v1::Scene> RadianceRoundTripForm(const v1::Scene& scene) {
  v1::Scene out = scene;
  out.clear_surfaces();
  for (int i = 0; i < scene.surfaces_size(); ++i) {
    const v1::Surface& s = scene.surfaces(i);
    if (s.has_obj()) {
      return absl::FailedPreconditionError(
          absl::StrCat("surfaces[", i,
                       "] is an OBJ mesh: Radiance models are written from polygon and box "
                       "surfaces only (convert the mesh to polygons)"));
    }
    if (s.has_box()) {
      AppendBoxFaces(s, out);
    } else {
      *out.add_surfaces() = s;
    }
  }
  if (scene.has_window()) {
    v1::Window window = scene.window();
    window.set_name(kOneWindowName);  // BuildScene's name for it
    if (scene.has_blind()) *window.mutable_blind() = scene.blind();
    out.clear_window();
    out.clear_blind();
    out.mutable_windows()->Clear();
    *out.add_windows() = window;
    for (const v1::Window& w : scene.windows()) *out.add_windows() = w;
  }
  if (scene.sensor_grids_size() > 0) {
    // The grids' sensors as BuildScene makes them, named after the explicit ones
    v1::Scene part;
    *part.mutable_sensors() = scene.sensors();
    *part.mutable_sensor_grids() = scene.sensor_grids();
    FENESTRA_ASSIGN_OR_RETURN(built, BuildRadPart(part, "scene"));
    out.clear_sensor_grids();
    for (size_t i = scene.sensors_size(); i < built.sensors.size(); ++i) {
      const Sensor& s = built.sensors[i];
      v1::Sensor* sensor = out.add_sensors();
      sensor->set_name(s.name);
      sensor->mutable_position()->set_x(s.position.x);
      sensor->mutable_position()->set_y(s.position.y);
      sensor->mutable_position()->set_z(s.position.z);
      sensor->mutable_direction()->set_z(1);
    }
  }
  return out;
}

absl::StatusOr<std::string> ExportRadiance(const v1::Scene& scene, std::string* points) {
  FENESTRA_ASSIGN_OR_RETURN(form, RadianceRoundTripForm(scene));
  RadWriter writer;
  FENESTRA_RETURN_IF_ERROR(writer.Write(form));
  if (points) *points = std::move(writer.points);
  return std::move(writer.rad);
}

}  // namespace fenestra
