#pragma once

#include <cstdint>
#include <numbers>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "core/common/vec3.h"
#include "core/geometry/mesh.h"
#include "core/geometry/slat_boxes.h"

namespace fenestra {

struct Window;

// A design parameter: value and the range an optimizer may explore.
struct ParameterRange {
  double value = 0, min = 0, max = 0;
};

// The range a blind parameter must stay within, whatever the scene or a job asks for.
struct ParameterBounds {
  double lowest = 0, highest = 0;
};
// Bounds no real Venetian blind reaches. Tilt: the generator's range.
inline constexpr ParameterBounds kTiltBoundsRad{-std::numbers::pi / 2, std::numbers::pi / 2};
// Slat width: micro-blinds between panes have 8 mm slats, external louvres up to 0.6 m.
inline constexpr ParameterBounds kSlatWidthBoundsM{0.001, 1.0};
// Gap between slats: a blind whose slats are a metre apart shades nothing.
inline constexpr ParameterBounds kSlatSpacingBoundsM{0, 1.0};
// Slat thickness: aluminium slats are 0.2 mm thick, timber louvres a few centimetres.
inline constexpr ParameterBounds kSlatThicknessBoundsM{1e-4, 0.1};
// Slat length beyond the opening at each end, and wall-to-slat clearance: blinds overlap
// the wall by centimetres and hang centimetres from it.
inline constexpr double kMaxSideMarginM = 1.0;
inline constexpr double kMaxWallGapM = 1.0;

// The Venetian blind's fixed description (from the scene).
struct BlindSpec {
  uint32_t material = 0;  // index into the scene's materials: every face but the outer ones
  // The material of the slats' outer broad faces (kSlatOuterFace); absent: `material`
  std::optional<uint32_t> outer_material;
  bool vertical = false;  // slats vertical (stacked across the window) instead of horizontal
  ParameterRange tilt_rad, slat_width_m, slat_spacing_m, slat_thickness_m;
  double wall_gap_m = 0.01;  // clearance between wall and slat at any tilt [m]
  double side_margin_m = 0;  // extra slat length beyond the opening at each end [m]
  // In place only in the hours IES LM-83's rule closes it (scene.proto, AUTOMATED_SUN),
  // retracted otherwise; false: in place in every hour.
  bool automated_sun = false;
  // Blinds of the same non-empty group share their design (scene.proto, VenetianBlind.group).
  std::string group;

  uint32_t OuterMaterial() const { return outer_material.value_or(material); }
};

// The slats' materials (indices into the scene's materials, neither a glass): of every face
// but the outer broad ones (kSlatOuterFace), and of those.
struct SlatFinish {
  uint32_t material = 0;
  uint32_t outer_material = 0;
  bool operator==(const SlatFinish&) const = default;
};

// One design: the free values of the blind.
struct BlindDesign {
  bool has_blind = false;
  double tilt_rad = 0, slat_width_m = 0, slat_spacing_m = 0, slat_thickness_m = 0;
  // The slats' finish where a job chooses it (its finish variable); absent: the spec's.
  std::optional<SlatFinish> finish;
  bool operator==(const BlindDesign&) const = default;
};

// The slats' finish at `design`: the design's, else the spec's material and outer material.
// Everything that gives the slats their materials (meshes, replays, the direct sun) asks here.
inline SlatFinish FinishOf(const BlindSpec& spec, const BlindDesign& design) {
  return design.finish.value_or(SlatFinish{spec.material, spec.OuterMaterial()});
}

// How the generator laid out the slats.
struct BlindLayout {
  int slat_count = 0;
  double pitch_m = 0;       // distance between neighbouring slat axes
  double axis_depth_m = 0;  // distance of the slat axes behind the wall's inner face
};

// The most slats a blind may have (12 triangles each); scenes and jobs whose narrowest slats
// would need more are refused.
inline constexpr int kMaxBlindSlats = 100'000;

// An upper bound on the slats LayoutBlind places in `window` for any design whose slat width
// is at least `min_slat_width_m` [m] (the pitch is at least the width).
double MaxSlatCount(const Window& window, const BlindSpec& spec, double min_slat_width_m);

// Checks that every design within the spec's ranges is a blind that fits `window`: slats
// thinner than wide, no wider than the opening they stack across, and at most
// kMaxBlindSlats of them at the narrowest width. InvalidArgument with the reason (the caller
// adds the field).
absl::Status CheckBlindFits(const BlindSpec& spec, const Window& window);

// Slat layout for `design` in `window` (see blind.cpp for the exact rule).
BlindLayout LayoutBlind(const Window& window, const BlindSpec& spec, const BlindDesign& design);

// A box (centre, three unit axes, half extents) that holds the blind of every design whose
// values lie within the spec's ranges.
struct BlindEnvelope {
  Vec3d center;
  Vec3d axis[3];  // stacking axis, slat length axis, into the room
  double half_extent[3] = {0, 0, 0};
};

// The envelope of `spec` in `window`, with `margin_m` to spare on every side.
BlindEnvelope EnvelopeOfBlind(const Window& window, const BlindSpec& spec, double margin_m);

// The slats of a design as a stack of equal boxes, which GenerateBlind triangulates
// (through BoxesOfStack): slat k
// (0 <= k < count) is centred at center + (k - (count - 1) / 2) pitch_m stack; its half
// extents are half_length_m along `length`, half_width_m along cos(tilt) stack + sin(tilt)
// into_room and half_thickness_m along -sin(tilt) stack + cos(tilt) into_room.
struct SlatStack {
  Vec3d center, stack, length, into_room;
  double pitch_m = 0, half_length_m = 0, half_width_m = 0, half_thickness_m = 0, tilt_rad = 0;
  int count = 0;
};
SlatStack StackOfBlind(const Window& window, const BlindSpec& spec, const BlindDesign& design);

// The slats' boxes (core/geometry/slat_boxes.h) of a stack.
SlatBoxes BoxesOfStack(const SlatStack& slats);

// Triangles GenerateBlind makes per slat (its box's 6 faces, two each, in SlatBoxes's order).
inline constexpr int kTrianglesPerSlat = 12;
// The slats' outer broad face (SlatBoxes's face 4, the -thickness side): it faces the window at
// tilt 0 and turns towards the stacking axis as the tilt grows towards π/2.
inline constexpr int kSlatOuterFace = 4;

// The material of triangle `triangle` (0 <= triangle < kTrianglesPerSlat) of every slat of
// finish `finish` (FinishOf).
inline uint32_t SlatTriangleMaterial(const SlatFinish& finish, int triangle) {
  return triangle / 2 == kSlatOuterFace ? finish.outer_material : finish.material;
}

// Appends the slats (kTrianglesPerSlat each, indoor, of the design's finish, FinishOf) to
// `mesh` under part `part_index`.
BlindLayout GenerateBlind(const Window& window, const BlindSpec& spec, const BlindDesign& design,
                          uint32_t part_index, TriangleMesh& mesh);

}  // namespace fenestra
