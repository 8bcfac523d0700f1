#include "core/trace/room_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/trace/embree_scene.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {
namespace {

// Probe rays start this far off the window's plane [m].
constexpr double kProbeOffsetM = 0.001;

// The first surface a probe ray meets: an indoor triangle or a window rectangle.
struct ProbeHit {
  double distance_m = 0;
  std::optional<uint32_t> triangle;  // in scene.fixed; empty = a window
};

// Light passes a material that transmits: glazing, glass, trans.
bool Transmits(const Material& m) {
  return m.transmittance > 0 || m.through > 0 || m.kind == MaterialKind::kGlass;
}

// The scene's fixed indoor surfaces (the blinds and transmitting surfaces, such as the
// glazing in an opening, left out) and its windows, for probe rays.
class IndoorProbe {
 public:
  static absl::StatusOr<std::unique_ptr<IndoorProbe>> Build(const Scene& scene) {
    auto probe = std::unique_ptr<IndoorProbe>(new IndoorProbe(scene));
    TriangleMesh indoor;
    indoor.part_names = scene.fixed.part_names;
    const TriangleMesh& fixed = scene.fixed;
    for (size_t t = 0; t < fixed.TriangleCount(); ++t) {
      if (fixed.side[t] != Side::kIndoor || Transmits(scene.materials[fixed.material[t]])) continue;
      indoor.Add(fixed.vertices[3 * t], fixed.vertices[3 * t + 1], fixed.vertices[3 * t + 2],
                 fixed.material[t], Side::kIndoor, fixed.part[t]);
      probe->triangle_.push_back(static_cast<uint32_t>(t));
    }
    FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(indoor, scene.materials));
    probe->geometry_ = std::move(geometry);
    FENESTRA_ASSIGN_OR_RETURN(embree, EmbreeScene::Build(probe->geometry_));
    probe->embree_ = std::move(embree);
    return probe;
  }

  bool Empty() const { return triangle_.empty(); }

  // The first indoor surface along the ray from `origin`; `with_window` counts the windows
  // (but window `skip`, where the ray starts).
  std::optional<ProbeHit> First(Vec3d origin, Vec3d direction, bool with_window,
                                size_t skip = SIZE_MAX) const {
    std::optional<ProbeHit> first;
    SurfaceHit hit;
    const Vec3f local = geometry_.ToLocal(origin);
    const Vec3f d{static_cast<float>(direction.x), static_cast<float>(direction.y),
                  static_cast<float>(direction.z)};
    if (embree_->Intersector().Intersect(local, d, &hit)) {
      first = ProbeHit{Length(hit.position - local), triangle_[hit.triangle]};
    }
    if (with_window) {
      for (size_t k = 0; k < windows_.size(); ++k) {
        if (k == skip) continue;
        const std::optional<double> window = WindowDistance(windows_[k].window, origin, direction);
        if (window && (!first || *window < first->distance_m)) first = ProbeHit{*window, {}};
      }
    }
    return first;
  }

 private:
  explicit IndoorProbe(const Scene& scene) : windows_(scene.windows) {}

  static std::optional<double> WindowDistance(const Window& w, Vec3d origin, Vec3d direction) {
    const double facing = Dot(direction, w.normal);
    if (facing == 0) return std::nullopt;
    const double t = Dot(w.center - origin, w.normal) / facing;
    if (!(t >= 0)) return std::nullopt;
    const Vec3d p = origin + t * direction - w.center;
    if (std::abs(Dot(p, w.across)) > 0.5 * w.width_m || std::abs(Dot(p, w.up)) > 0.5 * w.height_m) {
      return std::nullopt;
    }
    return t;
  }

  std::vector<SceneWindow> windows_;
  std::vector<uint32_t> triangle_;  // probe triangle -> scene.fixed triangle
  TraceGeometry geometry_;
  std::unique_ptr<EmbreeScene> embree_;
};

std::string Point(Vec3d p) { return absl::StrCat("(", p.x, ", ", p.y, ", ", p.z, ")"); }

// "+x", "-x+y", ...: the axes a direction leans along.
std::string DirectionName(Vec3d d) {
  std::string name;
  const char* axes[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) > 0.3) absl::StrAppend(&name, d[i] > 0 ? "+" : "-", axes[i]);
  }
  return name;
}

std::string SurfaceName(const Scene& scene, const ProbeHit& hit) {
  if (!hit.triangle) return scene.windows.size() == 1 ? "the window" : "a window";
  return absl::StrCat("surface '", scene.fixed.part_names[scene.fixed.part[*hit.triangle]], "'");
}

absl::Status Invalid(const Scene& scene, const std::string& what, const std::string& reason) {
  return absl::InvalidArgumentError(absl::StrCat(scene.source_path, ": ", what, ": ", reason));
}

// ---------------------------------------------------------------------------------------
// The window
// ---------------------------------------------------------------------------------------

// Points of the window rectangle, `inset` inside its edges: corners, edge middles, centre.
std::vector<Vec3d> WindowSamples(const Window& w, double inset) {
  const double u = std::max(0.0, 0.5 * w.width_m - inset);
  const double v = std::max(0.0, 0.5 * w.height_m - inset);
  std::vector<Vec3d> points;
  for (const double a : {-u, 0.0, u}) {
    for (const double b : {-v, 0.0, v}) points.push_back(w.center + a * w.across + b * w.up);
  }
  return points;
}

// Where a window is in the scene file: "window" in the one-window form, else
// "windows[i] ('name')".
std::string WindowField(const Scene& scene, size_t i) {
  if (scene.windows.size() == 1 && scene.windows[0].name == kOneWindowName) return "window";
  return absl::StrCat("windows[", i, "] ('", scene.windows[i].name, "')");
}

// The rectangle is open through the wall, the room lies behind it and nothing of the room
// in front of it.
absl::Status CheckWindowOpening(const Scene& scene, size_t i, const IndoorProbe& probe) {
  const Window& w = scene.windows[i].window;
  const std::string field = WindowField(scene, i);
  for (const Vec3d& p :
       WindowSamples(w, std::min(kWindowFitM, 0.25 * std::min(w.width_m, w.height_m)))) {
    const Vec3d start = p + kProbeOffsetM * w.normal;
    // The room behind: an indoor surface, or another window across the room
    const std::optional<ProbeHit> behind = probe.First(start, -w.normal, true, i);
    if (!behind) {
      return Invalid(scene, field,
                     absl::StrCat("no indoor surface lies behind its point ", Point(p),
                                  ": the room must lie on the side opposite outward_normal"));
    }
    if (behind->distance_m <= w.depth_m + kProbeOffsetM + kWindowFitM) {
      return Invalid(
          scene, field,
          absl::StrCat("the opening is closed at ", Point(p), ": ", SurfaceName(scene, *behind),
                       " lies ", behind->distance_m - kProbeOffsetM,
                       " m behind the window, within the wall (depth_m ", w.depth_m,
                       "); the window rectangle must match an opening in the indoor "
                       "surfaces"));
    }
    if (const std::optional<ProbeHit> front = probe.First(start, w.normal, false)) {
      return Invalid(
          scene, field,
          absl::StrCat(SurfaceName(scene, *front), " lies ", front->distance_m + kProbeOffsetM,
                       " m in front of its point ", Point(p),
                       ": outward_normal must point away from the room, "
                       "and the window lie on the room's boundary"));
    }
  }
  return absl::OkStatus();
}

// Just outside an edge point, the indoor surfaces close the gap between window and room:
// seen from the room, the wall's inner face lies depth_m behind the window's outer face
// (within kWindowFitM), or a surface runs across the edge (a window filling its wall).
bool EdgeClosed(const Window& w, const IndoorProbe& probe, Vec3d edge_point, Vec3d outwards) {
  const double depth = w.depth_m + kProbeOffsetM;
  const Vec3d behind_wall = edge_point + kWindowFitM * outwards - (depth + kWindowFitM) * w.normal;
  const std::optional<ProbeHit> wall = probe.First(behind_wall, w.normal, false);
  if (wall && wall->distance_m <= 2 * kWindowFitM + kProbeOffsetM) return true;
  const Vec3d inside = edge_point - kWindowFitM * outwards - depth * w.normal;
  const std::optional<ProbeHit> across = probe.First(inside, outwards, false);
  return across && across->distance_m <= 2 * kWindowFitM;
}

absl::Status CheckWindowRim(const Scene& scene, size_t i, const IndoorProbe& probe) {
  const Window& w = scene.windows[i].window;
  const std::string field = WindowField(scene, i);
  struct Edge {
    Vec3d outwards, along;
    double offset, half_length;
  };
  const Edge edges[4] = {{w.up, w.across, 0.5 * w.height_m, 0.5 * w.width_m},
                         {-w.up, w.across, 0.5 * w.height_m, 0.5 * w.width_m},
                         {w.across, w.up, 0.5 * w.width_m, 0.5 * w.height_m},
                         {-w.across, w.up, 0.5 * w.width_m, 0.5 * w.height_m}};
  for (const Edge& e : edges) {
    for (const double s : {-0.5, 0.0, 0.5}) {
      const Vec3d point = w.center + e.offset * e.outwards + (s * e.half_length) * e.along;
      if (EdgeClosed(w, probe, point, e.outwards)) continue;
      return Invalid(
          scene, field,
          absl::StrCat("it does not lie at an opening of the indoor surfaces: ", kWindowFitM,
                       " m outside its edge towards ", DirectionName(e.outwards), ", at ",
                       Point(point + kWindowFitM * e.outwards),
                       ", no indoor surface closes the gap between window and room (seen from "
                       "the room, the wall's inner face should lie depth_m = ",
                       w.depth_m, " m behind the window, or a surface run across the edge)"));
    }
  }
  return absl::OkStatus();
}

// True when boxes a and b (centre, three unit axes, half extents) overlap: no separating axis
// among their face normals and the cross products of their edges. A flat rectangle is a box
// of half extent 0 across.
bool BoxesOverlap(const Vec3d& ca, const Vec3d (&a)[3], const double (&ha)[3], const Vec3d& cb,
                  const Vec3d (&b)[3], const double (&hb)[3]) {
  std::vector<Vec3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a[i]), axes.push_back(b[i]);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec3d c = Cross(a[i], b[j]);
      if (Length(c) > 1e-9) axes.push_back(Normalize(c));
    }
  }
  const Vec3d d = cb - ca;
  for (const Vec3d& axis : axes) {
    double ra = 0, rb = 0;
    for (int i = 0; i < 3; ++i) {
      ra += ha[i] * std::abs(Dot(a[i], axis));
      rb += hb[i] * std::abs(Dot(b[i], axis));
    }
    // Touching (a shared edge of windows side by side) is not overlapping; across flat boxes
    // (coplanar windows) only a gap separates them
    const double reach = ra + rb;
    const double gap = reach > kWindowFitM ? reach - kWindowFitM : reach + 1e-6;
    if (std::abs(Dot(d, axis)) >= gap) return false;
  }
  return true;
}

// Windows do not overlap one another, nor do the spaces their blinds' slats may take.
absl::Status CheckWindowsApart(const Scene& scene) {
  for (size_t i = 0; i < scene.windows.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      const Window& a = scene.windows[i].window;
      const Window& b = scene.windows[j].window;
      const Vec3d axes_a[3] = {a.across, a.up, a.normal}, axes_b[3] = {b.across, b.up, b.normal};
      const double ha[3] = {0.5 * a.width_m, 0.5 * a.height_m, 0};
      const double hb[3] = {0.5 * b.width_m, 0.5 * b.height_m, 0};
      if (BoxesOverlap(a.center, axes_a, ha, b.center, axes_b, hb)) {
        return Invalid(scene, WindowField(scene, i),
                       absl::StrCat("overlaps ", WindowField(scene, j)));
      }
      const auto& blind_a = scene.windows[i].blind;
      const auto& blind_b = scene.windows[j].blind;
      if (!blind_a || !blind_b) continue;
      const BlindEnvelope ea = EnvelopeOfBlind(a, *blind_a, 0);
      const BlindEnvelope eb = EnvelopeOfBlind(b, *blind_b, 0);
      if (BoxesOverlap(ea.center, ea.axis, ea.half_extent, eb.center, eb.axis, eb.half_extent)) {
        return Invalid(scene, WindowField(scene, i) + ".blind",
                       absl::StrCat("its slats may reach into the space of the blind of ",
                                    WindowField(scene, j), " at some design within the ranges"));
      }
    }
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------------------
// The sensors
// ---------------------------------------------------------------------------------------

// The 26 probe directions (the cube's faces, edges and corners), turned a little off the
// axes so that no probe runs exactly along an axis-aligned wall or through its corner;
// `turn` picks one of three turns.
std::vector<std::pair<Vec3d, std::string>> ProbeDirections(int turn) {
  const double angles[3][2] = {{0.0123, 0.0371}, {0.0517, -0.0283}, {-0.0419, 0.0611}};
  const double a = angles[turn][0], b = angles[turn][1];
  std::vector<std::pair<Vec3d, std::string>> directions;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      for (int k = -1; k <= 1; ++k) {
        if (i == 0 && j == 0 && k == 0) continue;
        const Vec3d d = Normalize(Vec3d{double(i), double(j), double(k)});
        // Rotate about z by a, then about x by b
        const Vec3d r{d.x * std::cos(a) - d.y * std::sin(a), d.x * std::sin(a) + d.y * std::cos(a),
                      d.z};
        const Vec3d turned{r.x, r.y * std::cos(b) - r.z * std::sin(b),
                           r.y * std::sin(b) + r.z * std::cos(b)};
        directions.push_back({turned, DirectionName(d)});
      }
    }
  }
  return directions;
}

// "<source>: sensors[3] ("desk 2") at (1, -50, 0.7) <reason>"
absl::Status SensorError(const Scene& scene, const Sensor& s, const std::string& reason) {
  return absl::InvalidArgumentError(absl::StrCat(scene.source_path, ": ", s.field, " (\"", s.name,
                                                 "\") at ", Point(s.position), " ", reason));
}

bool InsideBox(const SolidBox& box, Vec3d p) {
  for (int i = 0; i < 3; ++i) {
    if (!(p[i] > box.min[i] - kSensorClearanceM && p[i] < box.max[i] + kSensorClearanceM)) {
      return false;
    }
  }
  return true;
}

bool InsideEnvelope(const BlindEnvelope& e, Vec3d p) {
  for (int i = 0; i < 3; ++i) {
    if (!(std::abs(Dot(p - e.center, e.axis[i])) < e.half_extent[i])) return false;
  }
  return true;
}

// True when every turn of probe `index` leaves the room.
bool Escapes(const IndoorProbe& probe, Vec3d p, size_t index,
             const std::vector<std::pair<Vec3d, std::string>> (&turns)[3]) {
  for (const auto& directions : turns) {
    if (probe.First(p, directions[index].first, true)) return false;
  }
  return true;
}

class SensorCheck {
 public:
  SensorCheck(const Scene& scene, const IndoorProbe& probe) : scene_(scene), probe_(probe) {
    for (int t = 0; t < 3; ++t) turns_[t] = ProbeDirections(t);
    for (const SolidBox& box : scene.solid_boxes) boxes_[box.part] = &box;
    for (const SceneWindow& w : scene.windows) {
      if (!w.blind) continue;
      envelopes_.push_back(EnvelopeOfBlind(w.window, *w.blind, kSensorClearanceM));
      names_.push_back(scene.windows.size() == 1 ? "" : " (of window '" + w.name + "')");
    }
  }

  absl::Status Check(const Sensor& s) const {
    for (size_t k = 0; k < envelopes_.size(); ++k) {
      if (!InsideEnvelope(envelopes_[k], s.position)) continue;
      return SensorError(scene_, s,
                         absl::StrCat("lies in the space the blind's slats take", names_[k],
                                      " at some design within the ranges (just behind the "
                                      "window's inner face); move it into the room"));
    }
    const auto& directions = turns_[0];
    for (size_t i = 0; i < directions.size(); ++i) {
      const std::optional<ProbeHit> hit = probe_.First(s.position, directions[i].first, true);
      if (!hit) {
        if (!Escapes(probe_, s.position, i, turns_)) continue;
        return SensorError(scene_, s,
                           absl::StrCat("is outside the room: a ray towards ", directions[i].second,
                                        " leaves without meeting an indoor surface or the window"));
      }
      FENESTRA_RETURN_IF_ERROR(CheckHit(s, *hit));
    }
    return absl::OkStatus();
  }

 private:
  absl::Status CheckHit(const Sensor& s, const ProbeHit& hit) const {
    if (hit.distance_m < kSensorClearanceM) {
      return SensorError(
          scene_, s,
          absl::StrCat("lies on ", SurfaceName(scene_, hit), " (within ", kSensorClearanceM,
                       " m); a sensor must be in the room's air"));
    }
    if (!hit.triangle) return absl::OkStatus();
    auto box = boxes_.find(scene_.fixed.part[*hit.triangle]);
    if (box != boxes_.end() && InsideBox(*box->second, s.position)) {
      return SensorError(scene_, s,
                         absl::StrCat("is inside the solid box of ", SurfaceName(scene_, hit),
                                      "; a sensor must be in the room's air"));
    }
    return absl::OkStatus();
  }

  const Scene& scene_;
  const IndoorProbe& probe_;
  std::vector<std::pair<Vec3d, std::string>> turns_[3];
  std::unordered_map<uint32_t, const SolidBox*> boxes_;
  std::vector<BlindEnvelope> envelopes_;
  std::vector<std::string> names_;  // per envelope: which window's blind, in messages
};

}  // namespace

absl::Status CheckRoom(const Scene& scene) {
  FENESTRA_ASSIGN_OR_RETURN(probe, IndoorProbe::Build(scene));
  if (probe->Empty()) {
    return Invalid(scene, "surfaces",
                   "no surface is SIDE_INDOOR: the sensors need a room around them");
  }
  FENESTRA_RETURN_IF_ERROR(CheckWindowsApart(scene));
  for (size_t i = 0; i < scene.windows.size(); ++i) {
    FENESTRA_RETURN_IF_ERROR(CheckWindowOpening(scene, i, *probe));
    FENESTRA_RETURN_IF_ERROR(CheckWindowRim(scene, i, *probe));
  }
  const SensorCheck sensors(scene, *probe);
  for (const Sensor& s : scene.sensors) FENESTRA_RETURN_IF_ERROR(sensors.Check(s));
  for (const ViewPoint& v : scene.views) FENESTRA_RETURN_IF_ERROR(sensors.Check(EyeSensor(v)));
  return absl::OkStatus();
}

absl::StatusOr<Scene> ValidateScene(const v1::Scene& proto, const std::string& path) {
  FENESTRA_ASSIGN_OR_RETURN(scene, BuildScene(proto, path));
  FENESTRA_RETURN_IF_ERROR(CheckRoom(scene));
  return scene;
}

absl::StatusOr<Scene> LoadValidScene(const std::string& path) {
  FENESTRA_ASSIGN_OR_RETURN(proto, ReadSceneProto(path));
  return ValidateScene(proto, path);
}

}  // namespace fenestra
