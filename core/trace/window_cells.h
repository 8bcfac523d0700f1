#pragma once

// The window cells whose every view meets an outdoor surface, so that the indoor stage's
// outdoor test (OutdoorView in core/trace/two_stage_modes.h) can skip the traversal for
// them: most views from a window in a street meet the street or the buildings across it.
//
// A cell (a window part P and a direction cell C of the basis) qualifies when one convex
// planar polygon of the outdoor surfaces (a triangle, or two coplanar triangles that form a
// convex quad, as a box's face) is met by every ray from P along C. The rays from a point
// of P along C meet the polygon's plane within the convex hull of where the rays along C's
// boundary meet it, and the rays along one direction from the points of P within the
// hull of where those from P's corners meet it. So it suffices that the rays from P's
// corners along samples of C's boundary all meet the polygon shrunk by a margin that
// covers the boundary between the samples (its small circles bulge out of the chords by
// at most 1e-3 rad here), all from its front or all from its back.
#include <cstdint>
#include <vector>

#include "core/geometry/hemisphere_basis.h"
#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_modes.h"

namespace fenestra {

// Per window cell (part * basis cells + direction cell): 1 when every view from it meets
// one of `geometry`'s surfaces, else 0. `window` in `geometry`'s frame. The parts go on
// every core.
std::vector<uint8_t> WindowCellsMeetingSurfaces(const TraceGeometry& geometry,
                                                const TraceWindow& window,
                                                const HemisphereBasis& basis);

}  // namespace fenestra
