// The two path modes of the two-stage method (core/README.md, "Two-stage method"), for
// TracePath.
//
// The window is the interface: a rectangle (the opening's outer face) with a frame
// (across, up, outward normal); directions are binned by the hemisphere basis of
// core/geometry/hemisphere_basis.h in that frame, by the outward direction omega, the way
// light comes from. The rectangle may be split into columns x rows equal parts, each with
// its own cells (window cell = part * basis cells + direction cell): O then holds the
// radiance averaged over each part rather than over the whole window, which matters where
// the outdoor view changes across the window (a street's edge seen from a wide window).
//
// Direct light is kept apart from the cells. A window connection (x_w, omega) whose ray
// from x_w along omega meets no outdoor surface sees the sky patch of omega itself: the
// indoor stage tests that ray against the outdoor surfaces and scores such light straight
// into a column per sky bin (the direct part of I, no averaging over a cell). Only light
// whose first outdoor segment meets a surface goes through the window cells and O, which
// then holds the radiance of the outdoor surfaces, smooth in position and direction where
// the sky's edge against the buildings (a step in radiance from sky to wall) is not. So
// D = I O with I's columns the window cells, then the 146 sky bins, and O's rows the
// reflected radiance of each window cell, then the identity. The test is only traced for
// views from window cells that may reach the sky: from most cells of a window in a street
// every view meets the street or the buildings across it (core/trace/window_cells.h).
//
// OutdoorMode: a path starts at a uniform point of its window part, its direction within
// one basis cell distributed by projected solid angle (cos omega d omega dA is the measure
// in which radiance crossing the window carries flux, so also the one in which the indoor
// stage weights a cell), then bounces in the outdoor scene. A path whose first segment
// reaches the sky is only counted (the indoor stage scores that light directly); any
// other path escaping through sky bin j adds its weight to O[cell, j], so O[cell, j] / (the
// paths whose first segment met a surface) estimates the mean radiance arriving at the
// window from the cell per unit radiance of bin j, given that the view meets a surface. A
// path that goes back in through the window ends there: light that leaves the room and
// returns through the window is the one interreflection the two-stage split leaves out.
//
// IndoorMode: a path starts at a sensor, cosine-sampled, and bounces in the indoor scene.
// Light from the window reaches each vertex (the sensor included, and every reflection the
// bounce limit allows) by two techniques, combined by multiple importance sampling (power
// heuristic): next-event estimation samples a uniform window point x_w and, if the
// segment is clear, scores the irradiance the window delivers there per unit radiance (at
// the sensor cos_s cos_w A / r^2; at a reflection w rho cos_v cos_w A / r^2, the sensor's
// cosine-sampled estimator pi L with L = rho / pi times the vertex's irradiance, w the path
// weight before the reflection); and a bounce ray that leaves through the window scores
// pi w. Next-event estimation alone has infinite variance where surfaces touch the window
// (the reveals): its 1 / r^2 grows without bound at the window's edge, while there the
// bounce ray samples the window well. Either way the score goes to the sky bin's direct
// column or to the window cell of (x_w, omega), by the outdoor test above.
#pragma once

#include <math.h>
#include <stdint.h>

#include <vector>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"
#include "core/geometry/hemisphere_basis.h"
#include "core/sky/sky_bin.h"
#include "core/trace/path.h"
#include "core/trace/ray_offset.h"
#include "core/trace/sampling.h"

namespace fenestra {

// The window rectangle in the trace frame.
struct TraceWindow {
  Vec3f center;  // centre of the outer face (local frame)
  Vec3f across;  // unit, along the width
  Vec3f up;      // unit, along the height
  Vec3f normal;  // unit, outward
  float width;
  float height;
  int32_t columns = 1;  // parts across
  int32_t rows = 1;     // parts up
  // Among all windows of the scene (TraceWindows): the first of this window's cells, and the
  // area of the windows before it
  int32_t first_cell = 0;
  float area_before = 0.0f;

  FENESTRA_CPU_GPU float Area() const { return width * height; }
  FENESTRA_CPU_GPU int Parts() const { return columns * rows; }
  // The part of the window point Point(u0, u1).
  FENESTRA_CPU_GPU int PartOf(float u0, float u1) const {
    return Clamp(static_cast<int>(u1 * rows), rows) * columns +
           Clamp(static_cast<int>(u0 * columns), columns);
  }
  // The part of a point in the window plane.
  FENESTRA_CPU_GPU int PartAt(Vec3f point) const {
    const Vec3f offset = point - center;
    return PartOf(Dot(offset, across) / width + 0.5f, Dot(offset, up) / height + 0.5f);
  }
  // A uniform point of `part` for two uniforms.
  FENESTRA_CPU_GPU Vec3f PartPoint(int part, float u0, float u1) const {
    return Point((static_cast<float>(part % columns) + u0) / static_cast<float>(columns),
                 (static_cast<float>(part / columns) + u1) / static_cast<float>(rows));
  }
  FENESTRA_CPU_GPU static int Clamp(int i, int count) {
    return i < 0 ? 0 : (i >= count ? count - 1 : i);
  }
  // The window point for two uniforms.
  FENESTRA_CPU_GPU Vec3f Point(float u0, float u1) const {
    return center + across * ((u0 - 0.5f) * width) + up * ((u1 - 0.5f) * height);
  }
  // Distance t > 0 at which origin + t direction passes through the window rectangle, or a
  // negative value if it does not.
  FENESTRA_CPU_GPU float Crossing(Vec3f origin, Vec3f direction) const {
    const float towards = Dot(direction, normal);
    if (towards == 0.0f) return -1.0f;
    const float t = Dot(center - origin, normal) / towards;
    if (!(t > 0.0f)) return -1.0f;
    const Vec3f offset = origin + direction * t - center;
    const bool inside =
        fabsf(Dot(offset, across)) <= 0.5f * width && fabsf(Dot(offset, up)) <= 0.5f * height;
    return inside ? t : -1.0f;
  }
  // Whether the ray enters the window rectangle from outside.
  FENESTRA_CPU_GPU bool Crosses(Vec3f origin, Vec3f direction) const {
    return Dot(direction, normal) < 0.0f && Crossing(origin, direction) > 0.0f;
  }
  // A window-frame direction in the trace frame.
  FENESTRA_CPU_GPU Vec3f ToWorld(Vec3f local) const {
    return across * local.x + up * local.y + normal * local.z;
  }
};

// Every window of a scene in the trace frame, in the scene's order: the indoor stage's light
// comes in through any of them, and an outdoor path that goes back in through any of them ends.
// Window w's cells are list[w].first_cell + part * basis cells + direction cell: the indoor
// matrix's columns hold every window's cells, one window after the other, then the direct
// columns, which all windows share (a sky bin seen through either window is the same sky).
struct TraceWindows {
  const TraceWindow* list;  // `count` windows (on a GPU, in device memory)
  int32_t count;
  int32_t cells;  // of all windows
  float area;     // of all windows [m2]

  // The window drawn for a uniform u with probability its area over all windows' area, so that
  // a window point drawn uniformly on it is a uniform point of all windows' area.
  FENESTRA_CPU_GPU int Pick(float u) const {
    const float target = u * area;
    for (int w = 0; w + 1 < count; ++w) {
      if (target < list[w].area_before + list[w].Area()) return w;
    }
    return count - 1;
  }
  // The window whose rectangle the ray passes through first, and the distance there in
  // *distance; -1 if none.
  FENESTRA_CPU_GPU int Crossed(Vec3f origin, Vec3f direction, float* distance) const {
    int crossed = -1;
    for (int w = 0; w < count; ++w) {
      const float t = list[w].Crossing(origin, direction);
      if (t > 0.0f && (crossed < 0 || t < *distance)) {
        crossed = w;
        *distance = t;
      }
    }
    return crossed;
  }
  // Whether the ray enters the room through one of the windows.
  FENESTRA_CPU_GPU bool Enters(Vec3f origin, Vec3f direction) const {
    for (int w = 0; w < count; ++w) {
      if (list[w].Crosses(origin, direction)) return true;
    }
    return false;
  }
};

// Random stream of outdoor paths starting in cell c of window w: kOutdoorStreamBase +
// w * kOutdoorWindowStreams + c, apart from the sensors' streams.
inline constexpr uint32_t kOutdoorStreamBase = 0x80000000u;
inline constexpr uint32_t kOutdoorWindowStreams = 1u << 19;  // > the most cells of a window

// Multiple importance sampling weight of the technique with density a against one with
// density b (the power heuristic, exponent 2).
FENESTRA_CPU_GPU inline float PowerHeuristic(float a, float b) {
  const float a2 = a * a, b2 = b * b;
  return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

inline constexpr float kInvPiF = 0.318309886183790672f;

// Random purposes (PathRandom::Draw's second argument) of the two-stage modes.
inline constexpr uint32_t kWindowSamplePurpose = 1;

// Cells of the window: its parts times the direction cells of the basis.
FENESTRA_CPU_GPU inline int WindowCellCount(const TraceWindow& window,
                                            const HemisphereBasis& basis) {
  return window.Parts() * basis.cell_count;
}

// Entries of a row of outdoor sums: the reflected light per sky bin, then the number of
// paths whose first segment reached the sky.
inline constexpr int kOutdoorRowSize = kTregenzaBinCount + 1;
inline constexpr int kFirstEscapeEntry = kTregenzaBinCount;

// O_b's entry for sky bin `bin` from a window cell's row of outdoor sums over the batch's
// `paths`: the reflected light over the paths whose first segment met a surface, 0 where none
// did.
FENESTRA_CPU_GPU inline double OutdoorCoefficient(const double* row, double paths, int bin) {
  const double met = paths - row[kFirstEscapeEntry];
  return met > 0 ? row[bin] / met : 0.0;
}

// Columns of the indoor matrix: the window cells, then the sky bins' direct columns twice:
// first for light reflected in the room at least once, then for the sensor's own view of the
// sky through the window (no reflection: the direct component, which the direct sun replaces;
// core/README.md, "Direct sun"). O's rows below the cells are the identity for each block.
inline constexpr int kIndoorDirectColumns = 2 * kTregenzaBinCount;
FENESTRA_CPU_GPU inline int IndoorColumnCount(const TraceWindows& windows) {
  return windows.cells + kIndoorDirectColumns;
}
// A view of `windows` (their first cells and areas before them filled in by LinkWindows).
inline TraceWindows ViewOfWindows(const std::vector<TraceWindow>& windows,
                                  const HemisphereBasis& basis) {
  TraceWindows view{windows.data(), static_cast<int32_t>(windows.size()), 0, 0.0f};
  for (const TraceWindow& w : windows) view.area += w.Area();
  if (!windows.empty()) {
    view.cells = windows.back().first_cell + WindowCellCount(windows.back(), basis);
  }
  return view;
}

// Fills in each window's first cell (of `basis`'s cells per part) and the area before it.
inline void LinkWindows(const HemisphereBasis& basis, std::vector<TraceWindow>* windows) {
  int32_t cells = 0;
  float area = 0.0f;
  for (TraceWindow& w : *windows) {
    w.first_cell = cells;
    w.area_before = area;
    cells += WindowCellCount(w, basis);
    area += w.Area();
  }
}

// Rows of O for `cells` window cells: the cells, then an identity row per direct column.
FENESTRA_CPU_GPU inline int OutdoorRowCount(int cells) { return cells + kIndoorDirectColumns; }
// The direct column of sky bin `bin` for light reflected in the room (`unreflected` false) or
// seen straight from the sensor.
FENESTRA_CPU_GPU inline int DirectColumn(int cells, int bin, bool unreflected) {
  return cells + bin + (unreflected ? kTregenzaBinCount : 0);
}

// The outdoor surfaces as the indoor stage sees them: whether the view from a window
// point along omega reaches the sky, exactly as the first segment of an outdoor path.
template <class Intersector>
struct OutdoorView {
  Intersector scene;   // the outdoor surfaces in front of the window, in their own frame
  Vec3f offset;        // the outdoor frame's position of the indoor frame's origin [m]
  const uint8_t* met;  // per window cell: every view from it meets a surface
                       // (core/trace/window_cells.h), or null

  FENESTRA_CPU_GPU bool SurelyMet(int cell) const { return met != nullptr && met[cell] != 0; }

  FENESTRA_CPU_GPU bool Escapes(Vec3f point, Vec3f outward, Vec3f omega) const {
    return !scene.Occluded(OffsetRayOrigin(point + offset, outward), omega, INFINITY);
  }

  // Light arriving through `window` at `point` from `omega` (cell `cell` of all `cells`
  // windows' cells), worth `value` per unit radiance, `unreflected` when it reaches the sensor
  // without a reflection in the room: into the direct column of omega's sky bin when the view
  // reaches the sky, else into the window cell. Sink: void Add(int column, double value).
  template <class Sink>
  FENESTRA_CPU_GPU void Score(const TraceWindow& window, int cells, Vec3f point, Vec3f omega,
                              int cell, double value, bool unreflected, Sink* sink) const {
    const bool direct = !SurelyMet(cell) && Escapes(point, window.normal, omega);
    sink->Add(direct ? DirectColumn(cells, TregenzaBin(omega), unreflected) : cell, value);
  }
};

template <class Sink>  // Sink: void Add(int bin, double value); void AddFirstEscape()
struct OutdoorMode {
  TraceWindow window;    // where the paths start
  TraceWindows windows;  // every window, `window` among them
  const HemisphereBasis* basis;
  int cell;  // cell of `window`: part * basis cells + direction cell
  Sink* sink;

  template <class Intersector>
  FENESTRA_CPU_GPU PathState Start(const Intersector&, const PathRandom& random) const {
    const Uniform4 u = random.Draw(0, 0);
    const int part = cell / basis->cell_count;
    const Vec3f direction = window.ToWorld(
        SampleBasisCell(*basis, cell - part * basis->cell_count, u.u[2], u.u[3], true));
    return PathState{OffsetRayOrigin(window.PartPoint(part, u.u[0], u.u[1]), window.normal),
                     direction, 1.0f, 0, 0};
  }

  template <class Intersector>
  FENESTRA_CPU_GPU void AtReflection(const Intersector&, const PathState&, const ReflectionVertex&,
                                     const PathRandom&) const {}

  // A first segment that reaches the sky is the indoor stage's direct light: counted only.
  // A ray that leaves back through a window goes into the room, which the outdoor stage
  // does not see: it ends without reaching the sky.
  FENESTRA_CPU_GPU void Escape(const PathState& path) {
    if (path.vertex == 0) {
      sink->AddFirstEscape();
      return;
    }
    if (windows.Enters(path.origin, path.direction)) return;
    sink->Add(TregenzaBin(path.direction), static_cast<double>(path.weight));
  }

  FENESTRA_CPU_GPU void Finish(const PathStats&) const {}
};

// Sink: void Add(int column, double value) (IndoorColumnCount columns);
// Outdoor: void Score(window, cells, point, omega, cell, value, unreflected, Sink*), as
// OutdoorView. With several windows, next-event estimation draws a uniform point of all
// windows' area (a window by its area, then a point on it), and a bounce ray scores at the
// window it leaves by.
template <class Sink, class Outdoor>
struct IndoorMode {
  Vec3f sensor_position;  // local frame
  Vec3f sensor_normal;    // unit
  TraceWindows windows;
  const HemisphereBasis* basis;
  int32_t max_bounces;  // as PathSettings: reflections whose light may reach the sensor
  const Outdoor* outdoor;
  Sink* sink;

  template <class Intersector>
  FENESTRA_CPU_GPU PathState Start(const Intersector& scene, const PathRandom& random) {
    // The sensor connects as a Lambertian surface of albedo 1: pi f cos = cos
    SurfaceScatter sensor;
    sensor.normal = sensor_normal;
    sensor.view = sensor_normal;
    sensor.diffuse = sensor.total = 1.0f;
    Connect(scene, sensor_position, sensor, 1.0f, random.Draw(0, kWindowSamplePurpose), true);
    const Uniform4 u = random.Draw(0, 0);
    const Vec3f direction = SampleCosineHemisphere(sensor_normal, u.u[0], u.u[1]);
    return PathState{OffsetRayOrigin(sensor_position, sensor_normal), direction, 1.0f, 0, 0,
                     Dot(sensor_normal, direction) * kInvPiF};
  }

  // Light scattered here reaches the sensor after path.reflections + 1 reflections.
  template <class Intersector>
  FENESTRA_CPU_GPU void AtReflection(const Intersector& scene, const PathState& path,
                                     const ReflectionVertex& vertex, const PathRandom& random) {
    if (max_bounces >= 0 && path.reflections >= max_bounces) return;
    Connect(scene, vertex.position, *vertex.scatter, path.weight,
            random.Draw(path.vertex, kWindowSamplePurpose), false);
  }

  // A bounce ray that leaves through a window scores pi w in the cell it leaves by.
  FENESTRA_CPU_GPU void Escape(const PathState& path) {
    float distance = 0.0f;
    const int w = windows.Crossed(path.origin, path.direction, &distance);
    if (w < 0) return;
    const TraceWindow& window = windows.list[w];
    const float cos_window = Dot(window.normal, path.direction);
    if (!(cos_window > 0.0f)) return;
    const int cell = BasisCell(*basis, Vec3f{Dot(path.direction, window.across),
                                             Dot(path.direction, window.up), cos_window});
    if (cell < 0) return;
    const Vec3f point = path.origin + path.direction * distance;
    const float mis = path.pdf > 0.0f
                          ? PowerHeuristic(path.pdf, WindowDensity(distance * distance, cos_window))
                          : 1.0f;
    Score(window, point, path.direction,
          window.first_cell + window.PartAt(point) * basis->cell_count + cell,
          kPi * static_cast<double>(path.weight * mis), path.reflections == 0);
  }

  // Light reaching `window` at `point` from `omega` (cell `cell` of all windows), worth
  // `value` per unit radiance, `unreflected` when no reflection in the room lies between: the
  // outdoor surfaces tell its column (OutdoorView::Score).
  FENESTRA_CPU_GPU void Score(const TraceWindow& window, Vec3f point, Vec3f omega, int cell,
                              double value, bool unreflected) {
    outdoor->Score(window, windows.cells, point, omega, cell, value, unreflected, sink);
  }

  FENESTRA_CPU_GPU void Finish(const PathStats&) const {}

  // Solid-angle density of a uniform point of all windows seen at squared distance r2 and
  // cosine cos_window.
  FENESTRA_CPU_GPU float WindowDensity(float r2, float cos_window) const {
    return r2 / (windows.area * cos_window);
  }

  // Next-event estimation from `position` towards a uniform window point, through the smooth
  // parts of `scatter` (on either side of the surface: the ray leaves from the side it goes
  // to); `weight` is what the path carries here; `unreflected` at the sensor itself.
  template <class Intersector>
  FENESTRA_CPU_GPU void Connect(const Intersector& scene, Vec3f position,
                                const SurfaceScatter& scatter, float weight, const Uniform4& u,
                                bool unreflected) {
    const TraceWindow& window = windows.list[windows.Pick(u.u[2])];
    const Vec3f point = window.Point(u.u[0], u.u[1]);
    const Vec3f to_window = point - position;
    const float distance_squared = Dot(to_window, to_window);
    if (!(distance_squared > 0.0f)) return;
    const Vec3f omega = to_window * (1.0f / sqrtf(distance_squared));
    const float cos_window = Dot(window.normal, omega);
    if (!(cos_window > 0.0f)) return;
    float pdf;
    const float value = scatter.Value(omega, &pdf);
    if (!(value > 0.0f)) return;
    // The window point itself lies in the opening, where there is no surface: anything
    // short of it (less a relative margin) blocks the segment
    const float distance = sqrtf(distance_squared);
    const Vec3f side = Dot(scatter.normal, omega) > 0.0f ? scatter.normal : -scatter.normal;
    if (scene.Occluded(OffsetRayOrigin(position, side), omega, distance * 0.9999995f)) return;
    // The direction's cell only for light that arrives (omega is above the window's plane)
    const int cell =
        BasisCell(*basis, Vec3f{Dot(omega, window.across), Dot(omega, window.up), cos_window});
    if (cell < 0) return;
    const float mis = PowerHeuristic(WindowDensity(distance_squared, cos_window), pdf);
    Score(window, point, omega,
          window.first_cell + window.PartOf(u.u[0], u.u[1]) * basis->cell_count + cell,
          static_cast<double>(weight * value * cos_window * windows.area / distance_squared * mis),
          unreflected);
  }
};

}  // namespace fenestra
