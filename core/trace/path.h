// The per-path logic of the Monte Carlo tracer, written once for CPU and GPU.
//
// TracePath follows one path: its mode samples the start, then the loop finds the closest
// hit, scatters (diffuse reflection about the geometric normal turned to the incoming side,
// or straight-through transmission at glazing), weights by the surface, applies the bounce
// limit and Russian roulette (or weight windows: roulette and splitting by an importance
// map), and hands an escaping ray back to the mode. Everything here
// is POD, fixed arrays and raw pointers, templated on:
//
//   Intersector  bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const;
//                closest hit along the ray (t in (0, inf)), in the scene's local frame.
//                bool Occluded(Vec3f origin, Vec3f direction, float distance) const;
//                whether any surface lies on the ray for t in (0, distance) (shadow rays).
//   Mode         what a path is for: where it starts and what its light is worth.
//     PathState Start(const Intersector&, const PathRandom&)     first vertex (draw 0)
//     void AtReflection(const Intersector&, const PathState&, const ReflectionVertex&,
//                       const PathRandom&)                      before each reflection
//     void Escape(const PathState&)                              the ray left the scene
//     void Finish(const PathStats&)                              once, at the end
//     bool GoesOn()                                              optional: after a step
//                       that ended the branch, whether it steps again from the same state
//                       (the indoor replay's records let a ray stopped at the blinds'
//                       envelope through, core/trace/indoor_replay_modes.h)
//
// With weight windows a path may split into branches (a tree): Start and Finish are called
// once per path, AtReflection and Escape once per event of any branch. PathState::vertex
// numbers the interactions of the whole tree, so every draw of a path is distinct.
//
// OneStageMode is the one-stage daylight-coefficient estimator (core/README.md, "One-stage
// method"): start at a sensor with a cosine-sampled direction and add pi times the path
// weight to the sky bin of the escape direction. The two-stage modes plug in here without
// touching the loop: the outdoor stage starts on the window (uniform point, direction
// within one hemisphere cell by projected solid angle) and escapes like the one-stage mode
// into O[cell, bin]; the indoor stage starts at a sensor, connects each vertex to a sampled
// window point in Start and AtReflection (next-event estimation, using random purpose 1),
// scores rays that leave through the window too, and weights the two by multiple importance
// sampling.
#pragma once

#include <math.h>
#include <stdint.h>

#include <type_traits>
#include <utility>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"
#include "core/sky/sky_bin.h"
#include "core/trace/importance_map.h"
#include "core/trace/philox.h"
#include "core/trace/ray_offset.h"
#include "core/trace/sampling.h"
#include "core/trace/scatter.h"

namespace fenestra {

// Bins of the Tregenza sky plus the ground (bin 0).
inline constexpr int kTregenzaBinCount = 146;
// The one-stage tallies' bins: each sky bin twice, first for light reflected at least once,
// then for the sensor's own view of it (no reflection: the direct component, which the
// direct sun replaces; core/README.md, "Direct sun").
inline constexpr int kOneStageBins = 2 * kTregenzaBinCount;
FENESTRA_CPU_GPU inline int OneStageBin(int bin, bool unreflected) {
  return bin + (unreflected ? kTregenzaBinCount : 0);
}
// Whether a one-stage bin is a sky bin (not the ground) of either block.
FENESTRA_CPU_GPU inline bool IsOneStageSkyBin(int bin) { return bin % kTregenzaBinCount != 0; }

// Per-triangle materials: materials[triangle_material[triangle]].
struct SurfaceTable {
  const TraceMaterial* materials;
  const uint32_t* triangle_material;
};

// The closest hit an intersector reports.
struct SurfaceHit {
  Vec3f position;     // on the triangle, interpolated from barycentrics (local frame)
  Vec3f normal;       // geometric normal, any orientation and length (0 if degenerate)
  uint32_t triangle;  // triangle index into the SurfaceTable
};

// A sensor: a point and the unit normal of the hemisphere it sees.
struct TraceSensor {
  Vec3f position;  // local frame [m]
  Vec3f normal;    // unit
};

// Every bounce setting (PathSettings, OneStageOptions, the stage options, the job's
// `*_bounces`): surface reflections a path may make; 0 = none (the direct component),
// kUnlimitedBounces (any negative value) = as many as Russian roulette allows.
inline constexpr int32_t kUnlimitedBounces = -1;

// How far paths go.
struct PathSettings {
  int32_t max_bounces;       // surface reflections allowed; kUnlimitedBounces (needs roulette)
  bool russian_roulette;     // play roulette when the weight falls below the threshold
  float roulette_threshold;  // in (0, 1]; 1 = survive with the reflectance, weight stays 1
  uint32_t max_vertices;     // hard cap on surface interactions per path (safety net)
  // Weight windows, when set: at a reflection at x the threshold becomes
  // min(1, window_scale / importance(x)) (window_scale = the mean score of a path from the
  // start), and a path heavier than twice it splits into copies of equal weight. Both keep
  // the estimate unbiased and every weight <= 1.
  const ImportanceMap* importance = nullptr;
  float window_scale = 0.0f;
  // How the paths' first draws are made (PathRandom): the path's batch then matters
  Sequence sequence = Sequence::kPseudoRandom;
};

// Branches a split path may hold waiting, and copies one split may make.
inline constexpr int kMaxPendingBranches = 64;
inline constexpr int kMaxSplit = 16;

// Where a path is: the next ray to trace and what it carries.
struct PathState {
  Vec3f origin;         // local frame, already offset from the surface it leaves
  Vec3f direction;      // unit
  float weight;         // throughput so far, <= 1
  int32_t reflections;  // surface reflections so far
  uint32_t vertex;      // interactions so far (0 = start); indexes random draws
  // Solid-angle density with which the point it leaves drew `direction` (ScatterSample::pdf;
  // cosine / pi at a sensor); 0 where no other technique samples the direction (after a delta
  // part: a mirror, straight-through transmission). Only the indoor stage's MIS reads it.
  float pdf = 0.0f;
};

// A vertex whose surface has smooth parts (SurfaceScatter::Smooth), before the path scatters
// there, for modes that connect vertices (indoor stage).
struct ReflectionVertex {
  Vec3f position;                 // on the surface (local frame)
  Vec3f normal;                   // unit, on the side the path arrived from
  const SurfaceScatter* scatter;  // what the surface does there
};

// How a path ended.
enum class PathEnd : uint8_t {
  kEscaped,      // left the scene; the mode scored it
  kAbsorbed,     // zero weight (black surface)
  kRoulette,     // terminated by Russian roulette
  kBounceLimit,  // needed one more reflection than allowed
  kTruncated,    // hit max_vertices
  kDegenerate,   // hit a triangle without a normal
};

struct PathStats {
  uint32_t rays;      // closest-hit queries, all branches
  float max_weight;   // largest throughput any branch carried
  PathEnd end;        // how the last branch ended
  uint32_t branches;  // 1 + splits
  uint32_t ends[6];   // branches by PathEnd
};

namespace path_internal {

// Records how a branch ended; false, for StepBranch to return.
FENESTRA_CPU_GPU inline bool Ended(PathEnd* end, PathEnd how) {
  *end = how;
  return false;
}

// Traces one ray of a branch: on to the next vertex (true, `path` updated), or the branch
// ends (false, `end` set). Pushes the copies of any split onto `pending`.
template <class Intersector, class Mode>
FENESTRA_CPU_GPU inline bool StepBranch(const Intersector& scene, const SurfaceTable& surfaces,
                                        const PathSettings& settings, const PathRandom& random,
                                        Mode& mode, PathState& path, uint32_t* interactions,
                                        PathState* pending, int pending_capacity,
                                        int* pending_count, PathStats* stats, PathEnd* end) {
  if (*interactions >= settings.max_vertices) return Ended(end, PathEnd::kTruncated);
  // Find the closest hit; an escaping ray is the mode's to score
  SurfaceHit hit{};
  ++stats->rays;
  if (!scene.Intersect(path.origin, path.direction, &hit)) {
    mode.Escape(path);
    return Ended(end, PathEnd::kEscaped);
  }
  path.vertex = ++*interactions;

  // Turn the geometric normal to the side the ray came from (surfaces are two-sided)
  const float length_squared = Dot(hit.normal, hit.normal);
  if (!(length_squared > 0.0f) || !(length_squared < 3.0e38f)) {
    return Ended(end, PathEnd::kDegenerate);
  }
  Vec3f normal = hit.normal * (1.0f / sqrtf(length_squared));
  if (Dot(normal, path.direction) > 0.0f) normal = -normal;

  // The surface's parts here; a mode may connect the vertex through its smooth parts before
  // the path picks one (core/trace/scatter.h)
  const TraceMaterial& material = surfaces.materials[surfaces.triangle_material[hit.triangle]];
  const SurfaceScatter scatter = ScatterAt(material, normal, -path.direction);
  if (scatter.Smooth()) {
    mode.AtReflection(scene, path, ReflectionVertex{hit.position, normal, &scatter}, random);
  }
  const Uniform4 u = random.Draw(path.vertex, 0);
  const ScatterSample sample = Sample(scatter, u);
  if (sample.scatters && settings.max_bounces >= 0 && path.reflections >= settings.max_bounces) {
    return Ended(end, PathEnd::kBounceLimit);
  }

  // Weight by the surface. Roulette below the threshold: survive with probability
  // w / threshold and carry the threshold on. Weight windows take the threshold from the
  // importance map and split heavy paths (at Lambertian reflections only). Either way the mean
  // is unchanged.
  float weight = path.weight * sample.factor;
  if (!(weight > 0.0f)) return Ended(end, PathEnd::kAbsorbed);
  float threshold = settings.roulette_threshold;
  if (settings.importance != nullptr) {
    const float importance = settings.importance->Lookup(hit.position, normal);
    threshold =
        importance > 0.0f && settings.window_scale > 0.0f
            ? (settings.window_scale < importance ? settings.window_scale / importance : 1.0f)
            : 1.0f;
  }
  const bool lambertian = scatter.total == scatter.diffuse;
  int copies = 1;
  if (settings.russian_roulette && weight < threshold) {
    if (!(u.u[2] * threshold < weight)) return Ended(end, PathEnd::kRoulette);
    weight = threshold;
  } else if (settings.importance != nullptr && lambertian && weight > 2.0f * threshold) {
    copies = static_cast<int>(weight / threshold);
    if (copies > kMaxSplit) copies = kMaxSplit;
    if (copies > pending_capacity - *pending_count + 1) {
      copies = pending_capacity - *pending_count + 1;
    }
    weight /= static_cast<float>(copies);
  }
  path.weight = weight;
  if (weight > stats->max_weight) stats->max_weight = weight;

  // Go on from the side the part leaves by; the copies of a split leave the same point in
  // directions of their own
  path.origin = OffsetRayOrigin(hit.position, sample.through ? -normal : normal);
  path.direction = sample.direction;
  path.pdf = sample.pdf;
  if (sample.scatters) ++path.reflections;
  for (int c = 1; c < copies; ++c) {
    PathState copy = path;
    copy.vertex = ++*interactions;
    const Uniform4 v = random.Draw(copy.vertex, 0);
    copy.direction = SampleCosineHemisphere(normal, v.u[0], v.u[1]);
    copy.pdf = Dot(normal, copy.direction) * SurfaceScatter::kInvPi;
    pending[(*pending_count)++] = copy;
  }
  return true;
}

// A path's first state (mode.Start) and its stats, reset.
template <class Intersector, class Mode>
FENESTRA_CPU_GPU inline PathState StartPath(const Intersector& scene, const PathRandom& random,
                                            Mode& mode, PathStats* stats) {
  const PathState path = mode.Start(scene, random);
  *stats = PathStats{0, path.weight, PathEnd::kEscaped, 0, {0, 0, 0, 0, 0, 0}};
  return path;
}

// Counts a branch that ended.
FENESTRA_CPU_GPU inline void EndBranch(PathEnd end, PathStats* stats) {
  stats->end = end;
  ++stats->branches;
  ++stats->ends[static_cast<int>(end)];
}

template <class Mode, class = void>
struct HasGoesOn : std::false_type {};
template <class Mode>
struct HasGoesOn<Mode, std::void_t<decltype(std::declval<Mode&>().GoesOn())>> : std::true_type {};

// mode.GoesOn() where the mode has it, else false.
template <class Mode>
FENESTRA_CPU_GPU inline bool GoesOn(Mode& mode) {
  if constexpr (HasGoesOn<Mode>::value) {
    return mode.GoesOn();
  } else {
    return false;
  }
}

// Follows one branch until it ends; pushes the copies of any split onto `pending`.
template <class Intersector, class Mode>
FENESTRA_CPU_GPU inline PathEnd FollowBranch(const Intersector& scene, const SurfaceTable& surfaces,
                                             const PathSettings& settings, const PathRandom& random,
                                             Mode& mode, PathState path, uint32_t* interactions,
                                             PathState* pending, int pending_capacity,
                                             int* pending_count, PathStats* stats) {
  PathEnd end = PathEnd::kEscaped;
  while (StepBranch(scene, surfaces, settings, random, mode, path, interactions, pending,
                    pending_capacity, pending_count, stats, &end) ||
         GoesOn(mode)) {
  }
  return end;
}

}  // namespace path_internal

// Follows one path (all its branches) from mode.Start to its end. See the file comment
// for the contracts.
// kPendingCapacity bounds the branches waiting to be followed; 0 turns splitting off and
// keeps the per-path state small (the GPU kernels, which do not use weight windows).
template <class Intersector, class Mode, int kPendingCapacity = kMaxPendingBranches>
FENESTRA_CPU_GPU inline PathStats TracePath(const Intersector& scene, const SurfaceTable& surfaces,
                                            const PathSettings& settings, const PathRandom& random,
                                            Mode& mode) {
  PathStats stats;
  PathState path = path_internal::StartPath(scene, random, mode, &stats);
  PathState pending[kPendingCapacity > 0 ? kPendingCapacity : 1];
  int pending_count = 0;
  uint32_t interactions = path.vertex;
  for (;;) {
    path_internal::EndBranch(
        path_internal::FollowBranch(scene, surfaces, settings, random, mode, path, &interactions,
                                    pending, kPendingCapacity, &pending_count, &stats),
        &stats);
    if (pending_count == 0) break;
    path = pending[--pending_count];
  }
  mode.Finish(stats);
  return stats;
}

// One-stage daylight coefficients: paths from one sensor, scored by escape bin.
//   Sink  void Add(int bin, double value);   value = pi * weight, per escaping branch, into
//                                            OneStageBin(sky bin, no reflection yet)
//         void EndPath();                    the path's branches are done
template <class Sink>
struct OneStageMode {
  Vec3f sensor_position;  // local frame
  Vec3f sensor_normal;    // unit
  Sink* sink;

  // Start on the sensor (moved off any surface it lies on), cosine-sampled direction.
  template <class Intersector>
  FENESTRA_CPU_GPU PathState Start(const Intersector&, const PathRandom& random) const {
    const Uniform4 u = random.Draw(0, 0);
    return PathState{OffsetRayOrigin(sensor_position, sensor_normal),
                     SampleCosineHemisphere(sensor_normal, u.u[0], u.u[1]), 1.0f, 0, 0};
  }

  template <class Intersector>
  FENESTRA_CPU_GPU void AtReflection(const Intersector&, const PathState&, const ReflectionVertex&,
                                     const PathRandom&) const {}

  // With cosine sampling, D[i, j] = pi * mean(weight of paths escaping through j).
  FENESTRA_CPU_GPU void Escape(const PathState& path) {
    sink->Add(OneStageBin(TregenzaBin(path.direction), path.reflections == 0),
              kPi * static_cast<double>(path.weight));
  }

  FENESTRA_CPU_GPU void Finish(const PathStats&) { sink->EndPath(); }
};

}  // namespace fenestra
