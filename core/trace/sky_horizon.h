#pragma once

// The skyline the window sees, as a bound that spares the indoor stage's outdoor test
// (OutdoorView in core/trace/two_stage_modes.h) most of its rays: per window part and
// azimuth bin, the largest sine of elevation at which a ray from anywhere in the part, with
// an azimuth in the bin, can meet an outdoor triangle. A ray above it reaches the sky for
// sure and needs no traversal; the others are traced.
//
// The bound is conservative: a triangle's bounding box B, seen from the part's box P, spans
// the vectors B - P (a box); within an azimuth wedge their elevation is at most
// atan(z_max / r_min), with z_max the box's top and r_min its least horizontal distance
// from the origin inside the wedge (the box's footprint clipped to the wedge).
#include <vector>

#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_modes.h"

namespace fenestra {

// Per part (window.Parts()) and azimuth bin (kHorizonAzimuthBins, azimuth = atan2(y, x)
// from -pi): the bound, row-major; `window` in `geometry`'s frame (z up).
std::vector<float> SkyHorizon(const TraceGeometry& geometry, const TraceWindow& window);

}  // namespace fenestra
