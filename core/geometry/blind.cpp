// Venetian blind generator.
//
// Frame: n = the window's outward normal, d = -n (into the room), a = the stacking axis
// (the window's `up` for horizontal slats, its `across` for vertical ones), l = the slat's
// length axis (the other in-plane axis). The wall's inner face is the plane
// center - depth_m * n.
//
// Exact rule:
// - Each slat is a box of width w (across the slat), thickness t and length L + 2 * margin,
//   where L is the opening's extent along l. Its cross-section rotates by the tilt α about
//   the slat's own axis: the width runs along cos α * a + sin α * d, the thickness along
//   -sin α * a + cos α * d. α = 0 puts the slats in the window plane, α = π/2 perpendicular
//   to it.
// - The axes lie in one plane parallel to the window, at depth g + sqrt(w² + t²) / 2 behind
//   the wall's inner face (g = wall_gap_m), so no slat reaches closer than g to the wall at
//   any tilt.
// - Pitch p = max(w + s, p_min(α)) with p_min(α) = min(w / |cos α|, t / |sin α|), the
//   smallest distance at which two neighbouring slats tilted by α do not interpenetrate
//   (separating axes of two equal rectangles). At α = 0 the pitch is w + s.
// - Count n = 1 + ceil((H - w) / p), H = the opening's extent along a: the fewest slats
//   whose stack, (n - 1) p + w, covers the opening. The stack is centred on the opening.
//   At α = 0, s = 0 the slats touch and form a closed plate over the whole opening.
#include "core/geometry/blind.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

constexpr double kCountTolerance = 1e-9;

struct Frame {
  Vec3d stack;   // a
  Vec3d length;  // l
  double stack_extent_m;
  double length_extent_m;
};

Frame BlindFrame(const Window& window, const BlindSpec& spec) {
  if (spec.vertical) return {window.across, window.up, window.width_m, window.height_m};
  return {window.up, window.across, window.height_m, window.width_m};
}

double MinimumPitch(double w, double t, double tilt) {
  const double c = std::abs(std::cos(tilt));
  const double s = std::abs(std::sin(tilt));
  double p = std::numeric_limits<double>::infinity();
  if (c > 0) p = std::min(p, w / c);
  if (s > 0) p = std::min(p, t / s);
  return p;
}

}  // namespace

absl::Status CheckBlindFits(const BlindSpec& spec, const Window& window) {
  if (!(spec.slat_thickness_m.max < spec.slat_width_m.min)) {
    return absl::InvalidArgumentError(
        absl::StrCat("slats up to ", spec.slat_thickness_m.max, " m thick and from ",
                     spec.slat_width_m.min, " m wide: a slat must be thinner than it is wide"));
  }
  const Frame frame = BlindFrame(window, spec);
  if (!(spec.slat_width_m.max <= frame.stack_extent_m)) {
    return absl::InvalidArgumentError(
        absl::StrCat("slats up to ", spec.slat_width_m.max, " m wide are wider than the window's ",
                     frame.stack_extent_m, " m ", spec.vertical ? "width" : "height",
                     " across which they stack"));
  }
  if (const double slats = MaxSlatCount(window, spec, spec.slat_width_m.min);
      !(slats <= kMaxBlindSlats)) {
    return absl::InvalidArgumentError(
        absl::StrCat("slats from ", spec.slat_width_m.min, " m wide need up to ", slats,
                     " slats across the window's ", frame.stack_extent_m, " m ",
                     spec.vertical ? "width" : "height", "; a blind has at most ", kMaxBlindSlats));
  }
  return absl::OkStatus();
}

BlindLayout LayoutBlind(const Window& window, const BlindSpec& spec, const BlindDesign& design) {
  const Frame frame = BlindFrame(window, spec);
  const double w = design.slat_width_m;
  const double t = design.slat_thickness_m;
  BlindLayout layout;
  layout.pitch_m = std::max(w + design.slat_spacing_m, MinimumPitch(w, t, design.tilt_rad));
  const double gaps = std::max(0.0, (frame.stack_extent_m - w) / layout.pitch_m);
  layout.slat_count = 1 + static_cast<int>(std::ceil(gaps - kCountTolerance));
  layout.axis_depth_m = spec.wall_gap_m + 0.5 * std::sqrt(w * w + t * t);
  return layout;
}

double MaxSlatCount(const Window& window, const BlindSpec& spec, double min_slat_width_m) {
  return 1 + std::ceil(BlindFrame(window, spec).stack_extent_m / min_slat_width_m);
}

SlatStack StackOfBlind(const Window& window, const BlindSpec& spec, const BlindDesign& design) {
  const BlindLayout layout = LayoutBlind(window, spec, design);
  const Frame frame = BlindFrame(window, spec);
  SlatStack slats;
  slats.stack = frame.stack;
  slats.length = frame.length;
  slats.into_room = -window.normal;
  const Vec3d inner_center = window.center - window.depth_m * window.normal;
  slats.center = inner_center + layout.axis_depth_m * slats.into_room;
  slats.pitch_m = layout.pitch_m;
  slats.count = layout.slat_count;
  slats.half_length_m = 0.5 * frame.length_extent_m + spec.side_margin_m;
  slats.half_width_m = 0.5 * design.slat_width_m;
  slats.half_thickness_m = 0.5 * design.slat_thickness_m;
  slats.tilt_rad = design.tilt_rad;
  return slats;
}

SlatBoxes BoxesOfStack(const SlatStack& slats) {
  const double c = std::cos(slats.tilt_rad);
  const double s = std::sin(slats.tilt_rad);
  SlatBoxes boxes;
  boxes.center = slats.center;
  boxes.stack = slats.stack;
  boxes.half_length = slats.half_length_m * slats.length;
  boxes.half_width = slats.half_width_m * (c * slats.stack + s * slats.into_room);
  boxes.half_thickness = slats.half_thickness_m * (-s * slats.stack + c * slats.into_room);
  boxes.pitch = slats.pitch_m;
  boxes.count = slats.count;
  return boxes;
}

BlindLayout GenerateBlind(const Window& window, const BlindSpec& spec, const BlindDesign& design,
                          uint32_t part_index, TriangleMesh& mesh) {
  const BlindLayout layout = LayoutBlind(window, spec, design);
  const SlatBoxes boxes = BoxesOfStack(StackOfBlind(window, spec, design));
  const SlatFinish finish = FinishOf(spec, design);
  for (int k = 0; k < boxes.count; ++k) {
    Vec3d corner[8];
    for (int i = 0; i < 8; ++i) corner[i] = boxes.Corner(k, i);
    for (int f = 0; f < 6; ++f) {
      const Vec3d& a = corner[SlatBoxes::FaceCorner(f, 0)];
      const Vec3d& b = corner[SlatBoxes::FaceCorner(f, 1)];
      const Vec3d& c = corner[SlatBoxes::FaceCorner(f, 2)];
      const Vec3d& d = corner[SlatBoxes::FaceCorner(f, 3)];
      mesh.Add(a, b, c, SlatTriangleMaterial(finish, 2 * f), Side::kIndoor, part_index);
      mesh.Add(a, c, d, SlatTriangleMaterial(finish, 2 * f + 1), Side::kIndoor, part_index);
    }
  }
  return layout;
}

// Every slat lies within r = sqrt(w² + t²) / 2 of its axis; the axes lie at depth g + r
// behind the wall's inner face and at most (n - 1) p / 2 <= (H - w + p) / 2 <= (H + p) / 2
// from the opening's centre along the stack; the pitch is at most max(w + s, sqrt(2) max(w,
// t)), since min(w / |cos α|, t / |sin α|) <= sqrt(2) max(w, t).
BlindEnvelope EnvelopeOfBlind(const Window& window, const BlindSpec& spec, double margin_m) {
  const double w = spec.slat_width_m.max, t = spec.slat_thickness_m.max;
  const double s = spec.slat_spacing_m.max;
  const double r = 0.5 * std::sqrt(w * w + t * t);
  const double pitch = std::max(w + s, std::sqrt(2.0) * std::max(w, t));
  const Frame frame = BlindFrame(window, spec);
  BlindEnvelope envelope;
  envelope.axis[0] = frame.stack;
  envelope.axis[1] = frame.length;
  envelope.axis[2] = -window.normal;
  envelope.half_extent[0] = 0.5 * (frame.stack_extent_m + pitch) + r + margin_m;
  envelope.half_extent[1] = 0.5 * frame.length_extent_m + spec.side_margin_m + margin_m;
  envelope.half_extent[2] = r + margin_m;
  const Vec3d inner_center = window.center - window.depth_m * window.normal;
  envelope.center = inner_center + (spec.wall_gap_m + r) * envelope.axis[2];
  return envelope;
}

}  // namespace fenestra
