// The two path modes of the two-stage method (DESIGN.md section 1), for TracePath.
//
// The window is the interface: a rectangle (the opening's outer face) with a frame
// (across, up, outward normal); directions are binned by the hemisphere basis of
// core/geometry/hemisphere_basis.h in that frame, by the outward direction omega, the way
// light comes from.
//
// OutdoorMode: a path starts at a uniform point of the window, its direction uniform in
// solid angle within one basis cell, then bounces in the outdoor scene. Escaping through
// sky bin j it adds its weight to O[cell, j], so O[cell, j] estimates the mean radiance
// arriving at the window from the cell per unit radiance of bin j. A path that goes back
// in through the window ends there: light that leaves the room and returns through the
// window is the one interreflection the two-stage split leaves out.
//
// IndoorMode: a path starts at a sensor, cosine-sampled, and bounces in the indoor scene.
// At every vertex (the sensor included, and every reflection the bounce limit allows) it
// samples a uniform window point x_w (next-event estimation) and, if the segment is clear,
// adds to I[sensor, cell(omega)] the irradiance the window delivers there per unit
// radiance: at the sensor cos_s cos_w A / r^2; at a reflection w rho cos_v cos_w A / r^2
// (the sensor's cosine-sampled estimator pi L, with L = rho / pi times the vertex's
// irradiance, and w the path weight before the reflection). A bounce ray that leaves
// through the window ends with no contribution: the explicit samples count that light.
#pragma once

#include <math.h>
#include <stdint.h>

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

  FENESTRA_CPU_GPU float Area() const { return width * height; }
  // The window point for two uniforms.
  FENESTRA_CPU_GPU Vec3f Point(float u0, float u1) const {
    return center + across * ((u0 - 0.5f) * width) + up * ((u1 - 0.5f) * height);
  }
  // Whether the ray origin + t direction, t > 0, enters the window rectangle from outside.
  FENESTRA_CPU_GPU bool Crosses(Vec3f origin, Vec3f direction) const {
    const float towards = Dot(direction, normal);
    if (!(towards < 0.0f)) return false;
    const float t = Dot(center - origin, normal) / towards;
    if (!(t > 0.0f)) return false;
    const Vec3f offset = origin + direction * t - center;
    return fabsf(Dot(offset, across)) <= 0.5f * width && fabsf(Dot(offset, up)) <= 0.5f * height;
  }
  // A window-frame direction in the trace frame.
  FENESTRA_CPU_GPU Vec3f ToWorld(Vec3f local) const {
    return across * local.x + up * local.y + normal * local.z;
  }
};

// Random stream of outdoor paths starting in cell c: kOutdoorStreamBase + c, apart from
// the sensors' streams.
inline constexpr uint32_t kOutdoorStreamBase = 0x80000000u;

// Random purposes (PathRandom::Draw's second argument) of the two-stage modes.
inline constexpr uint32_t kWindowSamplePurpose = 1;

template <class Sink>  // Sink: void Add(int bin, double value)
struct OutdoorMode {
  TraceWindow window;
  const HemisphereBasis* basis;
  int cell;
  Sink* sink;

  template <class Intersector>
  FENESTRA_CPU_GPU PathState Start(const Intersector&, const PathRandom& random) const {
    const Uniform4 u = random.Draw(0, 0);
    const Vec3f direction = window.ToWorld(SampleBasisCell(*basis, cell, u.u[2], u.u[3]));
    return PathState{OffsetRayOrigin(window.Point(u.u[0], u.u[1]), window.normal), direction, 1.0f,
                     0, 0};
  }

  template <class Intersector>
  FENESTRA_CPU_GPU void AtReflection(const Intersector&, const PathState&, const ReflectionVertex&,
                                     const PathRandom&) const {}

  // A ray that leaves back through the window goes into the room, which the outdoor
  // stage does not see: it ends without reaching the sky.
  FENESTRA_CPU_GPU void Escape(const PathState& path) {
    if (window.Crosses(path.origin, path.direction)) return;
    sink->Add(TregenzaBin(path.direction), static_cast<double>(path.weight));
  }

  FENESTRA_CPU_GPU void Finish(const PathStats&) const {}
};

template <class Sink>  // Sink: void Add(int cell, double value)
struct IndoorMode {
  Vec3f sensor_position;  // local frame
  Vec3f sensor_normal;    // unit
  TraceWindow window;
  const HemisphereBasis* basis;
  int32_t max_bounces;  // as PathSettings: reflections whose light may reach the sensor
  Sink* sink;

  template <class Intersector>
  FENESTRA_CPU_GPU PathState Start(const Intersector& scene, const PathRandom& random) {
    const Vec3f origin = OffsetRayOrigin(sensor_position, sensor_normal);
    Connect(scene, sensor_position, origin, sensor_normal, 1.0f,
            random.Draw(0, kWindowSamplePurpose));
    const Uniform4 u = random.Draw(0, 0);
    return PathState{origin, SampleCosineHemisphere(sensor_normal, u.u[0], u.u[1]), 1.0f, 0, 0};
  }

  // Light reflected here reaches the sensor after path.reflections + 1 reflections.
  template <class Intersector>
  FENESTRA_CPU_GPU void AtReflection(const Intersector& scene, const PathState& path,
                                     const ReflectionVertex& vertex, const PathRandom& random) {
    if (max_bounces >= 0 && path.reflections >= max_bounces) return;
    Connect(scene, vertex.position, OffsetRayOrigin(vertex.position, vertex.normal), vertex.normal,
            path.weight * vertex.reflectance, random.Draw(path.vertex, kWindowSamplePurpose));
  }

  FENESTRA_CPU_GPU void Escape(const PathState&) const {}
  FENESTRA_CPU_GPU void Finish(const PathStats&) const {}

  // Next-event estimation from `position` (rays leave from `origin`, offset off its
  // surface) towards a uniform window point; `factor` is what the path carries here.
  template <class Intersector>
  FENESTRA_CPU_GPU void Connect(const Intersector& scene, Vec3f position, Vec3f origin,
                                Vec3f normal, float factor, const Uniform4& u) {
    const Vec3f to_window = window.Point(u.u[0], u.u[1]) - position;
    const float distance_squared = Dot(to_window, to_window);
    if (!(distance_squared > 0.0f)) return;
    const Vec3f omega = to_window * (1.0f / sqrtf(distance_squared));
    const float cos_vertex = Dot(normal, omega);
    const float cos_window = Dot(window.normal, omega);
    if (!(cos_vertex > 0.0f) || !(cos_window > 0.0f)) return;
    const int cell =
        BasisCell(*basis, Vec3f{Dot(omega, window.across), Dot(omega, window.up), cos_window});
    if (cell < 0) return;
    // The window point itself lies in the opening, where there is no surface: anything
    // short of it (less a relative margin) blocks the segment
    const float distance = sqrtf(distance_squared);
    if (scene.Occluded(origin, omega, distance * 0.9999995f)) return;
    sink->Add(cell, static_cast<double>(factor * cos_vertex * cos_window * window.Area() /
                                        distance_squared));
  }
};

}  // namespace fenestra
