#include "core/dc/direct_sun.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
#include "core/dc/dc_backend.h"
#include "core/dc/indoor_replay.h"
#include "core/trace/embree_scene.h"
#include "core/trace/ray_offset.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {
namespace {

// Surfaces a line may pass through (glazing) before it counts as stopped: a safety net.
constexpr int kMaxCrossings = 32;
// A hit this close to a line's start is the surface the sensor lies on [m]: the line starts at
// the sensor itself (not moved off by the tracers' ulp-scaled offset, which reaches a quarter
// of a millimetre 10 m from the frame's origin, enough to slip past a slat's corner).
constexpr float kOwnSurfaceM = 1e-5f;
// Length of a line in the tests against the slats [m]: past any blind.
constexpr float kLineLength = 1e4f;

Vec3f ToFloat(Vec3d v) {
  return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

// The share of the sun's beam that gets along the line from `origin` towards `direction`
// through `geometry`: the product of the glazing transmittances it crosses, 0 where
// something opaque stops it.
double Transmission(const EmbreeIntersector& scene, const TraceGeometry& geometry, Vec3f origin,
                    Vec3f direction) {
  double transmission = 1;
  for (int crossing = 0; crossing < kMaxCrossings; ++crossing) {
    SurfaceHit hit;
    if (!scene.Intersect(origin, direction, &hit)) return transmission;
    const TraceMaterial m = geometry.materials[geometry.triangle_material[hit.triangle]];
    const bool own = crossing == 0 && Length(hit.position - origin) < kOwnSurfaceM;
    const Vec3f normal = Normalize(Dot(hit.normal, direction) > 0.0f ? hit.normal : -hit.normal);
    if (!own) {
      // Only glazing's straight pass leaves the beam where it was (trans scatters it)
      const float t = m.straight_scatters ? 0.0f : StraightTransmittance(m, Dot(normal, direction));
      if (!(t > 0.0f)) return 0;
      transmission *= t;
    }
    origin = OffsetRayOrigin(hit.position, normal);
  }
  return 0;
}

// What a slat of `finish` lets through along a line: a line through a slat crosses both broad
// faces, and which it meets first is not kept, so slats whose two materials differ in straight
// transmittance count as opaque, as trans slats do (their straight part scatters).
float SlatTransmittance(const std::vector<Material>& materials, const SlatFinish& finish) {
  const auto straight = [&](uint32_t index) {
    if (index >= materials.size()) return 0.0;
    const Material& slat = materials[index];
    return slat.kind == MaterialKind::kTrans ? 0.0 : std::max(slat.transmittance, 0.0);
  };
  const double inner = straight(finish.material);
  return inner == straight(finish.outer_material) ? static_cast<float>(inner) : 0.0f;
}

}  // namespace

struct DirectSun::Data {
  // A sensor's line towards one sun that the blind may stop, in the frame of `geometry`
  struct Line {
    SunEntry entry;
    Vec3f origin, direction;
  };
  TraceGeometry geometry;
  Scene scene;  // the blind and its ranges, the window
  int sensors = 0, columns = 0;
  std::vector<SunEntry> always;  // lines no blind of the ranges can reach
  std::vector<Line> lines;       // lines through a blind's envelope
};

DirectSun::DirectSun(std::unique_ptr<Data> data) : data_(std::move(data)) {}
DirectSun::~DirectSun() = default;

absl::StatusOr<std::unique_ptr<DirectSun>> DirectSun::Trace(const Scene& scene,
                                                            const std::vector<SunColumn>& suns,
                                                            int columns) {
  for (const SunColumn& sun : suns) {
    if (sun.column < 0 || sun.column >= columns) {
      return absl::InvalidArgumentError(
          absl::StrCat("direct sun: column ", sun.column, " outside [0, ", columns, ")"));
    }
    if (!(std::abs(Length(sun.direction) - 1) < 1e-6) || !(sun.normal_lux >= 0)) {
      return absl::InvalidArgumentError("direct sun: a sun without a unit direction or light");
    }
  }
  auto data = std::make_unique<Data>();
  // In a frame about the (first blind's) window, where the lines meet the slats: floats are
  // finest there
  const Vec3d frame = scene.BlindWindow().window.center;
  FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(scene.fixed, scene.materials, &frame));
  data->geometry = std::move(geometry);
  data->scene = scene;
  data->sensors = static_cast<int>(scene.sensors.size());
  data->columns = columns;
  FENESTRA_ASSIGN_OR_RETURN(embree, EmbreeScene::Build(data->geometry));
  const EmbreeIntersector intersector = embree->Intersector();
  std::vector<LocalEnvelope> envelopes;
  for (const SceneWindow& w : scene.windows) {
    if (w.blind) envelopes.push_back(LocalEnvelopeOfBlind(data->geometry, w));
  }
  // Each sensor's lines on a thread of its own, kept in sensor order
  std::vector<std::vector<SunEntry>> always(data->sensors);
  std::vector<std::vector<Data::Line>> lines(data->sensors);
  ParallelFor(data->sensors, ResolveThreadCount(0), [&](uint64_t s) {
    const Sensor& sensor = scene.sensors[s];
    const Vec3f origin = data->geometry.ToLocal(sensor.position);
    for (const SunColumn& sun : suns) {
      const double cosine = Dot(sensor.direction, sun.direction);
      if (!(cosine > 0) || !(sun.normal_lux > 0)) continue;
      const Vec3f direction = ToFloat(sun.direction);
      const double transmission = Transmission(intersector, data->geometry, origin, direction);
      if (!(transmission > 0)) continue;
      const SunEntry entry{static_cast<int32_t>(s), sun.column,
                           sun.normal_lux * cosine * transmission};
      if (std::any_of(envelopes.begin(), envelopes.end(), [&](const LocalEnvelope& e) {
            return e.Touches(origin, direction, kLineLength);
          })) {
        lines[s].push_back({entry, origin, direction});
      } else {
        always[s].push_back(entry);
      }
    }
  });
  for (int s = 0; s < data->sensors; ++s) {
    data->always.insert(data->always.end(), always[s].begin(), always[s].end());
    data->lines.insert(data->lines.end(), lines[s].begin(), lines[s].end());
  }
  return std::unique_ptr<DirectSun>(new DirectSun(std::move(data)));
}

std::vector<SunEntry> DirectSun::Entries(const BlindDesign& design, bool blind) const {
  const Data& d = *data_;
  std::vector<SunEntry> out;
  out.reserve(d.always.size() + d.lines.size());
  const bool slats = blind && d.scene.blind().has_value();
  // Every blind at the design (the blinds of a scene share it)
  std::vector<LocalSlats> local;
  for (const SceneWindow& w : d.scene.windows) {
    if (slats && w.blind) local.push_back(LocalSlatsOfBlind(d.geometry, w, design));
  }
  const float slat_transmittance =
      slats ? SlatTransmittance(d.scene.materials, FinishOf(*d.scene.blind(), design)) : 0.0f;
  // Both lists are in sensor order, each sensor's in column order: merged by sensor, then
  // column
  size_t a = 0, l = 0;
  const auto before = [](const SunEntry& x, const SunEntry& y) {
    return x.sensor != y.sensor ? x.sensor < y.sensor : x.column < y.column;
  };
  while (a < d.always.size() || l < d.lines.size()) {
    if (l == d.lines.size() || (a < d.always.size() && before(d.always[a], d.lines[l].entry))) {
      out.push_back(d.always[a++]);
      continue;
    }
    const Data::Line& line = d.lines[l++];
    SunEntry entry = line.entry;
    for (const LocalSlats& blind_slats : local) {
      if (blind_slats.Occluded(line.origin, line.direction, kLineLength)) {
        entry.lux *= slat_transmittance;
      }
    }
    if (entry.lux > 0) out.push_back(entry);
  }
  return out;
}

Matrix DirectSun::Illuminance(const BlindDesign& design, bool blind) const {
  Matrix e = Matrix::Zero(data_->sensors, data_->columns);
  for (const SunEntry& entry : Entries(design, blind)) e(entry.sensor, entry.column) = entry.lux;
  return e;
}

int DirectSun::Sensors() const { return data_->sensors; }
int DirectSun::Columns() const { return data_->columns; }
size_t DirectSun::Lines() const { return data_->always.size() + data_->lines.size(); }

void AddSunEntries(std::span<const SunEntry> entries, int sensors, Matrix& illuminance) {
  if (sensors <= 0) return;
  const Eigen::Index blocks = illuminance.rows() / sensors;
  for (Eigen::Index b = 0; b < blocks; ++b) {
    for (const SunEntry& entry : entries) {
      illuminance(b * sensors + entry.sensor, entry.column) += entry.lux;
    }
  }
}

absl::Status CheckSunEntries(std::span<const SunEntry> entries, const std::vector<Matrix>& batches,
                             const Matrix& sky) {
  if (entries.empty()) return absl::OkStatus();
  if (sky.rows() != kSplitSkyRows) {
    return absl::InvalidArgumentError("the direct sun needs a split sky");
  }
  const Eigen::Index sensors = batches.empty() ? 0 : batches[0].rows();
  for (const SunEntry& e : entries) {
    if (e.sensor < 0 || e.sensor >= sensors || e.column < 0 || e.column >= sky.cols() ||
        !std::isfinite(e.lux)) {
      return absl::InvalidArgumentError(absl::StrCat("a direct-sun entry for sensor ", e.sensor,
                                                     ", column ", e.column, " out of range"));
    }
  }
  return absl::OkStatus();
}

}  // namespace fenestra
